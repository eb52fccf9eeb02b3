// A mesh's triangle records (draw.glsl, TriangleRecord in src/render/gpu_mesh.rs) read in
// 64-bit words, for the compute rasterizer's shaders, which have 64-bit integers: a software
// rasterizer loads each word of a read through a device address on its own, invocation by
// invocation, so a record's twelve floats take six loads here instead of twelve. The bits are
// those mesh_corner and mesh_normal read, and range_pixel_of does the same arithmetic on them
// as range_pixel, so both rasterizers still write the same bits.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer TriangleWords {
    uint64_t word[];
};

// Floats 2k and 2k + 1 of triangle t's record.
vec2 record_floats(DrawData d, uint t, uint k) {
    return uintBitsToFloat(unpackUint2x32(TriangleWords(d.triangles).word[TRIANGLE_FLOATS / 2u * t + k]));
}

// A triangle's unit normal as the mesh stores it (model frame): floats 9–11.
vec3 mesh_normal_by_words(DrawData d, uint t) {
    vec2 a = record_floats(d, t, 4u), b = record_floats(d, t, 5u);
    return vec3(a.y, b);
}

// A triangle's corners as the mesh stores them (model frame): floats 0–8.
void mesh_corners_by_words(DrawData d, uint t, out vec3 corner[3]) {
    vec2 f0 = record_floats(d, t, 0u), f1 = record_floats(d, t, 1u), f2 = record_floats(d, t, 2u);
    vec2 f3 = record_floats(d, t, 3u), f4 = record_floats(d, t, 4u);
    corner[0] = vec3(f0, f1.x);
    corner[1] = vec3(f1.y, f2);
    corner[2] = vec3(f3, f4.x);
}

// range_pixel, reading the record in words.
RangePixel range_pixel_by_words(DrawData d, uint t, vec2 pixel) {
    vec2 f0 = record_floats(d, t, 0u), f1 = record_floats(d, t, 1u);
    return range_pixel_of(d, vec3(f0, f1.x), mesh_normal_by_words(d, t), triangle_label(d, t), pixel);
}
