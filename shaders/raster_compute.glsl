// What the compute rasterizer's passes share (src/render/compute_raster.rs): per-pixel
// visibility words, 64 bits each, one buffer a view: the depth's bits high (a non-negative
// float orders as its bits) and the triangle low, so an atomicMin keeps the nearest triangle,
// and among equal depths the first in the mesh, as the graphics pipeline's LESS depth test
// does.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "draw.glsl"

// One view as the passes see it; matches `RasterView` in src/render/compute_raster.rs.
struct RasterView {
    uvec4 area;        // the pixels to draw: first column, first row, width, height
    uint draw;         // the draw's entry in the view's draw table
    uint stride;       // pixels per row of the view's words (the attachments' width)
    uint pad0, pad1;
};

// No triangle at this pixel (the words are filled with ones before the raster pass).
const uint64_t EMPTY = 0xffffffffffffffffUL;

// Where a pixel's word is in its view's buffer.
uint word_index(RasterView view, ivec2 pixel) {
    return uint(pixel.y) * view.stride + uint(pixel.x);
}

// The view-frame z at the centre of pixel (c, r) of the plane through corner a with unit
// normal n, as raster.frag computes it.
float plane_z(DrawData d, vec3 a, vec3 n, ivec2 pixel) {
    vec2 centre = vec2(d.grid.x + float(pixel.x) * d.grid.z, d.grid.y - float(pixel.y) * d.grid.w);
    return a.z - (n.x * (centre.x - a.x) + n.y * (centre.y - a.y)) / n.z;
}
