// A triangle's edge functions in one integer width, included by raster.comp with 32-bit
// types for the small triangles' pass and 64-bit ones for the large triangles': EDGE_INT,
// EDGE_IVEC2 and EDGE_IVEC3 name the types, EDGES the struct. The one definition of the
// coverage rule's integer arithmetic for both widths.

// Twice the signed area of (a, b, p), in 1/256² pixel units.
EDGE_INT edge(EDGE_IVEC2 a, EDGE_IVEC2 b, EDGE_IVEC2 p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Whether a point on edge a → b (interior on its positive side) is covered: the edge is a top
// edge (horizontal, interior below) or a left edge (interior to its right).
bool top_left(EDGE_IVEC2 a, EDGE_IVEC2 b) {
    EDGE_IVEC2 e = b - a;
    return e.y < 0 || (e.y == 0 && e.x > 0);
}

// The edge functions of b–c, c–a and a–b at the centre of a box's first pixel, and their
// exact steps a pixel right and a row down.
struct EDGES {
    EDGE_IVEC3 first, right, down;
};

// The edge functions of the triangle with snapped corners a, b, c (1/256 pixel, relative to
// the box's first pixel centre), oriented to be positive inside, each less one where its edge
// is neither top nor left: a pixel is covered exactly when all three are at least 0 (on such
// an edge, 0 becomes −1), one sign test for the top-left rule. A triangle of no area covers
// nothing.
EDGES edges_of(EDGE_IVEC2 a, EDGE_IVEC2 b, EDGE_IVEC2 c) {
    EDGE_INT area = edge(a, b, c);
    if (area < 0) {
        EDGE_IVEC2 swap = b;
        b = c;
        c = swap;
    }
    EDGE_IVEC2 origin = EDGE_IVEC2(0);
    EDGES e;
    e.first = EDGE_IVEC3(edge(b, c, origin), edge(c, a, origin), edge(a, b, origin))
            - EDGE_IVEC3(top_left(b, c) ? 0 : 1, top_left(c, a) ? 0 : 1, top_left(a, b) ? 0 : 1);
    e.right = -256 * EDGE_IVEC3(c.y - b.y, a.y - c.y, b.y - a.y);
    e.down = 256 * EDGE_IVEC3(c.x - b.x, a.x - c.x, b.x - a.x);
    if (area == 0) {
        e = EDGES(EDGE_IVEC3(-1), EDGE_IVEC3(0), EDGE_IVEC3(0));
    }
    return e;
}
