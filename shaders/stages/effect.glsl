// What every effect pass shares (src/effects.rs, src/render/stages/effects.rs): one invocation
// per range pixel of the region, the range view's attachments, the labels after shadowing,
// and the buffers the effects write: each pixel's loss (the Reason code of the first effect
// that lost it, 0 while none has) and its measured z (absolute, range frame) where an effect
// changes z. Effects are evaluated at every pixel that holds a surface before shadowing, so a
// count of the unshadowed image sees the same losses.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#include "../common/view.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, r32ui) uniform readonly uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform readonly image2D range_z;
layout(set = 0, binding = 2, r32f) uniform readonly image2D range_dz_dx;
layout(set = 0, binding = 3, r32f) uniform readonly image2D range_dz_dy;
layout(set = 0, binding = 4, std430) readonly buffer ShadowedLabels { uint shadowed_label[]; };
layout(set = 0, binding = 5, std430) buffer Losses { uint loss[]; };
layout(set = 0, binding = 6, std430) buffer MeasuredZ { float measured_z[]; };
// Reflectivity of label l of this job at reflectivity_offset + l.
layout(set = 0, binding = 7, std430) readonly buffer Reflectivities { float reflectivity[]; };

layout(push_constant, std430) uniform Effect {
    uvec4 region;          // the pixels to evaluate: first column, first row, width, height
    uint width;
    uint height;
    uint use_shadowed;     // 1: labels after shadowing are in shadowed_label; 0: range_label
    uint z_in_buffer;      // 1: an earlier pass changed z: it is in measured_z
    float z_origin;        // the range view's z is stored as an offset from this
    uint reference_kind;   // the reference view (view.glsl): VIEW_ORTHOGRAPHIC or VIEW_PINHOLE
    uint witness_count;
    uint seed_or_width;    // the effect's seed, or edges' width in pixels
    vec4 params;           // the effect's parameters (src/render/stages/effects.rs)
    uint reflectivity_offset;
    float param4;          // a fifth parameter: disparity's noise_px
    uvec2 witnesses;       // device address of the witnesses (EffectWitnesses)
    vec4 reference_grid;   // the reference view's grid (view.glsl)
} e;

// The sensor's witnesses in file order (src/render/stages/effects.rs, EffectSensor): a unit
// direction toward the witness (w = 0) or its centre (w = 1), in the reference frame.
layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer EffectWitnesses {
    vec4 witness[];
};

// This pass's Reason code (src/effects.rs), given by the host.
layout(constant_id = 0) const uint REASON = 0xffffffffu;

bool in_region(ivec2 p) {
    return all(lessThan(uvec2(p) - e.region.xy, e.region.zw));
}

// The surface at p before shadowing; 0 outside the region, where nothing was drawn.
uint surface_label(ivec2 p) {
    return in_region(p) ? imageLoad(range_label, p).r : 0u;
}

uint label_after_shadow(ivec2 p) {
    if (!in_region(p)) {
        return 0u;
    }
    return e.use_shadowed == 0u ? imageLoad(range_label, p).r : shadowed_label[uint(p.y) * e.width + uint(p.x)];
}

// The range-frame z of p as rendered: one correctly rounded f32 addition of the local origin,
// as the host and the score pass add it.
float rendered_z(ivec2 p) {
    precise float z = imageLoad(range_z, p).r + e.z_origin;
    return z;
}

// z as the effects before this one left it.
float current_z(ivec2 p, uint index) {
    return e.z_in_buffer != 0u ? measured_z[index] : rendered_z(p);
}

// The surface's upward normal, unnormalised: (−∂z/∂x, −∂z/∂y, 1).
vec3 surface_normal(ivec2 p) {
    return vec3(-imageLoad(range_dz_dx, p).r, -imageLoad(range_dz_dy, p).r, 1.0);
}

// Records this pass's reason unless an earlier pass lost the pixel already.
void lose(uint index) {
    if (loss[index] == 0u) {
        loss[index] = REASON;
    }
}

// The pixel of this invocation, or (-1, -1) outside the region.
ivec2 this_pixel() {
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, e.region.zw))) {
        return ivec2(-1);
    }
    return ivec2(e.region.xy + gl_GlobalInvocationID.xy);
}

uint index_of(ivec2 p) {
    return uint(p.y) * e.width + uint(p.x);
}

// The surface at p as the reference view sees it: its point (reference frame), its normal on
// the side facing the view (not unit) and the inverse of the normal's length.
struct Surface {
    vec3 point;
    vec3 normal;
    float inverse_length;
};

Surface surface_seen(ivec2 p) {
    vec3 n = surface_normal(p);
    vec3 point = view_point(e.reference_kind, e.reference_grid, vec2(p), rendered_z(p));
    if (e.reference_kind == VIEW_PINHOLE) {
        // Scaled to components of at most 1: a face along the view's ray has a gradient of up
        // to 1e30, whose square would overflow. Its upward side faces away from the view.
        n /= max(1.0, max(abs(n.x), abs(n.y)));
        n = dot(n, point) > 0.0 ? -n : n;
    }
    return Surface(point, n, 1.0 / length(n));
}

// The cosine of the angle between the surface's normal and the direction from it toward the
// reference view: back along its ray to a pinhole view's centre; +z, the normal's z (1) over its
// length, under an orthographic view (which looks down −z: the paper's projector).
float cos_toward_reference(Surface s) {
    if (e.reference_kind == VIEW_PINHOLE) {
        return dot(s.normal, -s.point) * s.inverse_length / length(s.point);
    }
    return s.normal.z * s.inverse_length;
}

// The cosine of the angle between the surface's normal and the direction toward witness k.
float cos_toward_witness(Surface s, uint k) {
    vec4 w = EffectWitnesses(e.witnesses).witness[k];
    if (w.w == 0.0) {
        return dot(s.normal, w.xyz) * s.inverse_length;
    }
    vec3 toward = w.xyz - s.point;
    return dot(s.normal, toward) * s.inverse_length / length(toward);
}
