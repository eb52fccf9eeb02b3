// A pixel's visibility word, as the compute rasterizer keeps it (src/render/compute_raster.rs)
// and the shadow mask reads it: 64 bits, the depth's bits high (a non-negative float orders as
// its bits) and the triangle low, so an atomicMin keeps the nearest triangle, and among equal
// depths the first in the mesh, as the graphics pipeline's LESS depth test does. All ones where
// no triangle covers the pixel (the host fills the words with ones before the raster pass). A
// view's words are stored row by row. A shader without 64-bit integers reads a word as two
// 32-bit halves, the triangle's first; that half alone says whether a triangle covers the
// pixel (meshes have fewer than 2^29 triangles: src/mesh/adjacency.rs), so a shader that needs
// only the triangle reads only it.

// Each half of a word where no triangle covers the pixel: EMPTY_HALF (contract.glsl).
#include "contract.glsl"

// Where a pixel's word is among a view's words, `stride` pixels a row.
uint word_index(uint stride, ivec2 pixel) {
    return uint(pixel.y) * stride + uint(pixel.x);
}
