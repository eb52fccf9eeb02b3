#version 460
// [effects.edges]: the mixed-pixel filter. A point is lost when any pixel within `width`
// of it (Chebyshev distance, inside the image) holds no surface after shadowing or differs
// from it in z by more than the jump. seed_or_width: width_px; params.x: jump.
#include "effect.glsl"

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    float z = imageLoad(range_z, p).r;
    int width = int(e.seed_or_width);
    ivec2 lo = max(p - width, ivec2(0));
    ivec2 hi = min(p + width, ivec2(e.width, e.height) - 1);
    for (int y = lo.y; y <= hi.y; y++) {
        for (int x = lo.x; x <= hi.x; x++) {
            ivec2 q = ivec2(x, y);
            if (q == p) {
                continue;
            }
            // Differences of offsets from one origin: the origin cancels.
            if (label_after_shadow(q) == 0u || abs(imageLoad(range_z, q).r - z) > e.params.x) {
                lose(index_of(p));
                return;
            }
        }
    }
}
