#version 460
// [effects.dropout]: each point is lost with the given probability, drawn from (seed, pixel).
// seed_or_width: seed; params.x: probability.
#include "effect.glsl"
#include "random.glsl"

// Stream of the draws (noise uses another).
const uint DROPOUT_STREAM = 1u;

void main() {
    ivec2 p = this_pixel();
    if (p.x < 0 || surface_label(p) == 0u) {
        return;
    }
    if (uniform2(e.seed_or_width, p, DROPOUT_STREAM).x < e.params.x) {
        lose(index_of(p));
    }
}
