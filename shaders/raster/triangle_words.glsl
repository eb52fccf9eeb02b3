// A mesh's triangle records (draw.glsl, TriangleRecord in src/render/gpu_mesh.rs) read in
// 64-bit words, for the compute rasterizer's shaders, which have 64-bit integers: a software
// rasterizer loads each word of a read through a device address on its own, invocation by
// invocation, so a record's twelve floats take six loads here instead of twelve. The bits are
// those mesh_corner and mesh_normal read, and range_pixel_of does the same arithmetic on them
// as range_pixel (and raster.comp's keep on the z it keeps in a word), so both rasterizers
// still write the same bits.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

// A TriangleRecord's 48 bytes as six words of two floats each, the lower float in the low half.
struct TriangleRecordWords {
    uint64_t word[6];
};
layout(buffer_reference, std430, buffer_reference_align = 8) readonly buffer TriangleWords {
    TriangleRecordWords record[];
};

// Floats 2k and 2k + 1 of triangle t's record.
vec2 record_floats(DrawData d, uint t, uint k) {
    return uintBitsToFloat(unpackUint2x32(TriangleWords(d.triangles).record[t].word[k]));
}

// A triangle's unit normal as the mesh stores it (model frame, floats 9–11), and its third
// corner's z (float 8), which comes in the same word.
vec3 mesh_normal_by_words(DrawData d, uint t, out float third_z) {
    vec2 a = record_floats(d, t, 4u), b = record_floats(d, t, 5u);
    third_z = a.x;
    return vec3(a.y, b);
}

// A triangle's corners as the mesh stores them (model frame, floats 0–8), the third's z as
// mesh_normal_by_words read it.
void mesh_corners_by_words(DrawData d, uint t, float third_z, out vec3 corner[3]) {
    vec2 f0 = record_floats(d, t, 0u), f1 = record_floats(d, t, 1u), f2 = record_floats(d, t, 2u);
    vec2 f3 = record_floats(d, t, 3u);
    corner[0] = vec3(f0, f1.x);
    corner[1] = vec3(f1.y, f2);
    corner[2] = vec3(f3, third_z);
}

// Corner k (0, 1, 2) of a triangle as the mesh stores it (floats 3k to 3k + 2), in two word
// reads where mesh_corner makes three.
vec3 mesh_corner_by_words(DrawData d, uint t, uint k) {
    uint first = 3u * k;
    vec2 low = record_floats(d, t, first >> 1u), high = record_floats(d, t, (first >> 1u) + 1u);
    return (first & 1u) == 0u ? vec3(low, high.x) : vec3(low.y, high);
}

// range_pixel, reading the record in words.
RangePixel range_pixel_by_words(DrawData d, uint t, vec2 pixel) {
    vec2 f0 = record_floats(d, t, 0u), f1 = record_floats(d, t, 1u);
    float third_z;
    vec3 normal = mesh_normal_by_words(d, t, third_z);
    return range_pixel_of(d, vec3(f0, f1.x), normal, triangle_label(d, t), pixel);
}

// range_pixel where the pixel's word already holds the plane's z there (z_of_key,
// visibility_word.glsl): the triangle's label, that z, and, where `with_gradient`, its plane's
// gradient (else zero), which is all that is left to read of its record: its normal. Where
// it reads the normal, `normal_z` is its z in the view's frame (else 0).
RangePixel range_pixel_at_z(DrawData d, uint t, float z, bool with_gradient, out float normal_z) {
    vec2 gradient = vec2(0.0);
    normal_z = 0.0;
    if (with_gradient) {
        float third_z;
        vec3 n = rotate_to_view(d, mesh_normal_by_words(d, t, third_z));
        gradient = plane_gradient(n);
        normal_z = n.z;
    }
    return RangePixel(triangle_label(d, t), z, gradient);
}

RangePixel range_pixel_at_z(DrawData d, uint t, float z, bool with_gradient) {
    float normal_z;
    return range_pixel_at_z(d, t, z, with_gradient, normal_z);
}
