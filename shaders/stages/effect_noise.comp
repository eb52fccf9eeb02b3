#version 460
// [effects.noise]: Gaussian noise along z, drawn from (seed, pixel), with
// σ = sigma + depth_coefficient·(z − depth_reference)² + incidence_coefficient·α²/(π/2 − α)²,
// α the angle between the normal and the ray toward the reference view (the paper's
// projector), capped (src/effects.rs).
// seed_or_width: seed; params: sigma, depth_coefficient, depth_reference, incidence_coefficient.
#include "effect.glsl"
#include "random.glsl"

const uint NOISE_STREAM = 2u;
// MAX_NOISE_INCIDENCE_DEG, in radians, given by the host.
layout(constant_id = 1) const float MAX_INCIDENCE = 0.0;

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    uint index = index_of(p);
    float z = current_z(p, index);
    float from_reference = z - e.params.z;
    float sigma = e.params.x + e.params.y * from_reference * from_reference;
    // The incidence term only where its coefficient is given: the normal is not read otherwise.
    if (e.params.w != 0.0) {
        float alpha = min(acos(clamp(cos_toward_reference(surface_seen(p)), 0.0, 1.0)), MAX_INCIDENCE);
        float oblique = alpha / (1.5707963267948966 - alpha);
        sigma += e.params.w * oblique * oblique;
    }
    measured_z[index] = z + sigma * gaussian(e.seed_or_width, p, NOISE_STREAM);
}
