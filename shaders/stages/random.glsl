// A counter-based random generator: pcg4d (Jarzynski and Olano, "Hash Functions for GPU
// Rendering", JCGT 2020), a hash of four words with no state, so a pixel's draw depends only on
// its key (seed, pixel, stream) and an image is the same whatever the batch or the order.

uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// Two independent uniform variates in [0, 1), 24 bits each, for (seed, pixel, stream).
vec2 uniform2(uint seed, ivec2 pixel, uint stream) {
    uvec4 h = pcg4d(uvec4(uvec2(pixel), seed, stream));
    return vec2(h.xy >> 8u) * (1.0 / 16777216.0);
}

// A standard normal variate for (seed, pixel, stream), by the Box-Muller transform (the first
// variate is taken from (0, 1], so its logarithm is finite: |result| < 5.8).
float gaussian(uint seed, ivec2 pixel, uint stream) {
    vec2 u = uniform2(seed, pixel, stream);
    float radius = sqrt(-2.0 * log(1.0 - u.x));
    return radius * cos(6.2831853071795865 * u.y);
}
