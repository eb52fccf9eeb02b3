// A pixel's visibility word, as the compute rasterizer keeps it (src/render/raster/compute/)
// and the shadow mask reads it: 64 bits, an order key high and the triangle low, so that an
// atomicMin keeps the nearest triangle, and among equal keys the first in the mesh, as the
// graphics pipeline's LESS depth test does. All ones where no triangle covers the pixel (the
// host fills the words with ones before the raster pass). A view's words are stored row by
// row. A shader without 64-bit integers reads a word as two 32-bit halves, the triangle's
// first; that half alone says whether a triangle covers the pixel (meshes have fewer than 2^29
// triangles: src/mesh/adjacency.rs), so a shader that needs only the triangle reads only it.
//
// The key is one of two:
// - In the range view of one draw, the z that the range view holds at the pixel (the plane's
//   at its exact centre), as z_key orders it. Whoever resolves the view reads z from the word
//   and only the label and normal from the triangle's record, not its corners
//   (docs/compute-rasterizer.md, "The mask's lookups").
// - In a shadow view, whose key nothing reads, and in the views of several draws, whose ties
//   passes compare depths within the tie tolerance (raster.comp, TIES), the depth (0..1) of
//   the triangle's plane stepped from its box's first pixel: a non-negative float orders as
//   its bits.

// Each half of a word where no triangle covers the pixel: EMPTY_HALF (contract.glsl).
#include "contract.glsl"

// Where a pixel's word is among a view's words, `stride` pixels a row.
uint word_index(uint stride, ivec2 pixel) {
    return uint(pixel.y) * stride + uint(pixel.x);
}

// What turns a float's bits into its key (z_key), and a key back into the bits (z_of_key).
uint z_key_flip(uint bits) {
    return (bits & 0x80000000u) != 0u ? bits : ~bits & 0x7fffffffu;
}

// A z's key: smaller for the nearer (larger z), one key a z, every bit of it kept. A float's
// bits order as its magnitude; a negative one's, reversed. +0 counts as nearer than −0, which
// matters only to planes exactly coincident at a pixel. (A word is empty by its triangle half,
// whatever its key.)
uint z_key(float z) {
    return z_key_flip(floatBitsToUint(z));
}

// The z whose key z_key gave: the flip undoes itself.
float z_of_key(uint key) {
    return uintBitsToFloat(z_key_flip(key));
}
