#version 460
// Triangulation shadow test (paper Fig. 4; docs/design.md "The shadow test"; src/shadow.rs).
// One invocation per range pixel: move its point into the shadow frame with R_y(-theta),
// find the nearest shadow-buffer pixel and keep or drop the label.
//
// FROM_WORDS: the variant for views the compute rasterizer rendered (src/render/stages/shadow_mask.rs).
// It reads the shadow view from its visibility words, and resolves the range view itself: it
// reads the range view's words, writes the range view's attachments as the resolve pass would
// (raster_resolve.comp) and tests the values it wrote, so the range view takes no resolve pass
// of its own.
#include "../raster/draw.glsl"
#include "../raster/visibility_word.glsl"
#ifdef FROM_WORDS
#include "../raster/triangle_words.glsl"
#endif

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef FROM_WORDS
#define RANGE_ACCESS writeonly
#else
#define RANGE_ACCESS readonly
#endif
layout(set = 0, binding = 0, r32ui) uniform RANGE_ACCESS uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform RANGE_ACCESS image2D range_z;
layout(set = 0, binding = 2, r32f) uniform RANGE_ACCESS image2D range_dz_dx;
layout(set = 0, binding = 3, r32f) uniform RANGE_ACCESS image2D range_dz_dy;
// Per shadow pixel: label, draw index, triangle (src/render/targets.rs).
layout(set = 0, binding = 4, rgba32ui) uniform readonly uimage2D shadow_visibility;
layout(set = 0, binding = 5, std430) writeonly buffer Masked { uint masked_label[]; };
// The shadow view's draws, indexed by the draw index the shadow view stored per pixel.
layout(set = 0, binding = 6, std430) readonly buffer DrawTable { DrawData draws[]; };
// FROM_WORDS: the compute rasterizer's visibility words (visibility_word.glsl) of the shadow
// view, in place of the visibility image it never writes; the range view's draw table; and
// the range view's words. (Other buffers are bound there otherwise, never read.)
layout(set = 0, binding = 7, std430) readonly buffer ShadowWords { uint shadow_words[]; };
layout(set = 0, binding = 8, std430) readonly buffer RangeDrawTable { DrawData range_draws[]; };
layout(set = 0, binding = 9, std430) readonly buffer RangeWords { uint range_words[]; };

layout(push_constant, std430) uniform Mask {
    vec4 range_grid;    // x0, y0, dx, dy of the range view
    vec4 shadow_grid;   // x0, y0, dx, dy of the shadow view
    ivec4 sizes;        // range width, height; shadow width, height
    ivec4 region;       // the range pixels to mask: first column, first row, width, height
    float cos_theta;
    float sin_theta;
    float bias_pitch;   // constant bias, model units
    float bias_relative;// f32 rounding allowance, relative
    uint words_draw;    // FROM_WORDS: the one draw both views rendered
    uint shadow_stride; // FROM_WORDS: pixels per row of the shadow view's words
    uint range_stride;  // FROM_WORDS: pixels per row of the range view's words
} m;

// The test this pipeline runs, and the codes of the label tests, nearest pixel and 2x2; any
// other is the depth test. All given by the host (ShadowTest, src/shadow.rs): one pipeline a
// test, so that only its code is compiled (src/render/stages/shadow_mask.rs).
layout(constant_id = 0) const uint TEST = 0xffffffffu;
layout(constant_id = 1) const uint TEST_LABEL = 0xffffffffu;
layout(constant_id = 2) const uint TEST_LABEL_SQUARE = 0xffffffffu;
// Whether TEST is a label test, which reads labels only; else the depth test.
const bool LABEL_TEST = TEST == TEST_LABEL || TEST == TEST_LABEL_SQUARE;
// How an edge link packs the neighbour (src/mesh/adjacency.rs, given by the host).
layout(constant_id = 3) const uint LINK_INDEX_SHIFT = 0u;
layout(constant_id = 4) const uint LINK_SAME_WAY = 0u;
layout(constant_id = 5) const uint LINK_EDGE_MASK = 0u;
// FROM_WORDS: 0 where no pass after the mask reads the range view's label or gradient (a
// score pass of shadowed labels, without effects), which are then not written (MaskVariant,
// src/render/stages/shadow_mask.rs). Its z always is.
layout(constant_id = 6) const uint WRITE_LABEL_AND_GRADIENT = 1u;

#ifdef FROM_WORDS
// The shadow view's one draw, read in main with the range view's.
DrawData shadow_draw;
#endif

// What shadow pixel q (in the grid) saw: its label, draw index and triangle, or all zeros.
// From the words, the label is read only for the label tests; the depth test needs only
// whether a triangle was seen there, and gets 1.
uvec4 shadow_seen(ivec2 q) {
#ifdef FROM_WORDS
    uint at = 2u * word_index(m.shadow_stride, q);
    uint triangle = shadow_words[at];
    if (triangle == EMPTY_HALF) {
        return uvec4(0u);
    }
    uint label = LABEL_TEST ? triangle_label(shadow_draw, triangle) : 1u;
    return uvec4(label, m.words_draw, triangle, 0u);
#else
    return imageLoad(shadow_visibility, q);
#endif
}

// Whether shadow pixel q exists and carries `label`.
bool shadow_label_is(ivec2 q, uint label) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, m.sizes.zw)) && shadow_seen(q).r == label;
}

// The arithmetic of the shadow test is unfused (`precise`) wherever it decides a pixel, so
// that both variants of this shader, the graphics pipeline's and the compute rasterizer's,
// decide it alike on a GPU that would fuse multiply-adds differently in each.

// A triangle's corner and unit normal in the shadow view's frame: read in 64-bit words where
// the variant has them (FROM_WORDS), two loads a corner in place of three, for the depth
// test's walks, which read a corner at every step.
vec3 view_corner(DrawData d, uint t, uint k) {
#ifdef FROM_WORDS
    return to_view(d, mesh_corner_by_words(d, t, k));
#else
    return triangle_corner(d, t, k);
#endif
}

vec3 view_normal(DrawData d, uint t) {
#ifdef FROM_WORDS
    float third_z;
    return rotate_to_view(d, mesh_normal_by_words(d, t, third_z));
#else
    return triangle_normal(d, t);
#endif
}

// Twice the signed area of (a, b, q): which side of the line a → b the point q lies on.
float edge_function(vec2 a, vec2 b, vec2 q) {
    precise float area = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    return area;
}

// Distance from q to the segment a–b.
float segment_distance(vec2 q, vec2 a, vec2 b) {
    precise vec2 ab = b - a;
    precise float along = (q.x - a.x) * ab.x + (q.y - a.y) * ab.y;
    precise float t = clamp(along / max(ab.x * ab.x + ab.y * ab.y, 1e-30), 0.0, 1.0);
    precise vec2 off = q - (a + t * ab);
    return length(off);
}

float l1_length(vec2 v) {
    return abs(v.x) + abs(v.y);
}

// Steps a walk over a surface may take before giving up; see walk_to.
const int MAX_WALK_STEPS = 32;
// walk_to's answer when it gave up.
const uint WALK_TOO_LONG = 0xfffffffeu;

// Walks over the surface of draw d, from triangle t across edges toward the point p (shadow
// frame xy), each step leaving through the edge p lies farthest outside of. Returns the
// triangle whose projection holds p (edges included, within `tolerance`), NO_NEIGHBOUR where
// this layer of the surface ends before p — a border, or a fold, where the surface turns away
// from the camera (its silhouette) — or WALK_TOO_LONG.
uint walk_to(DrawData d, uint t, vec2 p, float tolerance) {
    // Written without arrays: a software rasterizer keeps dynamically indexed arrays in memory.
    // Each step's corners are the ones the step before had.
    vec2 a = view_corner(d, t, 0u).xy, b = view_corner(d, t, 1u).xy, c = view_corner(d, t, 2u).xy;
    for (int step = 0; step < MAX_WALK_STEPS; step++) {
        float winding = edge_function(a, b, c) >= 0.0 ? -1.0 : 1.0;
        // How far p lies outside each edge's line (a–b, b–c, c–a).
        vec3 outside = winding * vec3(edge_function(a, b, p), edge_function(b, c, p), edge_function(c, a, p))
                     / max(vec3(length(b - a), length(c - b), length(a - c)), vec3(1e-30));
        float farthest = max(outside.x, max(outside.y, outside.z));
        if (farthest <= tolerance) {
            return t;
        }
        uint exit = outside.x == farthest ? 0u : (outside.y == farthest ? 1u : 2u);
        uint link = triangle_link(d, t, exit);
        if (link == NO_NEIGHBOUR) {
            return NO_NEIGHBOUR;
        }
        // Across the edge the surface goes on only if the neighbour lies on the other side of
        // the edge's line; on the same side, it folds back.
        vec2 from = exit == 0u ? a : (exit == 1u ? b : c);
        vec2 to = exit == 0u ? b : (exit == 1u ? c : a);
        vec2 opposite = exit == 0u ? c : (exit == 1u ? a : b);
        // The neighbour shares from and to (the same points: vertices are matched by
        // position), so only its third corner is read.
        uint next = link >> LINK_INDEX_SHIFT, edge = link & LINK_EDGE_MASK;
        vec2 third = view_corner(d, next, (edge + 2u) % 3u).xy;
        if (edge_function(from, to, opposite) * edge_function(from, to, third) >= 0.0) {
            return NO_NEIGHBOUR;
        }
        // Its corners in order: its edge number `edge` runs from → to, or back.
        bool same_way = (link & LINK_SAME_WAY) != 0u;
        vec2 first = same_way ? from : to, second = same_way ? to : from;
        a = edge == 0u ? first : (edge == 1u ? third : second);
        b = edge == 0u ? second : (edge == 1u ? first : third);
        c = edge == 0u ? third : (edge == 1u ? second : first);
        t = next;
    }
    return WALK_TOO_LONG;
}

// How far the plane of triangle t of draw d lies above p' (shadow frame) on the camera ray
// through it (negative: below), and how much of that f32 rounding of the plane may account
// for, on top of the point's own `bias` (its error grows with the plane's steepness). A
// triangle seen edge-on has no plane over p': it rises by −∞.
vec2 plane_rise(DrawData d, uint t, vec3 ps, float scale, float bias, out vec2 gradient) {
    vec3 n = view_normal(d, t);
    if (n.z == 0.0) {
        gradient = vec2(0.0);
        return vec2(-1.0 / 0.0, bias);
    }
    vec3 a = view_corner(d, t, 0u);
    gradient = -n.xy / n.z;
    precise float rise = a.z + (gradient.x * (ps.x - a.x) + gradient.y * (ps.y - a.y)) - ps.z;
    precise float allowance = bias + m.bias_relative * scale * l1_length(gradient);
    return vec2(rise, allowance);
}

// Whether the surface seen at shadow pixel q hides p' (shadow frame): the triangle over p' on
// that surface — found by walking from the one the pixel saw, since triangles smaller than a
// pixel are missing from the shadow buffer — rises above p' by more than the bias (exact ray
// casting). `own` is the gradient of the surface through p', for the rare walk that gives up:
// then the plane of the pixel's triangle, extrapolated to p', must rise above it by more than
// a crease between them could explain (each edge bends a polyhedral surface's gradient by at
// most their difference, over at most p''s distance from the triangle).
// `lower` is the (draw, triangle) over p' last found not to hide it: walks from the pixels
// around p' mostly end on the same triangle, whose plane is then not evaluated again.
bool hides(DrawData d, uvec2 seen_at, vec3 ps, vec2 own, float scale, float bias, inout uvec2 lower) {
    uint seen = seen_at.y;
    uint t = walk_to(d, seen, ps.xy, m.bias_relative * scale);
    if (t == NO_NEIGHBOUR || uvec2(seen_at.x, t) == lower) {
        return false;
    }
    float beyond = 0.0; // how far the plane is extrapolated beyond its triangle
    if (t == WALK_TOO_LONG) {
        t = seen;
        vec2 a = view_corner(d, t, 0u).xy, b = view_corner(d, t, 1u).xy, c = view_corner(d, t, 2u).xy;
        beyond = min(segment_distance(ps.xy, a, b), min(segment_distance(ps.xy, b, c), segment_distance(ps.xy, c, a)));
    }
    vec2 gradient;
    vec2 rise = plane_rise(d, t, ps, scale, bias, gradient);
    precise float bound = rise.y + l1_length(gradient - own) * beyond;
    if (rise.x > bound) {
        return true;
    }
    if (beyond == 0.0) {
        lower = uvec2(seen_at.x, t);
    }
    return false;
}

bool shadowed(ivec2 pixel, RangePixel range) {
    uint label = range.label;
    precise vec2 xy = orthographic_centre(m.range_grid, vec2(pixel));
    float z = range.z;
    // p' = R_y(-theta) p
    precise vec3 ps = vec3(m.cos_theta * xy.x - m.sin_theta * z, xy.y, m.sin_theta * xy.x + m.cos_theta * z);
    precise vec2 projected = orthographic_pixel(m.shadow_grid, ps.xy);
    ivec2 s = ivec2(floor(projected + 0.5));
    // The shadow grid covers every point the range view can see (sensor.rs); a point
    // outside it can only come from rounding at its border and is treated as lit.
    bool in_grid = all(greaterThanEqual(s, ivec2(0))) && all(lessThan(s, m.sizes.zw));
    if (TEST == TEST_LABEL) {
        return in_grid && shadow_seen(s).r != label;
    }
    if (TEST == TEST_LABEL_SQUARE) {
        // The four shadow pixels whose centres surround p'; outside the grid it is lit, as above.
        ivec2 corner = ivec2(floor(projected));
        bool outside = any(lessThan(corner, ivec2(-1))) || any(greaterThanEqual(corner, m.sizes.zw));
        return !outside && !shadow_label_is(corner, label) && !shadow_label_is(corner + ivec2(1, 0), label)
            && !shadow_label_is(corner + ivec2(0, 1), label) && !shadow_label_is(corner + ivec2(1, 1), label);
    }
    // Depth mode. The camera sees the side of a surface the projector lights only when that
    // side faces it: n · d_cam > 0 with n = (−∂z/∂x, −∂z/∂y, 1), d_cam = (sin θ, 0, cos θ).
    vec2 gradient = range.gradient;
    precise float facing = m.cos_theta - m.sin_theta * gradient.x;
    float scale = max(max(abs(ps.x), abs(ps.y)), max(abs(ps.z), abs(z)));
    // z came from a plane evaluated in f32, which errs in proportion to its steepness.
    precise float steepness = 1.0 + l1_length(gradient);
    precise float bias = m.bias_pitch + m.bias_relative * scale * (1.0 + steepness);
    // The gradient came from an f32 normal; its error grows with the square of steepness.
    precise float facing_bound = m.bias_relative * steepness * steepness;
    if (facing <= facing_bound) {
        return true;
    }
    // The same plane in the shadow frame: n = R_y(−θ)(−∂z/∂x, −∂z/∂y, 1), whose z is `facing`.
    precise vec2 own = vec2(m.cos_theta * gradient.x + m.sin_theta, gradient.y) / facing;
    if (!in_grid) {
        return false;
    }
    // Then whatever lies between the point and the camera: the surfaces seen at the shadow
    // pixels around p', each once. Exact wherever the occluder over p' is seen at one of those
    // nine pixel centres, or is joined by its edges to a triangle that is.
    // Neighbours that saw the same triangle as the centre, or as the neighbour before them,
    // are not walked again (a large triangle fills the whole neighbourhood).
    uvec4 at_centre = shadow_seen(s);
    // Background carries no triangle: a pair no draw can have, so no neighbour is skipped for it.
    uvec2 centre = at_centre.x != 0u ? at_centre.yz : uvec2(0xffffffffu);
    uvec2 previous = centre;
    // The draw last read from the table, read again only for a pixel that saw another (a view
    // of one object has one): a software rasterizer gathers it word by word.
    uint loaded = 0xffffffffu;
    DrawData d;
    uvec2 lower = uvec2(0xffffffffu);
    // Each invocation goes through its nine on its own cursor, one walk a round: invocations
    // that run in lockstep then take as many rounds as the most walks any of them needs, not
    // one for each of the nine that any of them walks from.
    int k = 0;
    while (true) {
        // The next pixel to walk from: the centre first, then its eight neighbours in rows.
        uvec2 seen = uvec2(0xffffffffu);
        bool found = false;
        for (; k < 9 && !found; k++) {
            int i = k == 0 ? 4 : k - int(k <= 4);
            ivec2 q = s + ivec2(i % 3 - 1, i / 3 - 1);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, m.sizes.zw))) {
                continue;
            }
            uvec4 at = shadow_seen(q);
            seen = at.yz;
            found = at.x != 0u && (k == 0 || (seen != centre && seen != previous));
        }
        if (!found) {
            return false;
        }
        previous = seen;
        if (seen.x != loaded) {
            d = draws[seen.x];
            loaded = seen.x;
        }
        if (hides(d, seen, ps, own, scale, bias, lower)) {
            return true;
        }
    }
}

#ifdef FROM_WORDS
// The range view at a pixel from its words (a view of one draw, whose words hold z keys:
// visibility_word.glsl), written to its attachments as raster_resolve.comp writes them (zeros
// where no triangle covers it), its label and gradient only where a later pass reads them:
// the stores cost time on a software rasterizer.
// The gradient is read only where it is written or the depth test needs it.
RangePixel resolve_range(DrawData d, ivec2 pixel) {
    uint at = 2u * word_index(m.range_stride, pixel);
    uint t = range_words[at];
    RangePixel range = RangePixel(0u, 0.0, vec2(0.0));
    if (t != EMPTY_HALF) {
        bool with_gradient = WRITE_LABEL_AND_GRADIENT != 0u || !LABEL_TEST;
        range = range_pixel_at_z(d, t, z_of_key(range_words[at + 1u]), with_gradient);
    }
    imageStore(range_z, pixel, vec4(range.z));
    if (WRITE_LABEL_AND_GRADIENT != 0u) {
        imageStore(range_label, pixel, uvec4(range.label));
        imageStore(range_dz_dx, pixel, vec4(range.gradient.x));
        imageStore(range_dz_dy, pixel, vec4(range.gradient.y));
    }
    return range;
}
#else
// The range view at a pixel, from its attachments; the gradient only for the depth test.
RangePixel read_range(ivec2 pixel) {
    RangePixel range = RangePixel(imageLoad(range_label, pixel).r, imageLoad(range_z, pixel).r, vec2(0.0));
    if (!LABEL_TEST) {
        range.gradient = vec2(imageLoad(range_dz_dx, pixel).r, imageLoad(range_dz_dy, pixel).r);
    }
    return range;
}
#endif

void main() {
#ifdef FROM_WORDS
    // Read while every invocation is still active: a software rasterizer then reads them once
    // for all of them instead of gathering them per invocation.
    DrawData range_draw = range_draws[m.words_draw];
    shadow_draw = draws[m.words_draw];
#endif
    if (any(greaterThanEqual(ivec2(gl_GlobalInvocationID.xy), m.region.zw))) {
        return;
    }
    ivec2 pixel = m.region.xy + ivec2(gl_GlobalInvocationID.xy);
#ifdef FROM_WORDS
    RangePixel range = resolve_range(range_draw, pixel);
#else
    RangePixel range = read_range(pixel);
#endif
    uint index = uint(pixel.y) * uint(m.sizes.x) + uint(pixel.x);
    masked_label[index] = (range.label != 0u && shadowed(pixel, range)) ? 0u : range.label;
}
