#version 460
// The compute rasterizer's resolve pass (src/render/raster/compute/): one invocation per
// pixel of a view's area writes what raster.frag would have written for the triangle its word
// kept into the view's attachments, or zeros where no triangle covers the pixel (the graphics
// pass clears to 0). Recorded for the range view only where no shadow mask follows, as the
// mask reading words resolves the range view itself as it tests it, and reads the shadow
// view's words as they are (shadow_mask.comp); and for both views of a view of several draws
// (SEVERAL_DRAWS), whose shadow mask reads the attachments as the graphics path leaves them.
//
// SHADOW_VIEW: the shadow view's variant, writing its visibility attachment (a rig's witness
// bands' too). PINHOLE: a rig's pinhole reference view's, whose words hold depths (raster.comp),
// writing what raster.frag's PINHOLE variant writes (pinhole_range_pixel, draw.glsl).
layout(local_size_x = 8, local_size_y = 8) in;
#include "raster_compute.glsl"

#ifdef SHADOW_VIEW
// Label, draw index, triangle, 0 (src/render/targets.rs).
layout(set = 0, binding = 0, rgba32ui) uniform writeonly uimage2D visibility;
layout(set = 0, binding = 1, std430) readonly buffer DrawTable { DrawData draws[]; };
layout(set = 0, binding = 2, std430) readonly buffer Nearest { uint64_t nearest[]; };
#else
// The range view's colour attachments, in src/render/targets.rs order, then its draw table and
// words (src/gpu/descriptors.rs binds images first).
layout(set = 0, binding = 0, r32ui) uniform writeonly uimage2D label;
layout(set = 0, binding = 1, r32f) uniform writeonly image2D z;
layout(set = 0, binding = 2, r32f) uniform writeonly image2D dz_dx;
layout(set = 0, binding = 3, r32f) uniform writeonly image2D dz_dy;
layout(set = 0, binding = 4, std430) readonly buffer DrawTable { DrawData draws[]; };
layout(set = 0, binding = 5, std430) readonly buffer Nearest { uint64_t nearest[]; };
#endif

// The view's first draw, and where several draws share the words, the place of each
// triangle's draw after it is the triangle's tag (raster.comp).
layout(push_constant, std430) uniform Resolve { RasterView view; } r;

// 1: the words hold triangles of several draws, tagged with their draw's place after the
// view's first draw (raster.comp; the draws numbered in the ties order, src/render/mod.rs);
// 0: of the view's one draw, untagged. One pipeline each: a software rasterizer would gather a
// draw a pixel where the one draw is read once for all.
layout(constant_id = 0) const uint SEVERAL_DRAWS = 0u;

void main() {
    // Read while every invocation is still active: a software rasterizer then reads it once
    // for all of them instead of gathering it per invocation.
    DrawData d = draws[r.view.draw];
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, r.view.area.zw))) {
        return;
    }
    ivec2 pixel = ivec2(r.view.area.xy + gl_GlobalInvocationID.xy);
    uint64_t word = nearest[word_index(r.view.stride, pixel)];
    uint tagged = uint(word & 0xffffffffUL), t = tagged, draw = r.view.draw;
    if (SEVERAL_DRAWS != 0u && word != EMPTY) {
        t = untagged(tagged);
        draw += tagged >> MEMBER_SHIFT;
        d = draws[draw];
    }
#ifdef SHADOW_VIEW
    uvec4 seen = word != EMPTY ? uvec4(triangle_label(d, t), draw, t, 0u) : uvec4(0u);
    imageStore(visibility, pixel, seen);
#else
    RangePixel range = RangePixel(0u, 0.0, vec2(0.0));
    if (word != EMPTY) {
#ifdef PINHOLE
        range = pinhole_range_pixel(d, t, vec2(pixel));
#else
        // One draw's words hold the z (visibility_word.glsl); several draws', depths.
        range = SEVERAL_DRAWS != 0u ? range_pixel_by_words(d, t, vec2(pixel))
                                    : range_pixel_at_z(d, t, z_of_key(uint(word >> 32)), true);
#endif
    }
    imageStore(label, pixel, uvec4(range.label));
    imageStore(z, pixel, vec4(range.z));
    imageStore(dz_dx, pixel, vec4(range.gradient.x));
    imageStore(dz_dy, pixel, vec4(range.gradient.y));
#endif
}
