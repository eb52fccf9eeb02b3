#version 460
// [effects.grazing]: a point is lost where its surface normal makes more than the allowed
// angle with the direction toward the reference view or toward any witness (the paper's
// scanner: the projector, +z, and the camera, (sin θ, 0, cos θ)); an angle that cannot be
// measured (a face seen edge-on) loses it too.
// params.x: the cosine of max_incidence_deg.
#include "effect.glsl"

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    Surface s = surface_seen(p);
    bool seen = cos_toward_reference(s) >= e.params.x;
    for (uint k = 0u; seen && k < e.witness_count; k++) {
        seen = cos_toward_witness(s, k) >= e.params.x;
    }
    if (!seen) {
        lose(index_of(p));
    }
}
