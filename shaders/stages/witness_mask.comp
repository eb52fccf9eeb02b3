#version 460
// The label test of a rig on the GPU (src/render/pinhole/; docs/sensors-and-rigs.md): one
// invocation per pixel of a region of a pinhole reference view. Its point p = Z · ray is seen by
// a witness when p's surface faces the witness, p lies in front of it (a pinhole witness) and
// on its image, and the witness's label image carries p's label at p's projection (the paper's
// test, Fig. 4): the nearest pixel, or any of the four around it (TEST_LABEL_SQUARE). A pinhole
// witness's image is drawn in projection, a directional witness's orthographically along its
// direction. A point any witness does not see is shadowed; bit k of its `lost_by` word says
// witness k did not see it.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#include "../common/view.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, r32ui) uniform readonly uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform readonly image2D range_z;
layout(set = 0, binding = 2, r32f) uniform readonly image2D range_dz_dx;
layout(set = 0, binding = 3, r32f) uniform readonly image2D range_dz_dy;
// The witnesses' label images, one band of rows each (label, draw index, triangle): the
// pinhole witnesses' and the directional witnesses'.
layout(set = 0, binding = 4, rgba32ui) uniform readonly uimage2D witness_visibility;
layout(set = 0, binding = 5, rgba32ui) uniform readonly uimage2D directional_visibility;
layout(set = 0, binding = 6, std430) writeonly buffer Masked { uint masked_label[]; };
layout(set = 0, binding = 7, std430) writeonly buffer LostBy { uint lost_by[]; };

// One witness as the mask sees it (src/render/pinhole/witness_mask.rs, WitnessConstants).
struct WitnessData {
    vec4 from_reference[3]; // rows of witness-from-reference, composed in f64 on the host
    vec4 centre;            // a pinhole witness's centre (w = 1), or the unit direction toward a
                            // directional one (w = 0), in the reference frame
    vec4 grid;              // its label image's grid (view.glsl): a pinhole witness's fx, fy,
                            // cx, cy (`columns` applied), a directional one's x0, y0, dx, dy
    uvec4 band;             // its image's width, height, first row, and attachment (0: the
                            // pinhole witnesses', 1: the directional witnesses')
};
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer Witnesses {
    WitnessData witnesses[];
};

layout(push_constant, std430) uniform WitnessMask {
    vec4 intrinsics;        // fx, fy, cx, cy of the reference view
    uvec4 region;           // the pixels to test: first column, first row, width, height
    uint width;             // the reference view's width
    uint witness_count;
    uvec2 witnesses;        // device address of the job's witnesses (Witnesses)
    float facing_tolerance; // the least cosine at which a surface faces a witness (src/exact/)
} m;

// The label test, by the codes of ShadowTest (src/shadow.rs).
layout(constant_id = 0) const uint TEST = 0xffffffffu;
layout(constant_id = 1) const uint TEST_LABEL_SQUARE = 0xffffffffu;

// Whether pixel q of a witness's image exists and carries `label`.
bool carries(WitnessData w, ivec2 q, uint label) {
    if (!(all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(w.band.xy))))) {
        return false;
    }
    ivec2 at = q + ivec2(0, w.band.z);
    uint seen = w.band.w == 0u ? imageLoad(witness_visibility, at).r : imageLoad(directional_visibility, at).r;
    return seen == label;
}

// Whether witness w sees p, whose surface has normal `lit` (on the side the reference sees).
bool sees(WitnessData w, vec3 p, vec3 lit, uint label) {
    bool directional = w.centre.w == 0.0;
    precise vec3 toward = directional ? w.centre.xyz : w.centre.xyz - p;
    precise float facing = dot(lit, toward);
    if (!(facing > m.facing_tolerance * length(lit) * length(toward))) {
        return false;
    }
    precise vec3 q = vec3(dot(w.from_reference[0].xyz, p) + w.from_reference[0].w,
                          dot(w.from_reference[1].xyz, p) + w.from_reference[1].w,
                          dot(w.from_reference[2].xyz, p) + w.from_reference[2].w);
    // Parallel rays come from beyond everything; a pinhole witness sees what lies in front.
    if (!(directional || q.z > 0.0)) {
        return false;
    }
    precise vec2 uv = directional ? orthographic_pixel(w.grid, q.xy) : pinhole_pixel(w.grid, q);
    // Off the image by more than a pixel (checked in floats: a far projection does not fit an
    // int, whose conversion is then undefined).
    if (!(all(greaterThanEqual(uv, vec2(-1.0))) && all(lessThanEqual(uv, vec2(w.band.xy))))) {
        return false;
    }
    if (TEST == TEST_LABEL_SQUARE) {
        ivec2 corner = ivec2(floor(uv));
        return carries(w, corner, label) || carries(w, corner + ivec2(1, 0), label)
            || carries(w, corner + ivec2(0, 1), label) || carries(w, corner + ivec2(1, 1), label);
    }
    // The nearest pixel; its square around its centre is the image's (Intrinsics::contains).
    return carries(w, ivec2(floor(uv + 0.5)), label);
}

void main() {
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, m.region.zw))) {
        return;
    }
    ivec2 pixel = ivec2(m.region.xy + gl_GlobalInvocationID.xy);
    uint index = uint(pixel.y) * m.width + uint(pixel.x);
    uint label = imageLoad(range_label, pixel).r;
    uint lost = 0u;
    if (label != 0u) {
        float z = imageLoad(range_z, pixel).r;
        precise vec3 p = view_point(VIEW_PINHOLE, m.intrinsics, vec2(pixel), z);
        vec3 n = vec3(-imageLoad(range_dz_dx, pixel).r, -imageLoad(range_dz_dy, pixel).r, 1.0);
        // Scaled to components of at most 1: a face along the view's axis has a gradient of
        // up to 1e30, whose square would overflow.
        n /= max(1.0, max(abs(n.x), abs(n.y)));
        // The side of the surface the reference view sees: the one facing back along its ray.
        vec3 lit = dot(n, p) > 0.0 ? -n : n;
        for (uint k = 0u; k < m.witness_count; k++) {
            if (!sees(Witnesses(m.witnesses).witnesses[k], p, lit, label)) {
                lost |= 1u << k;
            }
        }
    }
    lost_by[index] = lost;
    masked_label[index] = lost == 0u ? label : 0u;
}
