#version 460
// Triangulation shadow test (paper Fig. 4; DESIGN.md "The shadow test"; src/shadow.rs).
// One invocation per range pixel: move its point into the shadow frame with R_y(-theta),
// find the nearest shadow-buffer pixel and keep or drop the label.
layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 0, binding = 0, r32ui) uniform readonly uimage2D range_label;
layout(set = 0, binding = 1, r32f) uniform readonly image2D range_z;
layout(set = 0, binding = 2, r32ui) uniform readonly uimage2D shadow_label;
layout(set = 0, binding = 3, r32f) uniform readonly image2D shadow_z;
layout(set = 0, binding = 4, r32f) uniform readonly image2D shadow_slope;
layout(set = 0, binding = 5, std430) writeonly buffer Masked { uint masked_label[]; };

layout(push_constant, std430) uniform Mask {
    vec4 range_grid;    // x0, y0, dx, dy of the range view
    vec4 shadow_grid;   // x0, y0, dx, dy of the shadow view
    ivec4 sizes;        // range width, height; shadow width, height
    ivec4 region;       // the range pixels to mask: first column, first row, width, height
    float cos_theta;
    float sin_theta;
    float bias_pitch;   // constant bias, model units
    float bias_relative;// f32 rounding allowance, relative
    uint mode;          // 1 = label, 2 = depth
} m;

const uint MODE_LABEL = 1u;

bool shadowed(ivec2 pixel, uint label) {
    float x = m.range_grid.x + float(pixel.x) * m.range_grid.z;
    float y = m.range_grid.y - float(pixel.y) * m.range_grid.w;
    float z = imageLoad(range_z, pixel).r;
    // p' = R_y(-theta) p
    float xs = m.cos_theta * x - m.sin_theta * z;
    float zs = m.sin_theta * x + m.cos_theta * z;
    float column = (xs - m.shadow_grid.x) / m.shadow_grid.z;
    float row = (m.shadow_grid.y - y) / m.shadow_grid.w;
    ivec2 s = ivec2(floor(column + 0.5), floor(row + 0.5));
    // The shadow grid covers every point the range view can see (sensor.rs); a point
    // outside it can only come from rounding at its border and is treated as lit.
    if (any(lessThan(s, ivec2(0))) || any(greaterThanEqual(s, m.sizes.zw))) {
        return false;
    }
    uint occluder = imageLoad(shadow_label, s).r;
    if (m.mode == MODE_LABEL) {
        return occluder != label;
    }
    if (occluder == 0u) {
        return false;
    }
    // The surface seen at shadow pixel s, its plane carried along the row to the point's
    // exact column; exact when that facet reaches the point. A crease between s and its
    // neighbour toward the point can move the surface by at most the change of slope times
    // the offset, so that much is allowed (src/shadow.rs).
    float offset = column - float(s.x);
    float slope = imageLoad(shadow_slope, s).r;
    float front_z = imageLoad(shadow_z, s).r + slope * offset;
    float bias = m.bias_pitch + m.bias_relative * max(max(abs(zs), abs(front_z)), max(abs(xs), abs(y)));
    ivec2 toward = ivec2(s.x + (offset >= 0.0 ? 1 : -1), s.y);
    if (toward.x >= 0 && toward.x < m.sizes.z && imageLoad(shadow_label, toward).r != 0u) {
        bias += abs(slope - imageLoad(shadow_slope, toward).r) * abs(offset);
    }
    return front_z - zs > bias;
}

void main() {
    if (any(greaterThanEqual(ivec2(gl_GlobalInvocationID.xy), m.region.zw))) {
        return;
    }
    ivec2 pixel = m.region.xy + ivec2(gl_GlobalInvocationID.xy);
    uint label = imageLoad(range_label, pixel).r;
    uint index = uint(pixel.y) * uint(m.sizes.x) + uint(pixel.x);
    masked_label[index] = (label != 0u && shadowed(pixel, label)) ? 0u : label;
}
