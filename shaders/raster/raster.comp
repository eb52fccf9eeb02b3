#version 460
// The compute rasterizer's coverage passes (src/render/raster/compute/), over the range
// view and, where there is one, the shadow view at once: a triangle's corners and normal are
// read once for both (reading them is most of a small triangle's set-up). Corners go to window
// coordinates as raster.vert and the viewport transform put them, are snapped to 1/256 pixel
// (lavapipe's sub-pixel precision), and a pixel is covered when its centre is inside every
// edge, or on a top or left edge (the top-left rule, framebuffer y down), in exact integer
// arithmetic (raster_edges.glsl). Each covered pixel keeps the nearest triangle by atomicMin
// on its view's visibility word (visibility_word.glsl). The range view of one draw orders its
// triangles by the z it holds, the plane's at the exact pixel centre (range_pixel, draw.glsl),
// and keeps that z in the word, from which the view is resolved. The shadow view, whose key
// nothing reads, and views of several draws, whose ties passes compare depths, order them by
// the depth of the triangle's plane, affine in the pixel's column and row in an orthographic
// view (two multiply-adds a pixel). That depth decides, in every view, whether the pixel is
// clipped.
//
// Small triangles: one invocation per triangle walks its bounding box in each view, in 32-bit
// arithmetic, by tiles of at most 8 × 8 pixels, each first as coverage bits, then keeping
// each covered pixel, up to 33 × 33 pixels (25 tiles; one, where the host found every box
// fits one: TILES). A triangle whose corners lie more than 32 pixels from its box's first
// pixel centre (beyond 32-bit edge functions; so does any box over 33 pixels a side) is
// queued for that view instead, and LARGE_TRIANGLES, dispatched indirectly, gives each queued
// (triangle, view) a workgroup whose 64 invocations share its rows, in 64-bit arithmetic: one
// invocation never serialises thousands of pixels.
//
// A view of several draws (TIES): its draws are the members of one dispatch, sharing the
// view's words, each triangle's index tagged with its member's place in the order the
// graphics path draws them in its ties pass (draw.rs: the lowest label last). The graphics
// path keeps, among the fragments within the tie depth of the nearest (tie_depth, draw.glsl),
// the last drawn. Here the first passes keep the nearest (depth, tagged triangle) as for one
// draw; then the TIES variants cover every triangle again, the large ones from the queue the
// first filled, and where a triangle's depth less its tie depth (tie_depth, of its own
// plane) is no more than the nearest's, keep the larger tagged triangle with an atomicMax:
// the last drawn.
//
// PINHOLE: the variants for a rig's pinhole views (src/render/raster/compute/rig.rs), one or
// two views a dispatch (the reference view, and a witness's band as the shadow view), each
// view's words shared by the members, its draws, as in a view of several draws. Corners go
// to window coordinates as raster.vert's pinhole_clip_position and the viewport transform put
// them (x and y times 1 / w, as lavapipe divides). The depth s / Z − s / far of a triangle's plane is affine in the pixel's column
// and row too (1 / Z at a pixel is (n · ray) / (n · a), and the ray's x and y are affine in
// them), so it steps as an orthographic view's does; the nearest has the greatest, keyed by
// its flipped bits. A solid's triangles are culled as the graphics pipeline culls them, by the
// sign of their snapped corners' area (a pinhole view has no one direction to test a normal
// against; one turned clearly away is skipped by its normal first: turned_away), and the ties
// passes allow pinhole_tie_depth (draw.glsl) at each pixel. A triangle the near plane cuts, or
// one reaching far beyond the view, goes to the large triangles' pass, which clips it to the
// near plane and the viewport as the graphics pipeline's clipper does (clipped_polygon) and
// covers what is left, fanned into triangles.
//
// A software rasterizer runs every instruction of a shader for every group of invocations,
// whatever their branches, so the small triangles' pass holds no 64-bit path of its own.
#ifdef TIES
#extension GL_KHR_memory_scope_semantics : require
#endif
#include "raster_compute.glsl"
layout(local_size_x = COVERAGE_GROUP) in;

// Many hypotheses a dispatch: a coverage dispatch covers up to COVERAGE_MEMBERS jobs
// (contract.glsl), one a z slice of its workgroups (the large triangles' pass reads each queued
// triangle's member from the queue), so that a GPU pays a dispatch and a barrier per group
// rather than per hypothesis. MEMBERS, a specialization constant, is 1 or COVERAGE_MEMBERS:
// with 1, the member is the constant 0 and every read of its constants is at a constant offset,
// as a software rasterizer needs (it gathers a uniform read at an index it cannot prove the
// same for all its lanes, lane by lane), and keep_word's branches fold away.

// Each member's draw in each view and its constants (Member, below), which the host writes
// before the pass (CoverageUniforms in src/render/raster/compute/): draws[m] the range view's
// of member m, draws[COVERAGE_MEMBERS + m] its shadow view's (where it has none, zeros, read
// only to cull: it covers no pixels; member_draw). A uniform block, not a storage buffer: a
// software rasterizer loads a uniform block's value once for all the invocations it runs
// together, a storage buffer's invocation by invocation. A new branch on one of its values may
// make lavapipe compile the shader again at every dispatch (keep).

// What a member's pass needs beside its draws; matches `MemberConstants` in
// src/render/raster/compute/.
struct Member {
    RasterView views[2]; // range view, shadow view (of no pixels where the member has none)
    uint triangles;      // the mesh's triangle count; 0 for a member with nothing to cover
    int cull;            // skip triangles whose view-frame normal z has the opposite sign; 0: none
    uint dealt_rows;     // blocks of the workgroups dealt over the stripes, per stripe (main)
    uint place;          // where members share words, its place in the ties order, which tags
                         // its triangles there (above bit MEMBER_SHIFT); else 0
    uint z_keys;         // 1: its range view's words hold z keys (visibility_word.glsl): a
                         // view of one draw; 0: depths, for words shared by several draws
    int second_cull;     // PINHOLE: view 1's cull (a witness's band beside the reference view,
                         // which may lie inside a solid the reference view culls); else `cull`
    uint pad0, pad1;
};
layout(set = 0, binding = 0, std140) uniform Coverage {
    DrawData draws[2 * COVERAGE_MEMBERS];
    Member members[COVERAGE_MEMBERS];
};

// Member m's draw in view v (0: range, 1: shadow).
DrawData member_draw(uint m, uint v) {
    return draws[v * COVERAGE_MEMBERS + m];
}

// Each member's visibility words in each view (where a view or a member is missing, another
// member's are bound, never written: a member with no job covers no triangles, a view of no
// pixels none of them): a binding each, as keep_word picks them, for COVERAGE_MEMBERS = 4
// (COVERAGE_STORAGE_BUFFERS in src/render/raster/compute/ counts them).
#if COVERAGE_MEMBERS != 4
#error "raster.comp binds and picks four members' words"
#endif
layout(set = 0, binding = 1, std430) buffer RangeWords0 { uint64_t words[]; } range_words0;
layout(set = 0, binding = 2, std430) buffer RangeWords1 { uint64_t words[]; } range_words1;
layout(set = 0, binding = 3, std430) buffer RangeWords2 { uint64_t words[]; } range_words2;
layout(set = 0, binding = 4, std430) buffer RangeWords3 { uint64_t words[]; } range_words3;
layout(set = 0, binding = 5, std430) buffer ShadowWords0 { uint64_t words[]; } shadow_words0;
layout(set = 0, binding = 6, std430) buffer ShadowWords1 { uint64_t words[]; } shadow_words1;
layout(set = 0, binding = 7, std430) buffer ShadowWords2 { uint64_t words[]; } shadow_words2;
layout(set = 0, binding = 8, std430) buffer ShadowWords3 { uint64_t words[]; } shadow_words3;
// The queue of large (triangle, member, view) entries: the view's bit (QUEUE_VIEW_BIT), then
// the member's bits (from MEMBER_SHIFT), above the triangle's index (meshes have fewer than
// 2^MEMBER_SHIFT triangles: src/mesh/adjacency.rs), with room for every triangle of every
// member in every view. PINHOLE: the triangles the clipper may cut (cover_pinhole) are queued
// from the queue's end, the others from its start, so that the large triangles' passes of the
// others hold no clipping code, which a software rasterizer would run for every queued
// triangle whether it clips or not, and CLIPPED's take the rest. Each part's indirect dispatch
// (x, y, z), x its length up to MAX_GROUPS, then its length: the start's, then the end's
// (LargeArgs in src/render/raster/compute/).
layout(set = 0, binding = 9, std430) buffer Large { uint large[]; };
layout(set = 0, binding = 10, std430) buffer LargeArgs { uvec4 queue_parts[2]; };
const uint QUEUE_START = 0u, QUEUE_END = 1u;

// Where the queue's entry i of a part lies: from its start, or from its end.
uint queued_at(uint part, uint i) {
    return part == QUEUE_START ? i : large.length() - 1u - i;
}

// Corners nearer than this to the centre of their box's first pixel (1/256 pixel: 32 pixels;
// their box then spans at most 33) keep every edge function in the box below 2^30.
const float NEAR = 8192.0;

// Workgroups a dispatch is given at most along x (every device allows 65,535), given by the
// host (raster/compute/): the large triangles' workgroups stride over the rest of the queue.
layout(constant_id = 0) const uint MAX_GROUPS = 1u;
// 1: the range view alone; 2: and the shadow view. One pipeline each (raster/compute/): a
// software rasterizer would run the shadow view's code even where it has none.
layout(constant_id = 1) const uint VIEW_COUNT = 2u;
// Workgroups a block, and stripes the blocks are dealt over (powers of two; main).
layout(constant_id = 2) const uint DEAL_BLOCK = 1u;
layout(constant_id = 3) const uint DEAL_STRIPES = 1u;
// 1: a dispatch covers one job, the member the constant 0; COVERAGE_MEMBERS: up to that many
// (see above).
layout(constant_id = 4) const uint MEMBERS = 1u;
// 1: boxes of up to 33 pixels a side are covered by tiles (cover_tiles); 0: the host found no
// triangle of the dispatch's meshes can have a box over 8 pixels in its views (every edge
// shorter than 6 pixels: raster/compute/), so the tiles' code is left out, and a box over 8
// pixels, were there one, would go to the large triangles' pass (exact too, but slow for
// many). A software rasterizer runs the tiles' loops at least once for every group of
// invocations, whatever their boxes, so a dispatch that needs none leaves them out.
layout(constant_id = 5) const uint TILES = 1u;

// Window coordinates of a view-frame point, operation for operation as raster.vert and the
// viewport transform compute them (its scale the viewport's half side, its offset the
// viewport's centre: src/render/raster/draw.rs, `ViewportFrame`).
vec3 window(DrawData d, vec3 v) {
#ifdef PINHOLE
    precise vec4 clip = pinhole_clip_position(d, v);
    precise float inverse_w = 1.0 / clip.w;
    precise vec2 w = clip.xy * inverse_w * d.viewport_half_side + d.viewport_centre;
    precise float depth = clip.z * inverse_w;
    return vec3(w, depth);
#else
    precise vec3 clip = clip_position(d, v);
    precise vec2 w = clip.xy * d.viewport_half_side + d.viewport_centre;
    return vec3(w, clip.z);
#endif
}

// Window coordinates snapped to 1/256 pixel, in those units: whole numbers.
vec2 snap(vec2 w) {
    return roundEven(w * 256.0);
}

// The edge functions in the width each pass steps them in: 64 bits for the queued triangles,
// 32 for the others.
#ifdef LARGE_TRIANGLES
#define EDGE_INT int64_t
#define EDGE_IVEC2 i64vec2
#define EDGE_IVEC3 i64vec3
#define EDGES Edges64
#else
#define EDGE_INT int
#define EDGE_IVEC2 ivec2
#define EDGE_IVEC3 ivec3
#define EDGES Edges32
#endif
#include "raster_edges.glsl"

// A triangle as the mesh stores it: read once, rendered in each view.
struct MeshTriangle {
    vec3 corner[3];
    vec3 normal;
};

// Its corners, the normal (and the third corner's z: triangle_words.glsl) already read.
MeshTriangle read_triangle(DrawData d, uint t, vec3 normal, float third_z) {
    MeshTriangle m;
    mesh_corners_by_words(d, t, third_z, m.corner);
    m.normal = normal;
    return m;
}

// A solid's triangles facing away from the camera are never the first hit
// (src/mesh/solid.rs).
bool culled(int cull, DrawData d, vec3 model_normal) {
    return cull != 0 && float(cull) * rotate_to_view(d, model_normal).z < 0.0;
}

// PINHOLE: whether the graphics pipeline's cull mode drops a triangle, `area` twice the signed
// area of its snapped corners (edge, raster_edges.glsl; framebuffer y down): a front face
// (counter-clockwise) has a negative one, and `cull` 1 drops back faces, −1 front faces.
bool culled_by_winding(int cull, EDGE_INT area) {
    return (cull > 0 && area > 0) || (cull < 0 && area < 0);
}

#ifdef PINHOLE
// PINHOLE: whether a solid's triangle (its normal and a corner as the mesh stores them) faces
// away from the view's centre by more than TURNED_AWAY (the sine of the angle between its
// plane and the ray to its corner): so far from edge-on that its snapped corners wind as its
// normal says, and the graphics pipeline culls it, unless it is a sliver narrower than about
// 1/64 pixel across where snapping may turn its winding (rasterizers.md, "Same images"). The
// small triangles' pass then skips it before reading its other corners, as the scanner's
// views skip a triangle by its normal.
const float TURNED_AWAY = 1.0 / 1024.0;
bool turned_away(int cull, DrawData d, vec3 model_normal, vec3 model_corner) {
    vec3 n = rotate_to_view(d, model_normal), a = to_view(d, model_corner);
    return cull != 0 && float(cull) * dot(n, a) > TURNED_AWAY * length(a);
}
#endif

// A triangle set up for coverage tests in one view of one member: its snapped corners, the
// pixels of its bounding box within the view's area, and its plane's depth.
struct Setup {
    uint member, view;      // whose words it keeps (keep_word)
    uint tag;               // its member's place, above bit MEMBER_SHIFT (Member)
    int cull;               // PINHOLE: its member's cull (Member; culled_by_winding)
    float tie;              // TIES: its tie depth (tie_depth); PINHOLE: s / far (its depths'
                            // constant term, for pinhole_tie_depth_of at each pixel)
    uint stride;            // the view's pixels a row
    float depth_first;      // the plane's depth (0..1) at the box's first pixel,
    vec2 depth_step;        // and its change a column right and a row down
    bool z_keys;            // its words' keys are z keys (Member): then the plane's z at the
    vec4 grid;              // pixel decides, from the view's grid (DrawData), a corner and the
    vec3 corner, normal;    // unit normal, both in the view's frame
    vec2 a, b, c;           // snapped corners (snap)
    ivec2 first, last;
};

// A triangle's corners and unit normal in a view's frame.
struct ViewTriangle {
    vec3 corner[3];
    vec3 normal;
};

ViewTriangle to_view_triangle(DrawData d, MeshTriangle m) {
    ViewTriangle v;
    v.corner[0] = to_view(d, m.corner[0]);
    v.corner[1] = to_view(d, m.corner[1]);
    v.corner[2] = to_view(d, m.corner[2]);
    v.normal = rotate_to_view(d, m.normal);
    return v;
}

#ifdef PINHOLE
// How far point p (view frame) lies inside clipping plane k of a pinhole view, in clip
// coordinates as raster.vert's pinhole_clip_position gives them to the clipper: 0 the near
// plane (z ≤ w), 1–4 the viewport's sides (x ≤ w, −w ≤ x, y ≤ w, −w ≤ y). The same f32
// arithmetic, so that a corner on the near plane (a face lying in it) is kept or cut as the
// graphics pipeline keeps or cuts it.
float inside_clip_plane(DrawData d, int k, vec3 p) {
    precise vec4 clip = pinhole_clip_position(d, p);
    float along = k == 0 ? clip.z : (k < 3 ? clip.x : clip.y);
    precise float inside = k == 0 || (k & 1) == 1 ? clip.w - along : clip.w + along;
    return inside;
}

// The polygon of a pinhole view's triangle that the graphics pipeline's clipper keeps: within
// the viewport (a far larger square than the view: src/render/raster/draw.rs, ViewportFrame)
// and beyond the near plane, its corners in order in `polygon` (at most 8, a triangle cut by
// five planes), and how many. For the large triangles' pass, whose parts of a triangle then
// reach no farther than the viewport: the small triangles' pass queues every triangle the near
// plane cuts, and every one with a corner farther than it covers (cover_pinhole).
int clipped_polygon(DrawData d, ViewTriangle v, out vec3 polygon[8]) {
    polygon[0] = v.corner[0];
    polygon[1] = v.corner[1];
    polygon[2] = v.corner[2];
    int corners = 3;
    for (int k = 0; k < 5; k++) {
        vec3 kept[8];
        int count = 0;
        for (int i = 0; i < corners; i++) {
            vec3 a = polygon[i], b = polygon[i + 1 == corners ? 0 : i + 1];
            float inside_a = inside_clip_plane(d, k, a), inside_b = inside_clip_plane(d, k, b);
            // A convex polygon gains at most one corner a plane; rounding could make one that
            // is not quite convex gain more, which the array's bound keeps out.
            if (inside_a >= 0.0 && count < 8) {
                kept[count++] = a;
            }
            if ((inside_a >= 0.0) != (inside_b >= 0.0) && count < 8) {
                kept[count++] = mix(a, b, inside_a / (inside_a - inside_b));
            }
        }
        polygon = kept;
        corners = count;
    }
    return corners;
}
#endif

// Sets up corners c0, c1, c2 (view frame) of triangle `plane`: the triangle itself, or
// (PINHOLE) a part of it the clipper keeps, whose depths are its plane's.
Setup set_up(uint member, uint v, DrawData d, Member constants, ViewTriangle plane, vec3 c0, vec3 c1, vec3 c2) {
    RasterView view = constants.views[v];
    Setup s;
    s.member = member;
    s.view = v;
    s.tag = constants.place << MEMBER_SHIFT;
    s.cull = v == 0u ? constants.cull : constants.second_cull;
    s.stride = view.stride;
    vec3 corner = plane.corner[0], normal = plane.normal;
    s.z_keys = v == 0u && constants.z_keys != 0u;
    s.grid = d.grid;
    s.corner = corner;
    s.normal = normal;
    precise vec3 v0 = window(d, c0);
    precise vec3 v1 = window(d, c1);
    precise vec3 v2 = window(d, c2);
    s.a = snap(v0.xy);
    s.b = snap(v1.xy);
    s.c = snap(v2.xy);
    // Pixel centres (col + ½, row + ½) inside the bounding box and the area.
    vec2 lo = min(min(v0.xy, v1.xy), v2.xy), hi = max(max(v0.xy, v1.xy), v2.xy);
    s.first = max(ivec2(floor(lo - 0.5)), ivec2(view.area.xy));
    s.last = min(ivec2(ceil(hi - 0.5)), ivec2(view.area.xy + view.area.zw) - 1);
#ifdef PINHOLE
    // s (n · ray) / (n · a) − s / far, the ray's x and y affine in the pixel's column and row.
    precise float across_corner = normal.x * corner.x + normal.y * corner.y + normal.z * corner.z;
    vec3 ray = pinhole_ray(d.grid, vec2(s.first));
    precise float across_ray = normal.x * ray.x + normal.y * ray.y + normal.z * ray.z;
    precise float depth_first = d.z_range.x * across_ray / across_corner - d.z_range.y;
    precise vec2 depth_step = d.z_range.x * (normal.xy / d.grid.xy) / across_corner;
    s.depth_first = depth_first;
    s.depth_step = depth_step;
    s.tie = d.z_range.y;
#else
    // In an orthographic view the plane's depth is affine in the pixel's column and row.
    s.depth_first = (d.z_range.y - plane_z(d.grid, corner, normal, vec2(s.first))) / (d.z_range.y - d.z_range.x);
    s.depth_step = depth_step(d, normal);
#ifdef TIES
    s.tie = tie_depth(d, s.depth_step);
#endif
#endif
    return s;
}

// The centre of the box's first pixel, in snapped units: where the edge functions start.
vec2 box_origin(Setup s) {
    return vec2(s.first) * 256.0 + 128.0;
}

// Keeps the nearer of `word` and member m's word at `at` in view v (TIES: the larger, their
// depths the same). A member's words are a binding of their own, so it is picked by
// branches, the same for a whole workgroup (with one member, constant: a software rasterizer
// runs every branch).
#ifdef TIES
#define KEEP atomicMax
#else
#define KEEP atomicMin
#endif
void keep_word(uint m, uint v, uint at, uint64_t word) {
    if (v == 0u) {
        switch (m) {
            case 0u: KEEP(range_words0.words[at], word); break;
            case 1u: KEEP(range_words1.words[at], word); break;
            case 2u: KEEP(range_words2.words[at], word); break;
            default: KEEP(range_words3.words[at], word); break;
        }
    } else {
        switch (m) {
            case 0u: KEEP(shadow_words0.words[at], word); break;
            case 1u: KEEP(shadow_words1.words[at], word); break;
            case 2u: KEEP(shadow_words2.words[at], word); break;
            default: KEEP(shadow_words3.words[at], word); break;
        }
    }
}

#ifdef TIES
// The word at `at` in view v that the members share (member 0's binding, as every member's
// is the same buffer), read atomically (relaxed), as other invocations keep theirs there.
uint64_t read_shared_word(uint v, uint at) {
    const int device = gl_ScopeDevice, storage = gl_StorageSemanticsBuffer, relaxed = gl_SemanticsRelaxed;
    return v == 0u ? atomicLoad(range_words0.words[at], device, storage, relaxed)
                   : atomicLoad(shadow_words0.words[at], device, storage, relaxed);
}
#endif

// Keeps the triangle at a covered pixel of its view if it is the nearest there so far.
void keep(uint t, Setup s, ivec2 pixel) {
    vec2 from_first = vec2(pixel - s.first);
    float depth = fma(from_first.x, s.depth_step.x, fma(from_first.y, s.depth_step.y, s.depth_first));
    // Clipped as the graphics pipeline clips, and the depth clear value (PINHOLE: 0, the far
    // plane, never greater; else 1, never less) never passes. (A pinhole view's near plane
    // clips its triangles, not its pixels: cover_pinhole, clipped_polygon.)
#ifdef PINHOLE
    if (!(depth > 0.0)) {
        return;
    }
#else
    if (!(depth >= 0.0 && depth < 1.0)) {
        return;
    }
#endif
    uint at = word_index(s.stride, pixel);
#ifdef TIES
    // The nearest depth, which this pass leaves as it is, and the tagged triangle kept so far:
    // a keep only where this one is within the tie depth and would replace it (it is then
    // rare: most pixels hold one triangle within the tie depth, the nearest, already kept).
    uint64_t word = read_shared_word(s.view, at), tagged = uint64_t(s.tag | t);
#ifdef PINHOLE
    float tie = pinhole_tie_depth_of(s.grid, s.tie, s.normal, vec2(pixel), depth);
    bool tied = min(depth + tie, 1.0) >= uintBitsToFloat(~uint(word >> 32));
#else
    bool tied = max(depth - s.tie, 0.0) <= uintBitsToFloat(uint(word >> 32));
#endif
    if (tied && tagged > (word & 0xfffffffful)) {
        keep_word(0u, s.view, at, (word & 0xffffffff00000000ul) | tagged);
    }
#else
    // The same z, from the same arithmetic on the same record, as the view's resolve would work out
    // (range_pixel_of, draw.glsl), which then reads it here. Worked out in every view and then
    // selected (an OpSelect of two locals: glslang makes a branch of a ?: whose operands call
    // functions), not branched on: with a branch on z_keys, lavapipe takes several times as
    // long a hypothesis, and its memory grows with each one, as if it compiled the shader again
    // at every dispatch. It can inline into a shader the values of a uniform block that decide
    // a branch, and this block is written before every dispatch.
#ifdef PINHOLE
    // The greatest depth is the nearest: a positive float's bits flipped order it first.
    uint key = ~floatBitsToUint(depth);
#else
    uint z = z_key(plane_z(s.grid, s.corner, s.normal, vec2(pixel)));
    uint depth_bits = floatBitsToUint(depth);
    uint key = s.z_keys ? z : depth_bits;
#endif
    uint64_t word = (uint64_t(key) << 32) | uint64_t(s.tag | t);
    keep_word(s.member, s.view, at, word);
#endif
}

#ifdef LARGE_TRIANGLES
// Tests the pixels of one row of the box, `e` the edge functions at its first, in 64 bits.
void cover_row(uint t, Setup s, int row, i64vec3 e, i64vec3 right) {
    for (int col = s.first.x; col <= s.last.x; col++) {
        if ((e.x | e.y | e.z) >= 0) {
            keep(t, s, ivec2(col, row));
        }
        e += right;
    }
}

// Covers a queued triangle's box, its rows shared by the workgroup's invocations.
void cover_large(uint t, Setup s) {
    // Exact anywhere in the view: 64-bit edge functions, relative to the box.
    i64vec2 origin = i64vec2(box_origin(s));
    i64vec2 a = i64vec2(s.a) - origin, b = i64vec2(s.b) - origin, c = i64vec2(s.c) - origin;
#ifdef PINHOLE
    if (culled_by_winding(s.cull, edge(a, b, c))) {
        return;
    }
#endif
    Edges64 e = edges_of(a, b, c);
    // A triangle of no area covers nothing (edges_of): no rows to walk.
    if (e.right == i64vec3(0) && e.down == i64vec3(0)) {
        return;
    }
    for (int row = s.first.y + int(gl_LocalInvocationIndex); row <= s.last.y; row += int(gl_WorkGroupSize.x)) {
        cover_row(t, s, row, e.first + e.down * int64_t(row - s.first.y), e.right);
    }
}

// The part of the queue this pass takes: the triangles the clipper may cut (CLIPPED), or the
// others.
#ifdef CLIPPED
const uint PART = QUEUE_END;
#else
const uint PART = QUEUE_START;
#endif

void main() {
    // The workgroups stride over their part of the queue, which may be longer than a
    // dispatch's groups.
    for (uint queued = gl_WorkGroupID.x; queued < queue_parts[PART].w; queued += gl_NumWorkGroups.x) {
        uint entry = large[queued_at(PART, queued)];
        uint v = entry >> QUEUE_VIEW_BIT, t = untagged(entry);
        uint member = MEMBERS == 1u ? 0u : (entry >> MEMBER_SHIFT) & (COVERAGE_MEMBERS - 1u);
        DrawData d = member_draw(member, v);
        float third_z;
        vec3 normal = mesh_normal_by_words(d, t, third_z);
        ViewTriangle in_view = to_view_triangle(d, read_triangle(d, t, normal, third_z));
#ifdef CLIPPED
        // What the clipper keeps of it (clipped_polygon), fanned into triangles.
        vec3 polygon[8];
        int corners = clipped_polygon(d, in_view, polygon);
        for (int k = 1; k + 1 < corners; k++) {
            cover_large(t, set_up(member, v, d, members[member], in_view, polygon[0], polygon[k], polygon[k + 1]));
        }
#else
        cover_large(t, set_up(member, v, d, members[member], in_view, in_view.corner[0], in_view.corner[1], in_view.corner[2]));
#endif
    }
}
#else
// Queues (t, its member, its view), from the queue's end where the clipper may cut it
// (`clipped`, PINHOLE): the queue has room for every triangle of every member in every view.
void queue_large(uint t, Setup s, bool clipped) {
    uint part = clipped ? QUEUE_END : QUEUE_START;
    uint i = atomicAdd(queue_parts[part].w, 1u);
    large[queued_at(part, i)] = t | (s.member << MEMBER_SHIFT) | (s.view << QUEUE_VIEW_BIT);
    if (i < MAX_GROUPS) {
        atomicAdd(queue_parts[part].x, 1u);
    }
}

// The tile of at most 8 × 8 pixels of a triangle's box from `tile` (relative to the box's
// first pixel), `tile_first` the edge functions at its first pixel, stepped in 32 bits: the
// pixels it covers are first found as bits (8 a row, rows 0–3 in x, 4–7 in y), then kept one
// set bit at a time, so that invocations running in lockstep take as many rounds of keep as
// the most pixels any of them covers, not as the largest box among them has pixels. (A
// software rasterizer runs a keep for every lane of every round, covered or not.)
void cover_tile(uint t, Setup s, ivec2 tile, ivec3 tile_first, Edges32 e) {
    uvec2 covered = uvec2(0u);
    ivec3 row_start = tile_first;
    ivec2 size = min(s.last - s.first + 1 - tile, ivec2(8));
    for (int row = 0; row < size.y; row++) {
        ivec3 at = row_start;
        for (int col = 0; col < size.x; col++) {
            uint bit = ((at.x | at.y | at.z) >= 0 ? 1u : 0u) << uint(((row & 3) << 3) | col);
            if (row < 4) {
                covered.x |= bit;
            } else {
                covered.y |= bit;
            }
            at += e.right;
        }
        row_start += e.down;
    }
    while (covered != uvec2(0u)) {
        bool low = covered.x != 0u;
        uint bits = low ? covered.x : covered.y;
        int k = findLSB(bits);
        bits &= bits - 1u;
        if (low) {
            covered.x = bits;
        } else {
            covered.y = bits;
        }
        keep(t, s, s.first + tile + ivec2(k & 7, (k >> 3) + (low ? 0 : 4)));
    }
}

// A box wider or taller than 8 pixels (at most 33), tile by tile: faster than pixel by pixel
// with a keep at each, and than the large triangles' pass, for the many such boxes of a dense
// mesh at high resolution. A box of one tile keeps its own, cheaper path (cover_tile). The edge
// functions at a tile's first pixel lie in the box, below 2^30: the sum wraps to them exactly.
void cover_tiles(uint t, Setup s, Edges32 e) {
    ivec2 box = s.last - s.first + 1;
    for (int ty = 0; ty < box.y; ty += 8) {
        for (int tx = 0; tx < box.x; tx += 8) {
            cover_tile(t, s, ivec2(tx, ty), e.first + e.right * tx + e.down * ty, e);
        }
    }
}

// How the small triangles' pass covers a set-up triangle: not at all (its box misses the
// view's area), here, or by the large triangles' pass (far, or with TILES 0 a box over 8
// pixels). The ties pass finds the same triangles far or large as the pass before it (the
// same precise arithmetic on the same inputs) and leaves them to the large triangles' ties
// pass, which reads the queue that pass filled.
const uint COVERED_NOWHERE = 0u, COVERED_HERE = 1u, COVERED_LARGE = 2u;
uint coverage_of(Setup s) {
#ifdef PINHOLE
    // A corner far beyond the view (a model reaching near the view's centre, its corners far
    // out in the image plane, or overflowing): the large triangles' pass clips it as the
    // graphics pipeline does (clipped_polygon), and its box is found from what that leaves.
    vec2 farthest = max(max(abs(s.a), abs(s.b)), abs(s.c));
    if (!all(lessThan(farthest, vec2(256.0 * 16777216.0)))) {
        return COVERED_LARGE;
    }
#endif
    ivec2 box = s.last - s.first + 1;
    if (box.x <= 0 || box.y <= 0) {
        return COVERED_NOWHERE;
    }
    // Relative to the box's first pixel centre, a corner's rounded difference below NEAR is
    // its exact one, where that centre is exact: a whole number below 2^24 (views under 65,536
    // pixels a side; beyond, the triangle is queued).
    vec2 origin = box_origin(s), a = s.a - origin, b = s.b - origin, c = s.c - origin;
    bool near = all(lessThan(max(max(abs(a), abs(b)), abs(c)), vec2(NEAR))) && all(lessThan(origin, vec2(16777216.0)));
    return near && (TILES != 0u || all(lessThanEqual(box, ivec2(8)))) ? COVERED_HERE : COVERED_LARGE;
}

// Covers a set-up triangle's pixels here (coverage_of: COVERED_HERE).
void cover_here(uint t, Setup s) {
    ivec2 box = s.last - s.first + 1;
    vec2 origin = box_origin(s);
    ivec2 a = ivec2(s.a - origin), b = ivec2(s.b - origin), c = ivec2(s.c - origin);
#ifdef PINHOLE
    if (culled_by_winding(s.cull, edge(a, b, c))) {
        return;
    }
#endif
    Edges32 e = edges_of(a, b, c);
    if (all(lessThanEqual(box, ivec2(8)))) {
        cover_tile(t, s, ivec2(0), e.first, e);
    } else {
        cover_tiles(t, s, e);
    }
}

#ifdef PINHOLE
// Whether a set-up triangle may reach past the viewport's sides, where the clipper cuts it: a
// snapped corner past 1 − 2⁻¹⁰ of the viewport's half side from its centre, or not finite. The
// margin is far wider than the rounding that parts window coordinates from the clipper's clip
// coordinates (inside_clip_plane), so that every triangle the clipper cuts is found; one found
// that it keeps whole is kept whole by clipped_polygon too, and covered alike.
bool may_reach_past_viewport(DrawData d, Setup s) {
    vec2 centre = d.viewport_centre * 256.0;
    vec2 farthest = max(max(abs(s.a - centre), abs(s.b - centre)), abs(s.c - centre));
    float bound = d.viewport_half_side * 256.0 * (1.0 - 1.0 / 1024.0);
    return !all(lessThanEqual(farthest, vec2(bound)));
}

// Covers triangle t of a member's pinhole view `view` (`v` its corners and normal there), or queues
// it for the large triangles' pass, which clips it as the graphics pipeline's clipper does
// (clipped_polygon): where it is large or far, and where the near plane cuts it (rare: a model
// reaching the view's centre, as a floor under a camera does).
void cover_pinhole(uint member, uint view, DrawData d, Member constants, uint t, ViewTriangle v) {
    Setup s = set_up(member, view, d, constants, v, v.corner[0], v.corner[1], v.corner[2]);
    float nearest = min(min(inside_clip_plane(d, 0, v.corner[0]), inside_clip_plane(d, 0, v.corner[1])),
                        inside_clip_plane(d, 0, v.corner[2]));
    bool cut = !(nearest >= 0.0);
    uint coverage = cut ? COVERED_LARGE : coverage_of(s);
    if (coverage == COVERED_HERE) {
        cover_here(t, s);
    }
#ifndef TIES
    else if (coverage == COVERED_LARGE) {
        queue_large(t, s, cut || may_reach_past_viewport(d, s));
    }
#endif
}
#else
// Covers a triangle's pixels in view v of a member, or queues it there for the large
// triangles' pass.
void cover(uint member, uint v, DrawData d, Member constants, uint t, MeshTriangle m) {
    ViewTriangle in_view = to_view_triangle(d, m);
    Setup s = set_up(member, v, d, constants, in_view, in_view.corner[0], in_view.corner[1], in_view.corner[2]);
    uint coverage = coverage_of(s);
    if (coverage == COVERED_HERE) {
        cover_here(t, s);
    }
#ifndef TIES
    else if (coverage == COVERED_LARGE) {
        queue_large(t, s, false);
    }
#endif
}
#endif

void main() {
    // A member a z slice of the workgroups.
    uint member = MEMBERS == 1u ? 0u : gl_WorkGroupID.z;
    DrawData range_draw = member_draw(member, 0u);
    DrawData shadow_draw = member_draw(member, 1u);
    Member constants = members[member];
    // Dispatched as up to 65,535 workgroups per row (src/render/raster/compute/). A software
    // rasterizer hands each of its threads a contiguous range of a dispatch's workgroups
    // (lavapipe: the count over the threads), and a mesh's triangles lie in its file's order,
    // near ones together: one range may hold every triangle facing the camera and another
    // none (a UV sphere seen along its poles: the front half first). So the workgroups' blocks
    // are dealt like cards: block b of the first DEAL_STRIPES × dealt_rows goes to the triangles
    // of block (b mod DEAL_STRIPES) × dealt_rows + b / DEAL_STRIPES, and every range of blocks
    // takes its share of each stripe of the mesh; the last blocks keep their place.
    uint group = gl_WorkGroupID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x;
    uint block = group / DEAL_BLOCK;
    if (block < DEAL_STRIPES * constants.dealt_rows) {
        block = (block % DEAL_STRIPES) * constants.dealt_rows + block / DEAL_STRIPES;
    }
    uint t = (block * DEAL_BLOCK + group % DEAL_BLOCK) * gl_WorkGroupSize.x + gl_LocalInvocationIndex;
    if (t >= constants.triangles) {
        return;
    }
    float third_z;
    vec3 normal = mesh_normal_by_words(range_draw, t, third_z);
#ifdef PINHOLE
    // One view, or two (VIEW_COUNT 2: a witness's band beside the reference view). A solid's
    // triangle turned clearly away from a view's centre needs no more than its normal and a
    // corner there (turned_away); the others are culled, where at all, by the winding of their
    // snapped corners (cover_here).
    vec3 first_corner = mesh_corner_by_words(range_draw, t, 0u);
    bool in_range = !turned_away(constants.cull, range_draw, normal, first_corner);
    bool in_shadow = VIEW_COUNT > 1u && !turned_away(constants.second_cull, shadow_draw, normal, first_corner);
    if (!in_range && !in_shadow) {
        return;
    }
    MeshTriangle m = read_triangle(range_draw, t, normal, third_z);
    if (in_range) {
        cover_pinhole(member, 0u, range_draw, constants, t, to_view_triangle(range_draw, m));
    }
    if (in_shadow) {
        cover_pinhole(member, 1u, shadow_draw, constants, t, to_view_triangle(shadow_draw, m));
    }
#else
    // The normal first: a triangle culled in every view needs no corners.
    bool in_range = !culled(constants.cull, range_draw, normal);
    bool in_shadow = VIEW_COUNT > 1u && !culled(constants.cull, shadow_draw, normal);
    if (!in_range && !in_shadow) {
        return;
    }
    MeshTriangle m = read_triangle(range_draw, t, normal, third_z);
    if (in_range) {
        cover(member, 0u, range_draw, constants, t, m);
    }
    if (in_shadow) {
        cover(member, 1u, shadow_draw, constants, t, m);
    }
#endif
}
#endif
