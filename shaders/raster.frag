#version 460
// Writes the surface label (u32 end to end, never through a float) and the view-frame z of
// the nearest surface, evaluated from the triangle's plane at the exact pixel centre rather
// than interpolated: interpolation error grows with a facet's slope, the plane does not.
// The plane's normal is the triangle's unit normal, computed once in f64 on the host
// (src/render/gpu_mesh.rs): a cross product of a sliver's nearly parallel edges here, in f32,
// would lose most of its digits. The shadow view (SHADOW_VIEW) also writes ∂z/∂column of
// that plane, which the depth-mode shadow test extrapolates with (src/shadow.rs).
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#include "draw.glsl"

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words {
    uint word[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Floats {
    float value[];
};

layout(location = 0) out uint label;
layout(location = 1) out float z;
#ifdef SHADOW_VIEW
layout(location = 2) out float slope;
#endif

vec3 corner(uint k) {
    uint v = Words(draw.indices).word[3u * uint(gl_PrimitiveID) + k];
    Floats p = Floats(draw.positions);
    return to_view(vec3(p.value[3u * v], p.value[3u * v + 1u], p.value[3u * v + 2u]));
}

void main() {
    label = draw.label_base + Words(draw.surface_ids).word[gl_PrimitiveID];
    vec3 a = corner(0u);
    Floats normals = Floats(draw.normals);
    uint t = 3u * uint(gl_PrimitiveID);
    vec3 n = rotate_to_view(vec3(normals.value[t], normals.value[t + 1u], normals.value[t + 2u]));
    vec2 centre = vec2(draw.grid.x + (gl_FragCoord.x - 0.5) * draw.grid.z,
                       draw.grid.y - (gl_FragCoord.y - 0.5) * draw.grid.w);
    // A fragment exists only where the triangle covers area in xy, so n.z ≠ 0.
    z = a.z - (n.x * (centre.x - a.x) + n.y * (centre.y - a.y)) / n.z;
#ifdef SHADOW_VIEW
    slope = -n.x / n.z * draw.grid.z;
#endif
}
