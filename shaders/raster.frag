#version 460
// Writes the surface label (u32 end to end, never through a float) and the linear view-frame
// z of the nearest surface. The shadow view (SHADOW_VIEW) also writes |∂z/∂column|, the
// slope the depth-mode shadow test scales its bias by (src/shadow.rs).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#include "draw.glsl"

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer SurfaceIds {
    uint id[];
};

layout(location = 0) in float view_z;
layout(location = 0) out uint label;
layout(location = 1) out float z;
#ifdef SHADOW_VIEW
layout(location = 2) out float slope;
#endif

void main() {
    label = draw.label_base + SurfaceIds(draw.surface_ids).id[gl_PrimitiveID];
    z = view_z;
#ifdef SHADOW_VIEW
    slope = abs(dFdxFine(view_z));
#endif
}
