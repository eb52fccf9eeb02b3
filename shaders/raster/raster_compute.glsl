// What the compute rasterizer's passes share (src/render/raster/compute/): each view's
// visibility words (visibility_word.glsl), one buffer a view, and how they are addressed.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "draw.glsl"
#include "triangle_words.glsl"
#include "visibility_word.glsl"

// One view as the passes see it; matches `RasterView` in src/render/raster/compute/.
struct RasterView {
    uvec4 area;        // the pixels to draw: first column, first row, width, height
    uint draw;         // the draw's entry in the view's draw table (the coverage passes
                       // read that entry as the host wrote it into their uniform block;
                       // raster.comp)
    uint stride;       // pixels per row of the view's words (the attachments' width)
    uint pad0, pad1;
};

// A member's place lies above a triangle's index from bit MEMBER_SHIFT (contract.glsl): in the
// queue of large triangles, and in the words of a view of several draws, which tag each
// triangle with its draw's place (raster.comp).

// The triangle's index in a tagged triangle or a queue entry: the bits below MEMBER_SHIFT.
uint untagged(uint tagged) {
    return tagged & ((1u << MEMBER_SHIFT) - 1u);
}

// No triangle at this pixel.
const uint64_t EMPTY = (uint64_t(EMPTY_HALF) << 32) | uint64_t(EMPTY_HALF);
