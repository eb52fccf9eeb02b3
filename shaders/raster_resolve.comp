#version 460
// The compute rasterizer's resolve pass (src/render/compute_raster.rs): one invocation per
// pixel of the range view's area writes what raster.frag would have written for the nearest
// triangle into the view's attachments, or zeros where no triangle covers the pixel (the
// graphics pass clears to 0). Recorded only where no shadow mask follows: the mask resolves
// the range view itself as it tests it, and reads the shadow view's words as they are
// (shadow_mask.comp).
layout(local_size_x = 8, local_size_y = 8) in;
#include "raster_compute.glsl"

// The range view's colour attachments, in src/render/targets.rs order, then its draw table and
// words (src/gpu/descriptors.rs binds images first).
layout(set = 0, binding = 0, r32ui) uniform writeonly uimage2D label;
layout(set = 0, binding = 1, r32f) uniform writeonly image2D z;
layout(set = 0, binding = 2, r32f) uniform writeonly image2D dz_dx;
layout(set = 0, binding = 3, r32f) uniform writeonly image2D dz_dy;
layout(set = 0, binding = 4, std430) readonly buffer DrawTable { DrawData draws[]; };
layout(set = 0, binding = 5, std430) readonly buffer Nearest { uint64_t nearest[]; };

layout(push_constant, std430) uniform Resolve { RasterView view; } r;

void main() {
    // Read while every invocation is still active: a software rasterizer then reads it once
    // for all of them instead of gathering it per invocation.
    DrawData d = draws[r.view.draw];
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, r.view.area.zw))) {
        return;
    }
    ivec2 pixel = ivec2(r.view.area.xy + gl_GlobalInvocationID.xy);
    uint64_t word = nearest[word_index(r.view.stride, pixel)];
    RangePixel range = RangePixel(0u, 0.0, vec2(0.0));
    if (word != EMPTY) {
        range = range_pixel_by_words(d, uint(word & 0xffffffffUL), vec2(pixel));
    }
    imageStore(label, pixel, uvec4(range.label));
    imageStore(z, pixel, vec4(range.z));
    imageStore(dz_dx, pixel, vec4(range.gradient.x));
    imageStore(dz_dy, pixel, vec4(range.gradient.y));
}
