#version 460
// Verification counts (paper §4; src/verify/counts.rs has the layout): one invocation per
// run of RUN pixels of a row of the hypothesis' footprint compares the hypothesis' synthetic
// labels and depths with the sensed image and adds to exact integer counters. Integer atomics
// are order-independent, so the counts are the same whatever the batch; areas are summed in
// fixed point for the same reason. Every buffer is bound, so that synchronization validation
// sees each access.
//
// An invocation tallies its run before it adds: a counter is added to once for as many
// neighbouring pixels as add to it in turn (most do: a run mostly sees one surface in one
// segment), where adding a pixel at a time spent half the pass on atomics that every
// invocation aimed at the same few counters.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, r32ui) uniform readonly uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform readonly image2D range_z;
layout(set = 0, binding = 2, std430) readonly buffer ShadowedLabels { uint shadowed_label[]; };
// Per pixel: dense segment index + 1 (0 = no data), and z's bits (src/verify/sensed.rs).
layout(set = 0, binding = 3, std430) readonly buffer Sensed { uvec2 sensed_pixel[]; };
// The slot's counters (src/verify/batch.rs); this hypothesis' start at counts_offset.
layout(set = 0, binding = 4, std430) buffer Counts { uint count[]; };
// Where effects are named (src/effects.rs): per pixel, the reason an effect lost it (0 if none
// did), and the measured z where an effect changes z.
layout(set = 0, binding = 5, std430) readonly buffer Losses { uint loss[]; };
layout(set = 0, binding = 6, std430) readonly buffer MeasuredZ { float measured_z[]; };

layout(push_constant, std430) uniform Score {
    uint counts_offset;     // this hypothesis' first counter word
    uint width;
    uint height;
    float z_origin;         // the range view's z is stored as an offset from this
    uvec4 region;           // the pixels that may hold the model: first column, first row, width, height
    uint surfaces;          // M
    uint segments;          // K
    float tolerance;        // τ
    float area_scale;       // area.rs unit_scale, of the area unit's sides (BlockGeometry)
    float dx;               // the orthographic pitch; PINHOLE: 1/fx and 1/fy
    float dy;
    vec2 principal;         // PINHOLE: cx, cy
} s;

// The counts layout's scalar words and where N_M starts, given by the host from
// src/verify/counts.rs.
layout(constant_id = 0) const uint N1_PLUS = 0xffffffffu;
layout(constant_id = 1) const uint N1_MINUS = 0xffffffffu;
layout(constant_id = 2) const uint N0 = 0xffffffffu;
layout(constant_id = 3) const uint POPULATIONS = 0xffffffffu;
// Pixels an invocation scores, consecutive in a row (given by the host, score_pass.rs).
layout(constant_id = 4) const uint RUN = 1u;
// What the pass counts from (ScoreSources, score_pass.rs), one pipeline each: lavapipe runs
// both sides of a branch on a uniform value, so each read not needed would still be made.
layout(constant_id = 5) const bool USE_SHADOWED = false;   // labels from the shadow mask's output, not range_label
layout(constant_id = 6) const bool USE_LOSSES = false;     // drop the pixels an effect lost
layout(constant_id = 7) const bool USE_MEASURED_Z = false; // z from measured_z, not the range view
// Whether sqrt_rounded corrects the device's square root (score_pass.rs: on a GPU), and ulps
// added to it first: 0, but for the test that stands in for a device whose sqrt errs.
layout(constant_id = 8) const bool CORRECT_SQRT = true;
layout(constant_id = 9) const int SQRT_ERROR_ULPS = 0;
// The view's kind (BlockRays, area.rs): an orthographic view's z grows toward the sensor and
// its blocks' points lie over a grid of pitch (dx, dy); a pinhole view's depth Z grows away
// from it and a pixel's point is Z times its ray, ((col − cx)/fx, (row − cy)/fy, 1).
layout(constant_id = 10) const bool PINHOLE = false;

// The synthetic z as the range image stores it: the view's f32 offset plus its local origin,
// one correctly rounded f32 addition, as the host adds it (src/sensor/grid.rs, local_origin).
float synthetic_z(ivec2 p) {
    if (USE_MEASURED_Z) {
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
    if (USE_LOSSES && loss[uint(p.y) * s.width + uint(p.x)] != 0u) {
        return 0u;
    }
    if (!USE_SHADOWED) {
        return imageLoad(range_label, p).r;
    }
    return shadowed_label[uint(p.y) * s.width + uint(p.x)];
}

// Pixels of a run counted for one counter (its index), not yet added.
struct Tally {
    uint index;
    uint pixels;
};

void add(inout Tally t) {
    if (t.pixels != 0u) {
        atomicAdd(count[s.counts_offset + t.index], t.pixels);
    }
    t.pixels = 0u;
}

// Counts a pixel for counter `index`, first adding what was counted for another.
void count_pixel(inout Tally t, uint index) {
    if (t.index != index) {
        add(t);
        t.index = index;
    }
    t.pixels += 1u;
}

// Area units of a run for one surface's area (index: its low word), an exact 64-bit sum.
struct AreaTally {
    uint index;
    uint low;
    uint high;
};

// Adds to the counter's two words: the low word's wrap-around is the carry.
void add(inout AreaTally a) {
    if ((a.low | a.high) == 0u) {
        return;
    }
    uint before = atomicAdd(count[s.counts_offset + a.index], a.low);
    uint high = a.high + (before + a.low < before ? 1u : 0u);
    if (high != 0u) {
        atomicAdd(count[s.counts_offset + a.index + 1u], high);
    }
    a.low = 0u;
    a.high = 0u;
}

void count_units(inout AreaTally a, uint index, uint units) {
    if (a.index != index) {
        add(a);
        a.index = index;
    }
    uint carry;
    a.low = uaddCarry(a.low, units, carry);
    a.high += carry;
}

// The sign of m² − s, m the midpoint between r and the float next to it above (`up`) or
// below, exactly, in integers: r and s positive normal floats, r within a few ulp of √s.
int midpoint_square_minus(float r, bool up, float s) {
    uint r_bits = floatBitsToUint(r), s_bits = floatBitsToUint(s);
    // r = M · 2^e and s = S · 2^f, M and S whole numbers of 24 bits.
    uint M = (r_bits & 0x7fffffu) | 0x800000u, S = (s_bits & 0x7fffffu) | 0x800000u;
    int e = int(r_bits >> 23) - 150, f = int(s_bits >> 23) - 150;
    // m = K · 2^k: (2M ± 1) · 2^(e − 1), or below a power of two, whose neighbour below is
    // half as far, (4M − 1) · 2^(e − 2).
    uint K = up ? 2u * M + 1u : (M == 0x800000u ? 4u * M - 1u : 2u * M - 1u);
    int k = up || M != 0x800000u ? e - 1 : e - 2;
    // K² · 2^(2k) against S · 2^f: K² (up to 50 bits) against S · 2^(f − 2k), a shift of
    // 24 to 27 bits next to √s.
    uint square_high, square_low;
    umulExtended(K, K, square_high, square_low);
    uint shift = uint(clamp(f - 2 * k, 1, 31));
    uint s_high = S >> (32u - shift), s_low = S << shift;
    if (square_high != s_high) {
        return square_high > s_high ? 1 : -1;
    }
    return square_low > s_low ? 1 : (square_low < s_low ? -1 : 0);
}

// √s as IEEE 754 rounds it to nearest, as the host's f32::sqrt gives it (area.rs): Vulkan
// lets a device's sqrt err by a few ulp (NVIDIA's approximates it), and the areas the host
// and the GPU count must agree to the bit. The device's root is moved to the float whose
// midpoints with its neighbours bracket √s (a square root is never such a midpoint: the
// comparisons are strict). Zero, subnormal and infinite sums are left as the device has them.
// Not compiled in on a CPU device, whose root is the IEEE one: there it would only cost time.
float sqrt_rounded(float s) {
    float r = sqrt(s);
    if (!CORRECT_SQRT) {
        return r;
    }
    if (SQRT_ERROR_ULPS != 0) {
        r = uintBitsToFloat(uint(int(floatBitsToUint(r)) + SQRT_ERROR_ULPS));
    }
    if (!(s >= 1.17549435e-38 && s <= 3.40282347e38)) {
        return r;
    }
    // Vulkan bounds sqrt's error by 1/inversesqrt's: up to about 6.5 ulp.
    for (int i = 0; i < 8; i++) {
        if (midpoint_square_minus(r, true, s) < 0) {
            r = uintBitsToFloat(floatBitsToUint(r) + 1u);
        } else if (midpoint_square_minus(r, false, s) > 0) {
            r = uintBitsToFloat(floatBitsToUint(r) - 1u);
        } else {
            break;
        }
    }
    return r;
}

// Units of a triangle whose doubled area's square is `sum`: its square root rounded as the
// host's is, scaled, capped (area.rs).
uint units_of(float sum) {
    precise float units = sqrt_rounded(sum) * s.area_scale;
    return uint(min(units, 4294967040.0));
}

// area.rs block_area_units, operation for operation, without fused multiply-adds.
uint triangle_units(float p, float q, float level) {
    precise float sum = p * p + q * q + level;
    return units_of(sum);
}

// The squared length of a × b, as area.rs `squared_cross` works it out.
float squared_cross(vec3 a, vec3 b) {
    precise float x = a.y * b.z - a.z * b.y;
    precise float y = a.z * b.x - a.x * b.z;
    precise float z = a.x * b.y - a.y * b.x;
    precise float sum = x * x + y * y + z * z;
    return sum;
}

// A pinhole view's point of pixel p at depth z: z times its ray (area.rs `pinhole_point`).
vec3 pinhole_point(ivec2 p, float z) {
    precise vec2 ray = (vec2(p) - s.principal) * vec2(s.dx, s.dy);
    precise vec3 point = vec3(z * ray.x, z * ray.y, z);
    return point;
}

void main() {
    uvec2 start = uvec2(gl_GlobalInvocationID.x * RUN, gl_GlobalInvocationID.y);
    if (any(greaterThanEqual(start, s.region.zw))) {
        return;
    }
    uint populations = POPULATIONS, overlaps = POPULATIONS + s.surfaces;
    uint areas = overlaps + s.segments * s.surfaces;
    Tally population = Tally(populations, 0u), overlap = Tally(overlaps, 0u);
    Tally n0 = Tally(N0, 0u), n1_plus = Tally(N1_PLUS, 0u), n1_minus = Tally(N1_MINUS, 0u);
    AreaTally area = AreaTally(areas, 0u, 0u);
    uint end = min(start.x + RUN, s.region.z);
    // Each label and z is read once: a pixel's right and across neighbours, which its 2×2
    // block reads, are the next pixel and the one below it. (A z is read wherever its label
    // may be, and used only where the label is a surface's.)
    ivec2 first = ivec2(s.region.xy + start);
    bool has_down = uint(first.y) + 1u < s.height;
    uint label = synthetic(first), label_below = has_down ? synthetic(first + ivec2(0, 1)) : 0u;
    float z_next = synthetic_z(first), z_next_below = has_down ? synthetic_z(first + ivec2(0, 1)) : 0.0;
    for (uint x = start.x; x < end; x++) {
        ivec2 p = ivec2(s.region.xy + uvec2(x, start.y));
        ivec2 right = p + ivec2(1, 0), down = p + ivec2(0, 1), across = p + ivec2(1, 1);
        bool has_right = uint(right.x) < s.width;
        uint m = label, m_below = label_below;
        uint m_right = has_right ? synthetic(right) : 0u;
        uint m_across = has_right && has_down ? synthetic(across) : 0u;
        label = m_right;
        label_below = m_across;
        float z = z_next, z01 = z_next_below;
        float z10 = has_right ? synthetic_z(right) : 0.0;
        float z11 = has_right && has_down ? synthetic_z(across) : 0.0;
        z_next = z10;
        z_next_below = z11;
        uint index = uint(p.y) * s.width + uint(p.x);
        uvec2 sensed = sensed_pixel[index];
        uint k = sensed.x;
        // N1 (sensed valid, synthetic not) is N_i − Σ t, which the host works out: the region
        // need not cover the whole image.
        if (m == 0u) {
            continue;
        }
        count_pixel(population, populations + m - 1u);
        if (k == 0u) {
            n0.pixels += 1u;
        } else {
            count_pixel(overlap, overlaps + (k - 1u) * s.surfaces + (m - 1u));
            // Positive where the synthetic surface lies nearer the sensor than the sensed one.
            precise float d = PINHOLE ? uintBitsToFloat(sensed.y) - z : z - uintBitsToFloat(sensed.y);
            if (abs(d) <= s.tolerance) {
                n1_plus.pixels += 1u;
            } else if (d > s.tolerance) {
                n1_minus.pixels += 1u;
            }
        }
        // The 2×2 block whose top-left pixel this is, if all four carry surface m.
        if (PINHOLE && has_right && has_down && m_right == m && m_below == m && m_across == m) {
            // area.rs pinhole_block_area_units.
            precise vec3 p00 = pinhole_point(p, z);
            precise vec3 e1 = pinhole_point(right, z10) - p00;
            precise vec3 e2 = pinhole_point(across, z11) - p00;
            precise vec3 e3 = pinhole_point(down, z01) - p00;
            uint surface_area = areas + 2u * (m - 1u);
            count_units(area, surface_area, units_of(squared_cross(e1, e2)));
            count_units(area, surface_area, units_of(squared_cross(e2, e3)));
        } else if (has_right && has_down && m_right == m && m_below == m && m_across == m) {
            precise float a = z10 - z;
            precise float b = z11 - z;
            precise float e = z01 - z;
            precise float dxdy = s.dx * s.dy;
            precise float level = dxdy * dxdy;
            precise float q1 = s.dx * (a - b);
            precise float p2 = s.dy * (b - e);
            uint surface_area = areas + 2u * (m - 1u);
            count_units(area, surface_area, triangle_units(s.dy * a, q1, level));
            count_units(area, surface_area, triangle_units(p2, s.dx * e, level));
        }
    }
    add(population);
    add(overlap);
    add(n0);
    add(n1_plus);
    add(n1_minus);
    add(area);
}
