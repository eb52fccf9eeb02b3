// What the compute rasterizer's two passes share (src/render/compute_raster.rs): the view's
// draw table and its per-pixel visibility words, 64 bits each: the depth's bits high (a
// non-negative float orders as its bits) and the triangle low, so an atomicMin keeps the
// nearest triangle, and among equal depths the first in the mesh, as the graphics pipeline's
// LESS depth test does.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "draw.glsl"

// The buffers follow the pass's storage images (src/gpu/descriptors.rs binds images first):
// the including shader defines FIRST_BUFFER as the number of its images.
layout(set = 0, binding = FIRST_BUFFER, std430) readonly buffer DrawTable { DrawData draws[]; };
layout(set = 0, binding = FIRST_BUFFER + 1, std430) buffer Nearest { uint64_t nearest[]; };

layout(push_constant, std430) uniform Raster {
    uvec4 area;        // the pixels to draw: first column, first row, width, height
    uint draw;         // the draw's entry in the table
    uint stride;       // pixels per row of the visibility words (the attachments' width)
    uint triangles;    // the mesh's triangle count
    uint large_capacity; // room in the queue of large triangles (raster.comp)
    int cull;          // skip triangles whose view-frame normal z has the opposite sign; 0: none
} r;

// No triangle at this pixel (the words are filled with ones before the raster pass).
const uint64_t EMPTY = 0xffffffffffffffffUL;

// The view-frame z at the centre of pixel (c, r) of the plane through corner a with unit
// normal n, as raster.frag computes it.
float plane_z(DrawData d, vec3 a, vec3 n, ivec2 pixel) {
    vec2 centre = vec2(d.grid.x + float(pixel.x) * d.grid.z, d.grid.y - float(pixel.y) * d.grid.w);
    return a.z - (n.x * (centre.x - a.x) + n.y * (centre.y - a.y)) / n.z;
}
