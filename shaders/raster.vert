#version 460
// Both views: orthographic, so w = 1 and the view-frame z varies linearly across a triangle.
#include "draw.glsl"

layout(location = 0) in vec3 position;
layout(location = 0) out float view_z;

void main() {
    vec4 p = vec4(position, 1.0);
    gl_Position = draw.clip_from_model * p;
    view_z = dot(draw.view_z_row, p);
}
