#version 460
// [effects.range]: a point outside the working volume min_z ≤ z ≤ max_z is lost.
// params.x, params.y: min_z and max_z (−∞ and +∞ where not given).
#include "effect.glsl"

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    float z = rendered_z(p);
    if (z < e.params.x || z > e.params.y) {
        lose(index_of(p));
    }
}
