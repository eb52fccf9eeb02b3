#version 460
// [effects.grazing]: a point is lost where its surface normal makes more than the allowed
// angle with the direction to the projector (+z) or to the camera (sin θ, 0, cos θ).
// params.x: the cosine of max_incidence_deg.
#include "effect.glsl"

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    vec3 n = surface_normal(p);
    float to_projector = 1.0 / length(n);
    float to_camera = dot(n, vec3(e.sin_theta, 0.0, e.cos_theta)) * to_projector;
    if (min(to_projector, to_camera) < e.params.x) {
        lose(index_of(p));
    }
}
