#version 460
// [effects.quantize]: z rounded to the nearest multiple of the step (ties to even).
// params.x: z_step.
#include "effect.glsl"

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    uint index = index_of(p);
    measured_z[index] = roundEven(current_z(p, index) / e.params.x) * e.params.x;
}
