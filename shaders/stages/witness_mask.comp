#version 460
// The shadow test of a rig on the GPU (src/render/pinhole/; docs/sensors-and-rigs.md): one
// invocation per pixel of a region of a pinhole reference view. Its point p = Z · ray is seen by
// a witness when p's surface faces the witness, p lies in front of it (a pinhole witness) and
// on its image, and then, by the test this pipeline runs:
// - the label tests: the witness's image carries p's label at p's projection (the paper's
//   test, Fig. 4): the nearest pixel, or any of the four around it (TEST_LABEL_SQUARE);
// - the depth test: no surface lies between p and the witness, found by walking over the
//   surfaces the witness's image saw around p's projection (occluder_walk.glsl).
// A pinhole witness's image is drawn in projection, a directional witness's orthographically
// along its direction. A point any witness does not see is shadowed; bit k of its `lost_by`
// word says witness k did not see it.
// The depth test runs in two passes: this one decides what it can without a walk over the
// surface and lists the pixels it leaves to walk from toward some witness; the second
// (WALKS_FROM_LIST, the variant defining it) decides each of them again toward every witness
// and takes the walks (src/render/stages/walk_list.rs says why).
//
// FROM_WORDS: the variants for a job of one draw that the compute rasterizer drew
// (src/render/raster/compute/rig.rs), as the scanner's mask reads its views
// (shadow_mask.comp): they read every view's visibility words in place of the attachments no
// resolve pass wrote, and the first pass resolves the reference view itself, writing its
// attachments as raster_resolve.comp would and testing what it wrote. A software rasterizer
// pays for each pass over the pixels and for every value stored and loaded again.
#include "../raster/draw.glsl"
#include "../raster/visibility_word.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

#ifdef FROM_WORDS
#define REFERENCE_ACCESS writeonly
#else
#define REFERENCE_ACCESS readonly
#endif
layout(set = 0, binding = 0, r32ui) uniform REFERENCE_ACCESS uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform REFERENCE_ACCESS image2D range_z;
layout(set = 0, binding = 2, r32f) uniform REFERENCE_ACCESS image2D range_dz_dx;
layout(set = 0, binding = 3, r32f) uniform REFERENCE_ACCESS image2D range_dz_dy;
// The witnesses' images, one band of rows each (label, draw index, triangle): the pinhole
// witnesses' and the directional witnesses'.
layout(set = 0, binding = 4, rgba32ui) uniform readonly uimage2D witness_visibility;
layout(set = 0, binding = 5, rgba32ui) uniform readonly uimage2D directional_visibility;
layout(set = 0, binding = 6, std430) writeonly buffer Masked { uint masked_label[]; };
// The second pass of the depth test sets bits the first left clear, atomically.
#ifdef WALKS_FROM_LIST
#define LOST_BY_ACCESS
#else
#define LOST_BY_ACCESS writeonly
#endif
layout(set = 0, binding = 7, std430) LOST_BY_ACCESS buffer LostBy { uint lost_by[]; };
// The depth test: the walk list, bindings 8 and 9 (pixels left to walk from toward some
// witness).
#define WALK_ARGS_BINDING 8
#define WALK_PIXELS_BINDING 9
#define WALK_MAX_GROUPS_ID 6
#include "walk_list.glsl"
// FROM_WORDS: the reference view's draw table and visibility words (visibility_word.glsl),
// and the words of the pinhole witnesses' attachment and of the directional witnesses', rows
// as their images' (src/render/raster/compute/rig.rs). (Other buffers are bound there
// otherwise, never read.)
layout(set = 0, binding = 10, std430) readonly buffer ReferenceDraws { DrawData reference_draws[]; };
layout(set = 0, binding = 11, std430) readonly buffer ReferenceWords { uint reference_words[]; };
layout(set = 0, binding = 12, std430) readonly buffer PinholeWitnessWords { uint pinhole_witness_words[]; };
layout(set = 0, binding = 13, std430) readonly buffer DirectionalWitnessWords { uint directional_witness_words[]; };

// One witness as the mask sees it (src/render/pinhole/witness_mask.rs, WitnessConstants).
struct WitnessData {
    vec4 from_reference[3]; // rows of witness-from-reference, composed in f64 on the host
    vec4 centre;            // a pinhole witness's centre (w = 1), or the unit direction toward a
                            // directional one (w = 0), in the reference frame
    vec4 grid;              // its image's grid (view.glsl): a pinhole witness's fx, fy, cx, cy
                            // (`columns` applied), a directional one's x0, y0, dx, dy
    uvec4 band;             // its image's width, height, first row, and attachment (0: the
                            // pinhole witnesses', 1: the directional witnesses')
    uvec4 drawn;            // the pixels of its image the job drew (first column, first row,
                            // width, height; rows from the band's first): occluder_holds
    uvec2 draws;            // the depth test: device address of its draw table (WitnessDraws),
                            // each draw in its frame at the draw index its image holds
};
// The job's witnesses, in file order, written into the slot's table before the test
// (src/render/pinhole/witness_mask.rs, WitnessTable): a software rasterizer reads a storage
// buffer's value at a fraction of the cost of one at a device address.
layout(set = 0, binding = 14, std430) readonly buffer WitnessTable { WitnessData witness_table[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer WitnessDraws {
    DrawData draws[];
};

layout(push_constant, std430) uniform WitnessMask {
    vec4 intrinsics;        // fx, fy, cx, cy of the reference view
    uvec4 region;           // the pixels to test: first column, first row, width, height
    uvec4 strides;          // FROM_WORDS: pixels a row of the words of the reference view, of
                            // the pinhole witnesses' attachment and of the directional
                            // witnesses'
    uint width;             // the reference view's width
    uint witness_count;     // the witnesses in WitnessTable
    float facing_tolerance; // the least cosine at which a surface faces a witness (src/exact/)
    float bias_per_depth;   // the depth test's constant bias, model units per unit of depth
    float bias_relative;    // the depth test's f32 rounding allowance, relative
    float hull_tolerance;   // how far in front of a hull face a vertex may lie
    uvec2 hull_faces;       // FROM_WORDS, the depth test: device address of the draw's mesh's
                            // hull-face bits (0: it has none)
} m;

// The test, by the codes of ShadowTest (src/shadow.rs).
layout(constant_id = 0) const uint TEST = 0xffffffffu;
layout(constant_id = 1) const uint TEST_LABEL_SQUARE = 0xffffffffu;
layout(constant_id = 2) const uint TEST_DEPTH = 0xffffffffu;
// How an edge link packs the neighbour (src/mesh/adjacency.rs, given by the host).
layout(constant_id = 3) const uint LINK_INDEX_SHIFT = 0u;
layout(constant_id = 4) const uint LINK_SAME_WAY = 0u;
layout(constant_id = 5) const uint LINK_EDGE_MASK = 0u;

// The witness being tested, whose image and draw table the depth test's walk reads.
WitnessData witness;

#ifdef FROM_WORDS
// The job's one draw in the reference view, read in main: its labels are the draw's in
// every view.
DrawData reference_draw;
#endif

// Whether the job drew pixel q of the witness's image: the depth test reads no other (beyond
// it, an attachment the jobs of a batch share holds an earlier job's triangles), nor any test
// from the words (whose triangles there may be another mesh's).
bool occluder_holds(ivec2 q) {
    ivec4 drawn = ivec4(witness.drawn);
    return all(greaterThanEqual(q, drawn.xy)) && all(lessThan(q, drawn.xy + drawn.zw));
}

// What the witness's image holds at pixel q (within it): label, draw index, triangle. From
// the words (the job's one draw, index 0), the label is read only for the label tests; the
// depth test needs only whether a triangle was seen there, and gets 1.
uvec4 occluder_seen(ivec2 q) {
    ivec2 at = q + ivec2(0, witness.band.z);
#ifdef FROM_WORDS
    if (!occluder_holds(q)) {
        return uvec4(0u);
    }
    uint triangle = witness.band.w == 0u ? pinhole_witness_words[2u * word_index(m.strides.y, at)]
                                         : directional_witness_words[2u * word_index(m.strides.z, at)];
    if (triangle == EMPTY_HALF) {
        return uvec4(0u);
    }
    return uvec4(TEST == TEST_DEPTH ? 1u : triangle_label(reference_draw, triangle), 0u, triangle, 0u);
#else
    return witness.band.w == 0u ? imageLoad(witness_visibility, at) : imageLoad(directional_visibility, at);
#endif
}

// Whether pixel q lies on the witness's image.
bool on_image(ivec2 q) {
    return all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(witness.band.xy)));
}

DrawData occluder_draw(uint draw) {
    return WitnessDraws(witness.draws).draws[draw];
}

vec3 view_corner(DrawData d, uint t, uint k) {
    return triangle_corner(d, t, k);
}

vec3 view_normal(DrawData d, uint t) {
    return triangle_normal(d, t);
}

#include "occluder_walk.glsl"

// Whether pixel q of the witness's image exists and carries `label`.
bool carries(ivec2 q, uint label) {
    return on_image(q) && occluder_seen(q).r == label;
}

// The rows of witness-from-reference applied to v, translated (w = 1) or not (w = 0).
vec3 to_witness(vec3 v, float w) {
    precise vec3 q = vec3(dot(witness.from_reference[0].xyz, v) + w * witness.from_reference[0].w,
                          dot(witness.from_reference[1].xyz, v) + w * witness.from_reference[1].w,
                          dot(witness.from_reference[2].xyz, v) + w * witness.from_reference[2].w);
    return q;
}

// What the test decided of a point toward the witness without walking over the surface:
// seen, not seen, or a walk to take (occluded, with what it takes).
const uint SEEN = 0u;
const uint UNSEEN = 1u;
const uint TO_WALK = 2u;
struct Walk {
    ivec2 s;
    vec3 q;
    vec3 own;
    float scale;
    float bias;
    bool central;
};

// A reference pixel's point p (reference frame) and its label (0: no surface there), and for
// the tests toward the witnesses: its surface's normal `lit`, on the side the reference sees;
// how many times f32 rounding of p's coordinates p errs by (`steepness`, the depth test); and
// the triangle p lies on where it lies on its mesh's convex hull, in a job of that mesh alone
// (else NO_NEIGHBOUR).
struct ReferencePoint {
    uint label;
    vec3 p;
    vec3 lit;
    float steepness;
    uint hull_face;
};

// Whether the witness sees the point, or a walk is to tell. Its arithmetic is unfused
// (`precise`) wherever it decides: the depth test's second pass works it out again, in a
// shader of its own, which a GPU could otherwise fuse differently.
uint decided(ReferencePoint r, out Walk walk) {
    walk = Walk(ivec2(0), vec3(0.0), vec3(0.0), 0.0, 0.0, false);
    vec3 p = r.p, lit = r.lit;
    bool directional = witness.centre.w == 0.0;
    precise vec3 toward = directional ? witness.centre.xyz : witness.centre.xyz - p;
    precise float facing = dot(lit, toward);
    precise float lengths = length(lit) * length(toward);
    if (!(facing > m.facing_tolerance * lengths)) {
        return UNSEEN;
    }
    vec3 q = to_witness(p, 1.0);
    // Parallel rays come from beyond everything; a pinhole witness sees what lies in front.
    if (!(directional || q.z > 0.0)) {
        return UNSEEN;
    }
    precise vec2 uv = directional ? orthographic_pixel(witness.grid, q.xy) : pinhole_pixel(witness.grid, q);
    // Off the image by more than a pixel (checked in floats: a far projection does not fit an
    // int, whose conversion is then undefined).
    if (!(all(greaterThanEqual(uv, vec2(-1.0))) && all(lessThanEqual(uv, vec2(witness.band.xy))))) {
        return UNSEEN;
    }
    if (TEST == TEST_LABEL_SQUARE) {
        ivec2 corner = ivec2(floor(uv));
        return carries(corner, r.label) || carries(corner + ivec2(1, 0), r.label)
            || carries(corner + ivec2(0, 1), r.label) || carries(corner + ivec2(1, 1), r.label)
            ? SEEN : UNSEEN;
    }
    // The nearest pixel; its square around its centre is the image's (Intrinsics::contains).
    ivec2 s = ivec2(floor(uv + 0.5));
    if (TEST != TEST_DEPTH) {
        return carries(s, r.label) ? SEEN : UNSEEN;
    }
    // The depth test. A pinhole witness sees only its image's squares; a directional
    // witness's image covers every point the reference view can see (directional.rs), and a
    // point outside it can only come from rounding at its border.
    if (!on_image(s)) {
        return directional ? SEEN : UNSEEN;
    }
    float steepness = r.steepness;
    // The normal came from an f32 gradient, whose error grows with the square of steepness:
    // as the scanner's mask does, a surface turned from the witness by less than that counts
    // as turned away (which also bounds its slope along the witness's rays, `own`).
    precise float facing_bound = m.bias_relative * steepness * steepness;
    if (!(facing > facing_bound * lengths)) {
        return UNSEEN;
    }
    float scale = max(max(max(abs(q.x), abs(q.y)), abs(q.z)), max(max(abs(p.x), abs(p.y)), abs(p.z)));
    // p came from a plane evaluated in f32, which errs in proportion to its steepness.
    precise float bias = m.bias_per_depth * p.z + m.bias_relative * scale * (1.0 + steepness);
    // p's own plane, and the rays toward the witness, in its frame.
    precise vec3 rays = directional ? vec3(0.0, 0.0, 1.0) : -q / length(q);
    vec3 own = ray_slope(to_witness(lit, 0.0), rays);
    // A point on a hull face, in views of its model alone (occluder_walk.glsl), whose front
    // turns toward the witness (it faces the witness, and `lit` is its front).
    if (r.hull_face != NO_NEIGHBOUR && hull_face_clear(facing, lengths, m.bias_per_depth * p.z, m.hull_tolerance)) {
        return SEEN;
    }
    walk = Walk(s, q, own, scale, bias, !directional);
    return TO_WALK;
}

// The point a reference pixel saw, from what the reference view holds there (`range`; a
// label of 0 and nothing else where it saw none), and where the job is of one draw the
// compute rasterizer drew (FROM_WORDS), the triangle its words hold (`t`).
ReferencePoint point_of(ivec2 pixel, RangePixel range, uint t) {
    ReferencePoint r = ReferencePoint(range.label, vec3(0.0), vec3(0.0), 0.0, NO_NEIGHBOUR);
    if (r.label != 0u) {
        precise vec3 p = view_point(VIEW_PINHOLE, m.intrinsics, vec2(pixel), range.z);
        vec3 n = vec3(-range.gradient, 1.0);
        // The hull faces' shortcut (decided) trusts `lit`, which a gradient clamped at ±1e30 (a
        // face along the view's rays: pinhole_range_pixel) no longer points along.
        bool normal_kept = max(abs(n.x), abs(n.y)) < 1e30;
        // Scaled to components of at most 1: a face along the view's axis has a gradient of
        // up to 1e30, whose square would overflow.
        n /= max(1.0, max(abs(n.x), abs(n.y)));
        // The side of the surface the reference view sees: the one facing back along its ray.
        precise float along_ray = dot(n, p);
        vec3 lit = along_ray > 0.0 ? -n : n;
        // How steeply the plane lies along the pixel's ray: Z, from the plane in f32, errs in
        // proportion (∞ for a plane along the ray, which then hides nothing behind it).
        vec3 ray = pinhole_ray(m.intrinsics, vec2(pixel));
        precise float steepness = l1_length(n) * l1_length(ray) / abs(dot(n, ray));
        uint hull_face = NO_NEIGHBOUR;
#ifdef FROM_WORDS
        // Where the reference view sees the face's front: its stored (outward) normal points
        // along `lit`, which is parallel to it (from its plane's gradient), so that their
        // product is far from 0 and any frame's rounding gives its sign.
        if (TEST == TEST_DEPTH && m.hull_faces != uvec2(0u) && normal_kept && on_hull(m.hull_faces, t)
            && dot(triangle_normal(reference_draw, t), lit) > 0.0) {
            hull_face = t;
        }
#endif
        r = ReferencePoint(r.label, p, lit, steepness, hull_face);
    }
    return r;
}

#ifdef FROM_WORDS
// The triangle the reference view's words hold at a pixel (EMPTY_HALF: none).
uint reference_triangle(ivec2 pixel) {
    return reference_words[2u * word_index(m.strides.x, pixel)];
}

// What the reference view holds at a pixel, worked out from its words as
// raster_resolve.comp's PINHOLE variant works it out (zeros where no triangle covers it).
RangePixel reference_range(ivec2 pixel, uint t) {
    return t == EMPTY_HALF ? RangePixel(0u, 0.0, vec2(0.0)) : pinhole_range_pixel(reference_draw, t, vec2(pixel));
}

// The point a reference pixel saw, from the words, and (`store`) the reference view's
// attachments written there.
ReferencePoint reference_point(ivec2 pixel, bool store) {
    uint t = reference_triangle(pixel);
    RangePixel range = reference_range(pixel, t);
    if (store) {
        imageStore(range_label, pixel, uvec4(range.label));
        imageStore(range_z, pixel, vec4(range.z));
        imageStore(range_dz_dx, pixel, vec4(range.gradient.x));
        imageStore(range_dz_dy, pixel, vec4(range.gradient.y));
    }
    return point_of(pixel, range, t);
}
#else
// The point a reference pixel saw, from the reference view's attachments.
ReferencePoint reference_point(ivec2 pixel, bool store) {
    uint label = imageLoad(range_label, pixel).r;
    RangePixel range = RangePixel(label, 0.0, vec2(0.0));
    if (label != 0u) {
        range.z = imageLoad(range_z, pixel).r;
        range.gradient = vec2(imageLoad(range_dz_dx, pixel).r, imageLoad(range_dz_dy, pixel).r);
    }
    return point_of(pixel, range, NO_NEIGHBOUR);
}
#endif

#ifdef WALKS_FROM_LIST
// The depth test's second pass: each invocation decides listed pixels again toward every
// witness, walks toward those the first pass left to a walk, and sets the bits of those a
// surface hides the point from (the first pass wrote the others' bits and the labels).
void main() {
#ifdef FROM_WORDS
    reference_draw = reference_draws[0];
#endif
    for (uint i = first_listed(); i < walk_args.w; i += listed_stride()) {
        uint index = walk_pixels[i];
        ReferencePoint r = reference_point(ivec2(index % m.width, index / m.width), false);
        uint lost = 0u;
        for (uint k = 0u; k < m.witness_count; k++) {
            witness = witness_table[k];
            Walk walk;
            if (decided(r, walk) == TO_WALK && occluded(walk.s, walk.q, walk.own, walk.scale, walk.bias, walk.central)) {
                lost |= 1u << k;
            }
        }
        if (lost != 0u) {
            atomicOr(lost_by[index], lost);
            masked_label[index] = 0u;
        }
    }
}
#else
void main() {
#ifdef FROM_WORDS
    // Read while every invocation is still active: a software rasterizer then reads it once
    // for all of them instead of gathering it per invocation.
    reference_draw = reference_draws[0];
#endif
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, m.region.zw))) {
        return;
    }
    ivec2 pixel = ivec2(m.region.xy + gl_GlobalInvocationID.xy);
    uint index = uint(pixel.y) * m.width + uint(pixel.x);
    ReferencePoint r = reference_point(pixel, true);
    uint lost = 0u;
    bool to_walk = false;
    if (r.label != 0u) {
        for (uint k = 0u; k < m.witness_count; k++) {
            witness = witness_table[k];
            Walk walk;
            uint verdict = decided(r, walk);
            if (verdict == UNSEEN) {
                lost |= 1u << k;
            } else if (verdict == TO_WALK) {
                to_walk = true;
            }
        }
    }
    lost_by[index] = lost;
    masked_label[index] = lost == 0u ? r.label : 0u;
    // The depth test alone lists (the label tests' pipelines then hold no list's atomics,
    // which a software rasterizer would run through).
    if (TEST == TEST_DEPTH && to_walk) {
        list_walk(index);
    }
}
#endif
