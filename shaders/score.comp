#version 460
// Verification counts (paper §4; src/verify/counts.rs has the layout): one invocation per
// pixel of the hypothesis' footprint compares the hypothesis' synthetic labels and depths with the sensed image and adds
// to exact integer counters. Integer atomics are order-independent, so the counts are the
// same whatever the batch; areas are summed in fixed point for the same reason.
// Every buffer is bound, so that synchronization validation sees each access.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, r32ui) uniform readonly uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform readonly image2D range_z;
layout(set = 0, binding = 2, std430) readonly buffer ShadowedLabels { uint shadowed_label[]; };
// Per pixel: dense segment index + 1, 0 = no data.
layout(set = 0, binding = 3, std430) readonly buffer SensedSegments { uint sensed_segment[]; };
layout(set = 0, binding = 4, std430) readonly buffer SensedZ { float sensed_z[]; };
// The batch's counters; this hypothesis' start at counts_offset.
layout(set = 0, binding = 5, std430) buffer Counts { uint count[]; };
// Where effects are named (src/effects.rs): per pixel, the reason an effect lost it (0 if none
// did), and the measured z where an effect changes z.
layout(set = 0, binding = 6, std430) readonly buffer Losses { uint loss[]; };
layout(set = 0, binding = 7, std430) readonly buffer MeasuredZ { float measured_z[]; };

layout(push_constant, std430) uniform Score {
    uint counts_offset;     // this hypothesis' first counter word
    uint use_shadowed;      // 1: labels from the shadow mask's output; 0: range_label
    uint width;
    uint height;
    float z_origin;         // the range view's z is stored as an offset from this
    uint use_losses;        // 1: drop the pixels an effect lost
    uint use_measured_z;    // 1: z from measured_z, not the range view
    uvec4 region;           // the pixels that may hold the model: first column, first row, width, height
    uint surfaces;          // M
    uint segments;          // K
    float tolerance;        // τ
    float area_scale;       // area.rs unit_scale
    float dx;
    float dy;
} s;

// The counts layout's scalar words and where N_M starts, given by the host from
// src/verify/counts.rs.
layout(constant_id = 0) const uint N1_PLUS = 0xffffffffu;
layout(constant_id = 1) const uint N1_MINUS = 0xffffffffu;
layout(constant_id = 2) const uint N0 = 0xffffffffu;
layout(constant_id = 3) const uint POPULATIONS = 0xffffffffu;

// The synthetic z as the range image stores it: the view's f32 offset plus its local origin,
// one correctly rounded f32 addition, as the host adds it (src/sensor.rs, local_origin).
float synthetic_z(ivec2 p) {
    if (s.use_measured_z != 0u) {
        return measured_z[uint(p.y) * s.width + uint(p.x)];
    }
    precise float z = imageLoad(range_z, p).r + s.z_origin;
    return z;
}

// The synthetic label; 0 outside the region, where the attachments were not drawn.
uint synthetic(ivec2 p) {
    if (any(greaterThanEqual(uvec2(p) - s.region.xy, s.region.zw))) {
        return 0u;
    }
    if (s.use_losses != 0u && loss[uint(p.y) * s.width + uint(p.x)] != 0u) {
        return 0u;
    }
    if (s.use_shadowed == 0u) {
        return imageLoad(range_label, p).r;
    }
    return shadowed_label[uint(p.y) * s.width + uint(p.x)];
}

// An exact 64-bit sum in two words: the low word's wrap-around is the carry.
void add_units(uint index, uint units) {
    uint before = atomicAdd(count[s.counts_offset + index], units);
    if (before + units < before) {
        atomicAdd(count[s.counts_offset + index + 1u], 1u);
    }
}

void add_one(uint index) {
    atomicAdd(count[s.counts_offset + index], 1u);
}

// area.rs block_area_units, operation for operation, without fused multiply-adds.
uint triangle_units(float p, float q, float level) {
    precise float sum = p * p + q * q + level;
    precise float units = sqrt(sum) * s.area_scale;
    return uint(min(units, 4294967040.0));
}

void main() {
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, s.region.zw))) {
        return;
    }
    ivec2 p = ivec2(s.region.xy + gl_GlobalInvocationID.xy);
    uint index = uint(p.y) * s.width + uint(p.x);
    uint m = synthetic(p);
    uint k = sensed_segment[index];
    // N1 (sensed valid, synthetic not) is N_i − Σ t, which the host works out: the region
    // need not cover the whole image.
    if (m == 0u) {
        return;
    }
    add_one(POPULATIONS + m - 1u);
    float z = synthetic_z(p);
    if (k == 0u) {
        add_one(N0);
    } else {
        uint overlaps = POPULATIONS + s.surfaces;
        add_one(overlaps + (k - 1u) * s.surfaces + (m - 1u));
        precise float d = z - sensed_z[index];
        if (abs(d) <= s.tolerance) {
            add_one(N1_PLUS);
        } else if (d > s.tolerance) {
            add_one(N1_MINUS);
        }
    }
    // The 2×2 block whose top-left pixel this is, if all four carry surface m.
    ivec2 right = p + ivec2(1, 0), down = p + ivec2(0, 1), across = p + ivec2(1, 1);
    if (uint(across.x) < s.width && uint(across.y) < s.height
        && synthetic(right) == m && synthetic(down) == m && synthetic(across) == m) {
        float z10 = synthetic_z(right);
        float z01 = synthetic_z(down);
        float z11 = synthetic_z(across);
        precise float a = z10 - z;
        precise float b = z11 - z;
        precise float e = z01 - z;
        precise float dxdy = s.dx * s.dy;
        precise float level = dxdy * dxdy;
        precise float q1 = s.dx * (a - b);
        precise float p2 = s.dy * (b - e);
        uint areas = POPULATIONS + s.surfaces + s.segments * s.surfaces + 2u * (m - 1u);
        add_units(areas, triangle_units(s.dy * a, q1, level));
        add_units(areas, triangle_units(p2, s.dx * e, level));
    }
}
