#version 460
// The compute rasterizer's resolve pass (src/render/compute_raster.rs): one invocation per
// pixel of the area writes what raster.frag would have written for the nearest triangle into
// the view's attachments, or zeros where no triangle covers the pixel (the graphics pass
// clears to 0).
layout(local_size_x = 8, local_size_y = 8) in;

// The view's colour attachments, in src/render/targets.rs order.
#ifdef SHADOW_VIEW
#define FIRST_BUFFER 1
layout(set = 0, binding = 0, rgba32ui) uniform writeonly uimage2D visibility;
#else
#define FIRST_BUFFER 4
layout(set = 0, binding = 0, r32ui) uniform writeonly uimage2D label;
layout(set = 0, binding = 1, r32f) uniform writeonly image2D z;
layout(set = 0, binding = 2, r32f) uniform writeonly image2D dz_dx;
layout(set = 0, binding = 3, r32f) uniform writeonly image2D dz_dy;
#endif
#include "raster_compute.glsl"

void main() {
    if (any(greaterThanEqual(gl_GlobalInvocationID.xy, r.area.zw))) {
        return;
    }
    ivec2 pixel = ivec2(r.area.xy + gl_GlobalInvocationID.xy);
    uint64_t word = nearest[uint(pixel.y) * r.stride + uint(pixel.x)];
    bool hit = word != EMPTY;
    DrawData d = draws[r.draw];
    uint t = uint(word & 0xffffffffUL);
#ifdef SHADOW_VIEW
    imageStore(visibility, pixel, hit ? uvec4(triangle_label(d, t), d.draw_index, t, 0u) : uvec4(0u));
#else
    if (!hit) {
        imageStore(label, pixel, uvec4(0u));
        imageStore(z, pixel, vec4(0.0));
        imageStore(dz_dx, pixel, vec4(0.0));
        imageStore(dz_dy, pixel, vec4(0.0));
        return;
    }
    vec3 n = triangle_normal(d, t);
    imageStore(label, pixel, uvec4(triangle_label(d, t)));
    imageStore(z, pixel, vec4(plane_z(d, triangle_corner(d, t, 0u), n, pixel)));
    imageStore(dz_dx, pixel, vec4(-n.x / n.z));
    imageStore(dz_dy, pixel, vec4(-n.y / n.z));
#endif
}
