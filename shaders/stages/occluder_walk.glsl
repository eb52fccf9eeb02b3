// The depth test's search for a surface between a point and a witness (src/shadow.rs,
// "depth"): the scanner's shadow mask (shadow_mask.comp) and a rig's witness mask
// (witness_mask.comp) both ask it of the visibility image a witness saw. It works in the
// witness's frame, where the rays toward the witness either run parallel along +z (a
// directional witness, the paper's camera: `central` false, larger z nearer the witness) or
// meet at the frame's origin, the witness's centre (a pinhole witness: `central` true). A
// central projection maps the surface's triangles onto triangles of rays and its planes onto
// planes, so the same walk over the surface's edges finds the triangle a point's ray crosses:
// only which side of an edge a point lies on, and how far along its ray a plane lies, are
// worked out for each kind of ray.
//
// The includer defines, before including this file: `view_corner(d, t, k)` and
// `view_normal(d, t)` (a triangle's corner and unit normal in the witness's frame);
// `occluder_seen(q)` (what the witness's visibility image holds at pixel q: label, draw
// index, triangle, or zeros), `occluder_holds(q)` (whether the image holds pixel q, drawn for
// this point) and `occluder_draw(draw)` (the draw table's entry at a draw index the image holds); the edge links' spec constants
// LINK_INDEX_SHIFT, LINK_SAME_WAY and LINK_EDGE_MASK; and push constants `m` with
// `bias_relative`, the f32 rounding allowance relative to the coordinates.

// Twice the signed area of (a, b, q): which side of the line a → b the point q lies on.
float edge_function(vec2 a, vec2 b, vec2 q) {
    precise float area = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    return area;
}

// Which side of edge a → b, as the witness sees it, the point q lies on: for parallel rays,
// edge_function in xy; for rays from the origin, the volume of (a, b, q) from it, whose sign
// says which side of the plane through the origin, a and b the point lies on.
float edge_side(vec3 a, vec3 b, vec3 q, bool central) {
    if (central) {
        precise float volume = dot(cross(a, b), q);
        return volume;
    }
    return edge_function(a.xy, b.xy, q.xy);
}

// What edge_side is divided by to give q's distance from the edge's line (parallel rays) or
// from its plane through the origin (central rays).
float edge_span(vec3 a, vec3 b, bool central) {
    return central ? length(cross(a, b)) : length(b.xy - a.xy);
}

// How far p lies outside each edge of triangle (a, b, c) (a–b, b–c, c–a), as the witness sees
// them: negative inside.
vec3 outside_edges(vec3 a, vec3 b, vec3 c, vec3 p, bool central) {
    float winding = edge_side(a, b, c, central) >= 0.0 ? -1.0 : 1.0;
    return winding * vec3(edge_side(a, b, p, central), edge_side(b, c, p, central), edge_side(c, a, p, central))
         / max(vec3(edge_span(a, b, central), edge_span(b, c, central), edge_span(c, a, central)), vec3(1e-30));
}

// Whether p lies within `tolerance` of the box around triangle (a, b, c) as the witness sees it.
// Within the tolerance of each edge's line is not within it of the triangle: beyond a sharp
// corner the two lines meeting there part slowly, and a point far beyond a sliver's tip (an
// aspect ratio of 10⁴: 10⁴ times the tolerance beyond) lies within the tolerance of both. A
// point within it of the lines and of the box lies within a small multiple of it of the
// triangle. Rays from the origin are compared in the image plane z = 1, where a distance δ at
// p spans at most δ (p.z + max(|p.x|, |p.y|)) / p.z²; a triangle with a corner at or behind
// the witness's centre, or a point there, has no box there and passes.
bool within_box(vec3 a, vec3 b, vec3 c, vec3 p, float tolerance, bool central) {
    vec2 q = p.xy;
    if (central) {
        if (min(min(a.z, b.z), min(c.z, p.z)) <= 0.0) {
            return true;
        }
        q /= p.z;
        a.xy /= a.z;
        b.xy /= b.z;
        c.xy /= c.z;
        tolerance *= (p.z + max(abs(p.x), abs(p.y))) / (p.z * p.z);
    }
    vec2 lo = min(min(a.xy, b.xy), c.xy) - tolerance, hi = max(max(a.xy, b.xy), c.xy) + tolerance;
    return all(greaterThanEqual(q, lo)) && all(lessThanEqual(q, hi));
}

float l1_length(vec2 v) {
    return abs(v.x) + abs(v.y);
}

float l1_length(vec3 v) {
    return abs(v.x) + abs(v.y) + abs(v.z);
}

// Steps a walk over a surface may take before giving up; see walk_to and hides.
const int MAX_WALK_STEPS = 256;
// walk_to's answer when it gave up.
const uint WALK_TOO_LONG = 0xfffffffeu;
// walk_to's answer when it reached a triangle an earlier walk toward the same point went
// through (WalkMemo).
const uint WALK_JOINED = 0xfffffffdu;

// The triangles the latest walks toward one point went through (of one draw), the newest
// first, none where a slot holds NO_NEIGHBOUR. A walk's path depends only on the triangle it
// is on and the point (its corners are the triangle's, whichever way it was entered), so a
// walk that reaches a triangle an earlier walk went through goes on as that one did: it ends
// where that one ended, whose surface did not hide the point (else the test had stopped), or
// gives up sooner, which says the same. A walk that comes back to a triangle of its own goes
// round until it gives up: it stops at once, and says the same. Walks from the pixels around
// a point converge on the triangle over it, and on a dense mesh most of them join an earlier
// one within a step or two. A walk that gave up forgets them all: its steps were not all
// taken.
struct WalkMemo {
    uvec4 newer;
    uvec4 older;
};

const WalkMemo NO_WALKS = WalkMemo(uvec4(NO_NEIGHBOUR), uvec4(NO_NEIGHBOUR));

bool walked(WalkMemo memo, uint t) {
    return any(equal(memo.newer, uvec4(t))) || any(equal(memo.older, uvec4(t)));
}

void remember(inout WalkMemo memo, uint t) {
    memo.older = uvec4(memo.newer.w, memo.older.xyz);
    memo.newer = uvec4(t, memo.newer.xyz);
}

// Walks over the surface of draw d, from triangle t across edges toward the ray through p,
// each step leaving through the edge p lies farthest outside of. Returns the triangle whose
// rays hold p's (edges included, within `tolerance`), NO_NEIGHBOUR where this layer of the
// surface ends before p — a border, or a fold, where the surface turns away from the witness
// (its silhouette) — WALK_JOINED where it reached a triangle of `memo`, or WALK_TOO_LONG.
uint walk_to(DrawData d, uint t, vec3 p, float tolerance, bool central, inout WalkMemo memo) {
    if (walked(memo, t)) {
        return WALK_JOINED;
    }
    remember(memo, t);
    // Written without arrays: a software rasterizer keeps dynamically indexed arrays in memory.
    // Each step's corners are the ones the step before had.
    vec3 a = view_corner(d, t, 0u), b = view_corner(d, t, 1u), c = view_corner(d, t, 2u);
    for (int step = 0; step < MAX_WALK_STEPS; step++) {
        vec3 outside = outside_edges(a, b, c, p, central);
        float farthest = max(outside.x, max(outside.y, outside.z));
        if (farthest <= tolerance && within_box(a, b, c, p, tolerance, central)) {
            return t;
        }
        uint exit = outside.x == farthest ? 0u : (outside.y == farthest ? 1u : 2u);
        uint link = triangle_link(d, t, exit);
        if (link == NO_NEIGHBOUR) {
            return NO_NEIGHBOUR;
        }
        // Across the edge the surface goes on only if the neighbour lies on the other side of
        // the edge's line; on the same side, it folds back.
        vec3 from = exit == 0u ? a : (exit == 1u ? b : c);
        vec3 to = exit == 0u ? b : (exit == 1u ? c : a);
        vec3 opposite = exit == 0u ? c : (exit == 1u ? a : b);
        // The neighbour shares from and to (the same points: vertices are matched by
        // position), so only its third corner is read.
        uint next = link >> LINK_INDEX_SHIFT, edge = link & LINK_EDGE_MASK;
        // Whether the surface folds here or goes on, the walk ends as the earlier one did.
        if (walked(memo, next)) {
            return WALK_JOINED;
        }
        vec3 third = view_corner(d, next, (edge + 2u) % 3u);
        if (edge_side(from, to, opposite, central) * edge_side(from, to, third, central) >= 0.0) {
            return NO_NEIGHBOUR;
        }
        // Its corners in order: its edge number `edge` runs from → to, or back.
        bool same_way = (link & LINK_SAME_WAY) != 0u;
        vec3 first = same_way ? from : to, second = same_way ? to : from;
        a = edge == 0u ? first : (edge == 1u ? third : second);
        b = edge == 0u ? second : (edge == 1u ? first : third);
        c = edge == 0u ? third : (edge == 1u ? second : first);
        t = next;
        remember(memo, t);
    }
    memo = NO_WALKS;
    return WALK_TOO_LONG;
}

// The slope of a plane of normal n along the rays toward the witness, `toward` their unit
// direction at the point: how much nearer the witness the plane lies for each unit moved
// across the rays (the plane's gradient (∂z/∂x, ∂z/∂y, 0) for rays along +z). Infinite for
// a plane along the rays.
vec3 ray_slope(vec3 n, vec3 toward) {
    precise float across = dot(n, toward);
    precise vec3 slope = -(n - across * toward) / across;
    return slope;
}

// How far the plane of triangle t of draw d lies nearer the witness than p (witness frame)
// along the ray through p (negative: farther), and how much of that f32 rounding of the
// plane may account for, on top of the point's own `bias` (its error grows with the plane's
// slope). A plane the ray does not cross between p and the witness (seen edge-on, or met only
// at or behind a pinhole witness's centre) rises by −∞.
vec2 plane_rise(DrawData d, uint t, vec3 p, float scale, float bias, bool central, out vec3 slope) {
    vec3 n = view_normal(d, t);
    vec3 a = view_corner(d, t, 0u);
    if (central) {
        float distance = length(p);
        precise vec3 toward = -p / distance;
        precise float across = dot(n, toward);
        slope = ray_slope(n, toward);
        precise float rise = dot(n, a - p) / across;
        if (across == 0.0 || !(rise < distance)) {
            slope = vec3(0.0);
            return vec2(-1.0 / 0.0, bias);
        }
        precise float allowance = bias + m.bias_relative * scale * l1_length(slope);
        return vec2(rise, allowance);
    }
    if (n.z == 0.0) {
        slope = vec3(0.0);
        return vec2(-1.0 / 0.0, bias);
    }
    vec2 gradient = -n.xy / n.z;
    slope = vec3(gradient, 0.0);
    precise float rise = a.z + (gradient.x * (p.x - a.x) + gradient.y * (p.y - a.y)) - p.z;
    precise float allowance = bias + m.bias_relative * scale * l1_length(gradient);
    return vec2(rise, allowance);
}

// Whether the surface seen at a pixel of the witness's image hides p (witness frame): the
// triangle over p on that surface — found by walking from the one the pixel saw, since
// triangles smaller than a pixel are missing from the image — rises above p by more than the
// bias (exact ray casting). The walk holds p within its tolerance of the triangle, so the
// plane is evaluated up to that far beyond the triangle's edges: it must rise above p by more
// than a crease between it and p's own surface could explain there (each edge bends a
// polyhedral surface's slope by at most their difference; `own` is the slope of the surface
// through p, ray_slope). A ray that skims the edge of a face seen nearly edge-on, which f32
// cannot tell on which side of the edge it passes, passes it so. A walk that gives up says
// nothing of p: an occluder over p lies within a pixel or two of where a pixel saw it, a few
// steps away (a dense sphere's pole, whose fan of slivers a walk may cross, takes at most half
// its segments), and a walk that goes on longer has wandered off the layer over p (across a
// silhouette f32 misjudged).
// `lower` is the (draw, triangle) over p last found not to hide it: walks from the pixels
// around p mostly end on the same triangle, whose plane is then not evaluated again.
bool hides(DrawData d, uvec2 seen_at, vec3 p, vec3 own, float scale, float bias, bool central, inout uvec2 lower,
           inout WalkMemo memo) {
    float tolerance = m.bias_relative * scale;
    uint t = walk_to(d, seen_at.y, p, tolerance, central, memo);
    if (t == NO_NEIGHBOUR || t == WALK_TOO_LONG || t == WALK_JOINED || uvec2(seen_at.x, t) == lower) {
        return false;
    }
    vec3 slope;
    vec2 rise = plane_rise(d, t, p, scale, bias, central, slope);
    precise float bound = rise.y + l1_length(slope - own) * tolerance;
    if (rise.x > bound) {
        return true;
    }
    lower = uvec2(seen_at.x, t);
    return false;
}

// The k-th of the nine pixels around a pixel, from it: the pixel itself, then its eight
// neighbours in rows.
ivec2 nine_offset(int k) {
    int i = k == 0 ? 4 : k - int(k <= 4);
    return ivec2(i % 3 - 1, i / 3 - 1);
}

// Whether triangle t is a face of its mesh's convex hull (src/mesh/hull_faces.rs: bit t % 32
// of word t / 32 at `bits`, a device address).
bool on_hull(uvec2 bits, uint t) {
    return ((Words(bits).word[t >> 5u] >> (t & 31u)) & 1u) != 0u;
}

// Whether a point on a hull face of its model, in views that hold that model alone, is clear
// toward a witness its face's front turns toward, without a walk: nothing of the model lies in
// front of the face's plane but vertices up to `hull_tolerance` in front of it (their f32
// rounding), which rise along the ray toward the witness, at cosine facing / `lengths` to the
// face's normal (`facing` the dot product of the normal and the ray's direction, `lengths` the
// product of their lengths), by at most hull_tolerance · lengths / facing. The walks could only
// confirm it where that is at most half the bias's constant part, `bias_constant`.
bool hull_face_clear(float facing, float lengths, float bias_constant, float hull_tolerance) {
    return facing * bias_constant > 2.0 * hull_tolerance * lengths;
}

// Whether a surface lies between p (witness frame) and the witness, p's ray meeting the
// witness's image nearest pixel s: the surfaces seen at the pixels around s, each
// once. Exact wherever the occluder over p is seen at one of those nine pixel centres, or is
// joined by its edges to a triangle that is.
bool occluded(ivec2 s, vec3 p, vec3 own, float scale, float bias, bool central) {
    // Which of the nine to walk from, bit k for the k-th in order (the centre, then its eight
    // neighbours in rows), read in one pass that every invocation takes alike. A pixel that
    // saw what the centre saw, or what the pixel before it saw, is not walked from again (a
    // large triangle fills the whole neighbourhood). Background carries no triangle: a pair
    // no draw can have, so no neighbour is skipped for it.
    uint to_walk = 0u;
    uvec2 centre = uvec2(0xffffffffu), before = uvec2(0xffffffffu);
    for (int k = 0; k < 9; k++) {
        ivec2 q = s + nine_offset(k);
        uvec4 at = occluder_holds(q) ? occluder_seen(q) : uvec4(0u);
        if (at.x == 0u) {
            continue;
        }
        if (k == 0) {
            centre = at.yz;
        }
        if (k == 0 || (at.yz != centre && at.yz != before)) {
            to_walk |= 1u << k;
        }
        before = at.yz;
    }
    // The draw last read from the table, read again only for a pixel that saw another (a view
    // of one object has one): a software rasterizer gathers it word by word.
    uint loaded = 0xffffffffu;
    DrawData d;
    uvec2 lower = uvec2(0xffffffffu);
    // The walks of the draw last read.
    WalkMemo memo = NO_WALKS;
    // Each invocation takes its own pixels in turn, one walk a round: invocations that run in
    // lockstep then take as many rounds as the most walks any of them needs, not one for each
    // of the nine that any of them walks from.
    while (to_walk != 0u) {
        int k = findLSB(to_walk);
        to_walk &= to_walk - 1u;
        uvec2 seen = occluder_seen(s + nine_offset(k)).yz;
        if (seen.x != loaded) {
            d = occluder_draw(seen.x);
            loaded = seen.x;
            memo = NO_WALKS;
        }
        if (hides(d, seen, p, own, scale, bias, central, lower, memo)) {
            return true;
        }
    }
    return false;
}
