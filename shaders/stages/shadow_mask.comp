#version 460
// Triangulation shadow test (paper Fig. 4; docs/design.md "The shadow test"; src/shadow.rs).
// One invocation per range pixel: move its point into the shadow frame with R_y(-theta),
// find the nearest shadow-buffer pixel and keep or drop the label.
//
// FROM_WORDS: the variant for views the compute rasterizer rendered (src/render/stages/shadow_mask.rs).
// It reads the shadow view from its visibility words, and resolves the range view itself: it
// reads the range view's words, writes the range view's attachments as the resolve pass would
// (raster_resolve.comp) and tests the values it wrote, so the range view takes no resolve pass
// of its own. Its depth test runs in two passes: this one decides every pixel it can without a
// walk over the surface and lists the others; the second (WALKS_FROM_LIST, the variant
// defining it too) walks from the listed pixels only. A software rasterizer runs invocations
// in lockstep and runs every branch's code even where no invocation takes it, so a pass that
// walked in place would pay for the walk's code at every pixel a shortcut decided.
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
// FROM_WORDS, depth test: the walk list, bindings 10 and 11.
#define WALK_ARGS_BINDING 10
#define WALK_PIXELS_BINDING 11
#define WALK_MAX_GROUPS_ID 7
#include "walk_list.glsl"

layout(push_constant, std430) uniform Mask {
    vec4 range_grid;    // x0, y0, dx, dy of the range view
    vec4 shadow_grid;   // x0, y0, dx, dy of the shadow view
    ivec4 sizes;        // range width, height; shadow width, height
    ivec4 region;       // the range pixels to mask: first column, first row, width, height
    float cos_theta;
    float sin_theta;
    float bias_pitch;   // constant bias, model units
    float bias_relative;// f32 rounding allowance, relative
    uvec2 hull_faces;   // FROM_WORDS: device address of the draw's mesh's hull-face bits (0: none)
    uint words_draw;    // FROM_WORDS: the one draw both views rendered
    uint shadow_stride; // FROM_WORDS: pixels per row of the shadow view's words
    uint range_stride;  // FROM_WORDS: pixels per row of the range view's words
    float hull_tolerance; // FROM_WORDS: how far in front of a hull face a vertex may lie
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

// Whether shadow pixel q lies in the shadow view's grid.
bool in_shadow_grid(ivec2 q) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, m.sizes.zw));
}

// Whether shadow pixel q exists and carries `label`.
bool shadow_label_is(ivec2 q, uint label) {
    return in_shadow_grid(q) && shadow_seen(q).r == label;
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

// What the depth test's walk (occluder_walk.glsl) reads of the shadow view.
uvec4 occluder_seen(ivec2 q) {
    return shadow_seen(q);
}

bool occluder_holds(ivec2 q) {
    return in_shadow_grid(q);
}

DrawData occluder_draw(uint draw) {
#ifdef FROM_WORDS
    // The view's one draw, read in main.
    return shadow_draw;
#else
    return draws[draw];
#endif
}

#include "occluder_walk.glsl"

// What the shadow test decided of a pixel without walking over the surface: lit, shadowed,
// or a walk to take (occluded, with what it takes).
const uint LIT = 0u;
const uint SHADOWED = 1u;
const uint TO_WALK = 2u;
struct Walk {
    ivec2 s;
    vec3 p;
    vec3 own;
    float scale;
    float bias;
};

// `on_hull_front`: p lies on a face of its model's convex hull, seen from the face's front
// (range_from_words), in views that hold that model alone.
uint decided(ivec2 pixel, RangePixel range, bool on_hull_front, out Walk walk) {
    walk = Walk(ivec2(0), vec3(0.0), vec3(0.0), 0.0, 0.0);
    uint label = range.label;
    precise vec2 xy = orthographic_centre(m.range_grid, vec2(pixel));
    float z = range.z;
    // p' = R_y(-theta) p
    precise vec3 ps = vec3(m.cos_theta * xy.x - m.sin_theta * z, xy.y, m.sin_theta * xy.x + m.cos_theta * z);
    precise vec2 projected = orthographic_pixel(m.shadow_grid, ps.xy);
    ivec2 s = ivec2(floor(projected + 0.5));
    // The shadow grid covers every point the range view can see (sensor.rs); a point
    // outside it can only come from rounding at its border and is treated as lit.
    bool in_grid = in_shadow_grid(s);
    if (TEST == TEST_LABEL) {
        return in_grid && shadow_seen(s).r != label ? SHADOWED : LIT;
    }
    if (TEST == TEST_LABEL_SQUARE) {
        // The four shadow pixels whose centres surround p'; outside the grid it is lit, as above.
        ivec2 corner = ivec2(floor(projected));
        bool outside = any(lessThan(corner, ivec2(-1))) || any(greaterThanEqual(corner, m.sizes.zw));
        return !outside && !shadow_label_is(corner, label) && !shadow_label_is(corner + ivec2(1, 0), label)
            && !shadow_label_is(corner + ivec2(0, 1), label) && !shadow_label_is(corner + ivec2(1, 1), label)
            ? SHADOWED : LIT;
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
        return SHADOWED;
    }
    // The same plane in the shadow frame: n = R_y(−θ)(−∂z/∂x, −∂z/∂y, 1), whose z is `facing`.
    precise vec2 own = vec2(m.cos_theta * gradient.x + m.sin_theta, gradient.y) / facing;
    if (!in_grid) {
        return LIT;
    }
    // A point on a hull face, in views of its model alone (occluder_walk.glsl); n's length
    // times the camera direction's (1).
    if (on_hull_front && hull_face_clear(facing, length(vec3(gradient, 1.0)), m.bias_pitch, m.hull_tolerance)) {
        return LIT;
    }
    // Then whatever lies between the point and the camera.
    walk = Walk(s, ps, vec3(own, 0.0), scale, bias);
    return TO_WALK;
}

// The whole test of a pixel, walking in place where it takes a walk (the depth test: the
// label tests' pipelines then hold no walk, which a software rasterizer would run through).
bool shadowed(ivec2 pixel, RangePixel range, bool on_hull_front) {
    Walk walk;
    uint verdict = decided(pixel, range, on_hull_front, walk);
    if (!LABEL_TEST && verdict == TO_WALK) {
        return occluded(walk.s, walk.p, walk.own, walk.scale, walk.bias, false);
    }
    return verdict == SHADOWED;
}

#ifdef FROM_WORDS
// The range view at a pixel from its words (a view of one draw, whose words hold z keys:
// visibility_word.glsl); zeros where no triangle covers it. The gradient is read only where
// it is written or the depth test needs it. For the depth test, `on_hull_front` says whether
// the pixel's triangle lies on its mesh's convex hull and the view sees its front (its normal
// toward the view, +z).
RangePixel range_from_words(DrawData d, ivec2 pixel, out bool on_hull_front) {
    uint at = 2u * word_index(m.range_stride, pixel);
    uint t = range_words[at];
    RangePixel range = RangePixel(0u, 0.0, vec2(0.0));
    on_hull_front = false;
    if (t != EMPTY_HALF) {
        bool with_gradient = WRITE_LABEL_AND_GRADIENT != 0u || !LABEL_TEST;
        float normal_z;
        range = range_pixel_at_z(d, t, z_of_key(range_words[at + 1u]), with_gradient, normal_z);
        on_hull_front = !LABEL_TEST && normal_z > 0.0 && m.hull_faces != uvec2(0u) && on_hull(m.hull_faces, t);
    }
    return range;
}

// range_from_words, written to the range view's attachments as raster_resolve.comp writes
// them, its label and gradient only where a later pass reads them: the stores cost time on a
// software rasterizer.
RangePixel resolve_range(DrawData d, ivec2 pixel, out bool on_hull_front) {
    RangePixel range = range_from_words(d, pixel, on_hull_front);
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

#ifdef WALKS_FROM_LIST
// The second pass of the depth test: each invocation walks from listed pixels, whose labels
// the first pass wrote, and drops the label where a surface hides the point.
void walk_from_list(DrawData range_draw) {
    for (uint i = first_listed(); i < walk_args.w; i += listed_stride()) {
        uint index = walk_pixels[i];
        ivec2 pixel = ivec2(index % uint(m.sizes.x), index / uint(m.sizes.x));
        bool on_hull_front;
        RangePixel range = range_from_words(range_draw, pixel, on_hull_front);
        Walk walk;
        if (decided(pixel, range, on_hull_front, walk) == TO_WALK
            && occluded(walk.s, walk.p, walk.own, walk.scale, walk.bias, false)) {
            masked_label[index] = 0u;
        }
    }
}

void main() {
    DrawData range_draw = range_draws[m.words_draw];
    shadow_draw = draws[m.words_draw];
    walk_from_list(range_draw);
}
#else
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
    bool on_hull_front;
    RangePixel range = resolve_range(range_draw, pixel, on_hull_front);
#else
    RangePixel range = read_range(pixel);
    bool on_hull_front = false;
#endif
    uint index = uint(pixel.y) * uint(m.sizes.x) + uint(pixel.x);
#ifdef FROM_WORDS
    if (!LABEL_TEST) {
        // The depth test's first pass: a listed pixel keeps its label until the second finds
        // it hidden.
        Walk walk;
        uint verdict = range.label == 0u ? LIT : decided(pixel, range, on_hull_front, walk);
        masked_label[index] = verdict == SHADOWED ? 0u : range.label;
        if (verdict == TO_WALK) {
            list_walk(index);
        }
        return;
    }
#endif
    masked_label[index] = (range.label != 0u && shadowed(pixel, range, on_hull_front)) ? 0u : range.label;
}
#endif
