#version 460
// [effects.reflectivity]: a point on a surface less reflective than the threshold is lost.
// params.x: the threshold.
#include "effect.glsl"

void main() {
    ivec2 p = this_pixel();
    uint label = p.x < 0 ? 0u : surface_label(p);
    if (label == 0u) {
        return;
    }
    if (reflectivity[e.reflectivity_offset + label] < e.params.x) {
        lose(index_of(p));
    }
}
