#version 460
// [effects.disparity]: depth measured as a disparity d = f·b / z, with Gaussian noise of
// noise_px pixels drawn from (seed, pixel) added to it, rounded to 1/subpixel of a pixel (ties
// to even); a point whose measured disparity lies outside [min_px, max_px] is lost (the
// sensor's search range), else its z becomes f·b / d' (src/effects.rs). z is the depth along a
// pinhole reference view's optical axis.
// seed_or_width: seed; params: f·b, subpixel, min_px, max_px; param4: noise_px.
#include "effect.glsl"
#include "random.glsl"

const uint DISPARITY_STREAM = 3u;

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    uint index = index_of(p);
    float focal_baseline = e.params.x;
    float subpixel = e.params.y;
    precise float disparity = focal_baseline / current_z(p, index);
    if (e.param4 > 0.0) {
        disparity += e.param4 * gaussian(e.seed_or_width, p, DISPARITY_STREAM);
    }
    precise float measured = roundEven(disparity * subpixel) / subpixel;
    // Outside the search, or no finite positive disparity (a point at the camera's centre).
    if (!(measured >= e.params.z && measured <= e.params.w) || !(measured > 0.0) || isinf(measured)) {
        lose(index);
        measured_z[index] = current_z(p, index);
        return;
    }
    measured_z[index] = focal_baseline / measured;
}
