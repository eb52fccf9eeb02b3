#version 460
// The scanner's views are orthographic: pixel (c, r) has its centre at x = x0 + c·dx, y = y0 −
// r·dy (src/sensor/orthographic.rs), which lands on framebuffer pixel centres (c + ½, r + ½)
// through the viewport (src/render/raster/draw.rs). PINHOLE: a pinhole view's, which projects
// (pinhole_clip_position, draw.glsl).
#include "draw.glsl"

layout(push_constant, std430) uniform Draw {
    DrawData draw;
};

layout(location = 0) in vec3 position;

void main() {
    // The range view rasterizes twice (depth, then colour within the tie tolerance of it), in
    // two pipelines: `precise` forbids fusing these operations differently in each, so both
    // compute the same depth for the same vertex. (`invariant gl_Position` would say so too,
    // but SPIR-V validation rejects it on the gl_PerVertex block glslang emits.)
#ifdef PINHOLE
    precise vec4 clip = pinhole_clip_position(draw, to_view(draw, position));
    gl_Position = clip;
#else
    precise vec3 clip = clip_position(draw, to_view(draw, position));
    gl_Position = vec4(clip, 1.0);
#endif
}
