// One posed mesh in one view: what the raster shaders get as push constants and what the
// shadow mask reads back from the draw table (src/render/raster/draw.rs, DrawConstants: 128 bytes,
// std430 either way), and what the compute rasterizer's coverage passes read as a uniform
// block (std140: the same offsets, as DrawData has no vec3 and no array of scalars or vec2;
// draw.rs asserts them). Also the one way any shader reaches a mesh's triangles.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#include "contract.glsl"
#include "../common/view.glsl"

struct DrawData {
    vec4 view_from_model[3]; // rows of view rotation ∘ pose, composed in f64 on the host
    vec4 grid;               // x0, y0, dx, dy: the view's pixel (0, 0) centre and pitch
    vec2 size;               // width, height in pixels
    vec2 z_range;            // z_min, z_max mapped onto depth 1..0 (larger z is closer)
    uvec2 triangles;         // device address of the mesh's triangles (TriangleRecord:
                             // corners, then the unit normal, model frame, f64-derived)
    float viewport_half_side; // the graphics pipeline's viewport (draw.rs, ViewportFrame):
    float viewport_inverse_half_side; // half its side (a power of two), its inverse,
    uvec2 surface_ids;       // device address of the mesh's per-triangle surface ids
    vec2 viewport_centre;    // the viewport's centre in window coordinates (whole pixels)
    uint label_base;         // label = label_base + surface id
    uint draw_index;         // this draw's entry in the draw table (shadow view)
    uvec2 links;             // device address of what lies across each triangle's edges
};

layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer Words {
    uint word[];
};

// The rotation of row `r` applied to `v`, in this order and unfused (`precise`): the functions
// here run in the vertex and fragment shaders of the graphics pipeline and in the compute
// rasterizer's shaders, which must compute the same bits, and a GPU may otherwise fuse
// multiply-adds differently in each stage (or order a dot product's terms as it likes).
float rotate_row(vec4 r, vec3 v) {
    precise float rotated = r.x * v.x + r.y * v.y + r.z * v.z;
    return rotated;
}

vec3 to_view(DrawData d, vec3 model) {
    precise vec3 v = vec3(rotate_row(d.view_from_model[0], model) + d.view_from_model[0].w,
                          rotate_row(d.view_from_model[1], model) + d.view_from_model[1].w,
                          rotate_row(d.view_from_model[2], model) + d.view_from_model[2].w);
    return v;
}

// Clip coordinates (w = 1) of a view-frame point: what raster.vert hands the graphics
// pipeline, and what the compute rasterizer's coverage passes turn into window coordinates as
// the viewport transform does (raster.comp, `window`). The viewport is 2 ×
// viewport_half_side pixels a side, a power of two, so multiplying by its inverse here and
// the viewport transform's multiplying by it again are exact (a product is correctly rounded
// in Vulkan, a quotient need not be): the window coordinates are the same bits whether a
// device fuses the transform's multiply-add or not.
vec3 clip_position(DrawData d, vec3 v) {
    precise vec2 pixel = orthographic_pixel(d.grid, v.xy) + 0.5;
    precise vec2 xy = (pixel - d.viewport_centre) * d.viewport_inverse_half_side;
    precise float depth = (d.z_range.y - v.z) / (d.z_range.y - d.z_range.x);
    return vec3(xy, depth);
}

// The rotation part alone: directions (normals) do not translate.
vec3 rotate_to_view(DrawData d, vec3 direction) {
    return vec3(rotate_row(d.view_from_model[0], direction), rotate_row(d.view_from_model[1], direction),
                rotate_row(d.view_from_model[2], direction));
}

// A plane's depth (0..1) change a column right and a row down, `n` its unit normal in the
// view's frame (n.z ≠ 0): the compute rasterizer steps its depths by it (raster.comp), and
// the tie tolerance grows with it (tie_depth).
vec2 depth_step(DrawData d, vec3 n) {
    precise vec2 step = vec2(n.x * d.grid.z, -n.y * d.grid.w) / (n.z * (d.z_range.y - d.z_range.x));
    return step;
}

// Depths (0..1) within this of the nearest at a pixel are a tie, decided for the lower label
// (src/render/raster/draw.rs), for a fragment of a triangle whose depth steps by `step` (depth_step).
// Coincident faces of two objects part by two roundings, which must not pick the winner:
// - their poses': a few f32 ulps of the view's largest coordinate (TIE_RELATIVE of it);
// - their depths': a GPU may work a triangle's depth out from its corners snapped to the
//   sub-pixel grid (NVIDIA's does; lavapipe and the compute rasterizer from the unsnapped
//   corners), which moves it by up to the depth change over half a snapping step (1/512
//   pixel) each way, so two faces part by up to that over 1/256 pixel: TIE_SLOPE allows
//   twice that. (With TIE_RELATIVE alone, two leaning boxes' coincident tops go in part to the
//   higher label on a GPU whose depths come from snapped corners.)
// The slope counted is at most, in each axis, a face's at 89° from the view (TIE_STEEPEST, tan
// 89°; θ has that limit too, src/sensor/scanner.rs): a sliver of a face seen almost edge-on, whose
// slope has no bound, would otherwise tie with, and so win through, any surface in front of
// it (a NaN slope, of a face seen exactly edge-on, counts as the cap). Coincident faces
// steeper than that may go to the higher label where a GPU's depths come from snapped corners.
const float TIE_SLOPE = 1.0 / 128.0;
const float TIE_STEEPEST = 57.29;
float tie_depth(DrawData d, vec2 step) {
    float span = d.z_range.y - d.z_range.x;
    vec2 far_corner = d.grid.xy + vec2(1.0, -1.0) * (d.size - 1.0) * d.grid.zw;
    vec2 xy = max(abs(d.grid.xy), abs(far_corner));
    float scale = max(max(xy.x, xy.y), max(abs(d.z_range.x), abs(d.z_range.y)));
    precise vec2 steepest = TIE_STEEPEST * d.grid.zw / span;
    vec2 slope = mix(steepest, abs(step), lessThan(abs(step), steepest));
    precise float tie = TIE_RELATIVE * scale / span + TIE_SLOPE * (slope.x + slope.y);
    return tie;
}

// A triangle as the mesh stores it (model frame); matches TriangleRecord in
// src/render/gpu_mesh.rs (48 bytes). Indexed as a record, its address is worked out in 64
// bits, whatever the mesh's size.
struct TriangleRecord {
    float corner[9]; // xyz of each corner
    float normal[3]; // the unit normal
};
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer TriangleRecords {
    TriangleRecord record[];
};

// Corner k (0, 1, 2) of a triangle as the mesh stores it (model frame).
vec3 mesh_corner(DrawData d, uint triangle, uint k) {
    TriangleRecords p = TriangleRecords(d.triangles);
    return vec3(p.record[triangle].corner[3u * k], p.record[triangle].corner[3u * k + 1u],
                p.record[triangle].corner[3u * k + 2u]);
}

// A triangle's unit normal as the mesh stores it (model frame).
vec3 mesh_normal(DrawData d, uint triangle) {
    TriangleRecords p = TriangleRecords(d.triangles);
    return vec3(p.record[triangle].normal[0], p.record[triangle].normal[1], p.record[triangle].normal[2]);
}

// Corner k (0, 1, 2) of a triangle, in the view's frame.
vec3 triangle_corner(DrawData d, uint triangle, uint k) {
    return to_view(d, mesh_corner(d, triangle, k));
}

// A triangle's unit normal in the view's frame.
vec3 triangle_normal(DrawData d, uint triangle) {
    return rotate_to_view(d, mesh_normal(d, triangle));
}

// The view-frame z at the centre of pixel (c, r), given as floats, of the plane through
// corner a with unit normal n, in a view whose pixels lie on `grid` (DrawData.grid): for the
// range view (range_pixel), and the compute rasterizer's depths and z keys (raster.comp).
float plane_z(vec4 grid, vec3 a, vec3 n, vec2 pixel) {
    precise vec2 centre = orthographic_centre(grid, pixel);
    precise float z = a.z - (n.x * (centre.x - a.x) + n.y * (centre.y - a.y)) / n.z;
    return z;
}

// The gradient (∂z/∂x, ∂z/∂y) of a plane whose unit normal in the view's frame is n.
vec2 plane_gradient(vec3 n) {
    return vec2(-n.x / n.z, -n.y / n.z);
}

// What lies across edge k (corners k, k + 1) of a triangle: NO_NEIGHBOUR, or a link that
// shaders/stages/shadow_mask.comp decodes (src/mesh/adjacency.rs, Mesh::edge_links).
uint triangle_link(DrawData d, uint triangle, uint k) {
    return Words(d.links).word[3u * triangle + k];
}

uint triangle_label(DrawData d, uint triangle) {
    return d.label_base + Words(d.surface_ids).word[triangle];
}

// What the range view holds at a pixel: its label (0: nothing), z and the plane's gradient
// (∂z/∂x, ∂z/∂y).
struct RangePixel {
    uint label;
    float z;
    vec2 gradient;
};

// The range view at pixel (c, r), given as floats, of a triangle with this first corner and
// unit normal (model frame, as the mesh stores them) and label: see range_pixel.
RangePixel range_pixel_of(DrawData d, vec3 corner, vec3 normal, uint label, vec2 pixel) {
    vec3 n = rotate_to_view(d, normal);
    return RangePixel(label, plane_z(d.grid, to_view(d, corner), n, pixel), plane_gradient(n));
}

// The range view at pixel (c, r), given as floats, that triangle t of draw d covers: its label, and the view-frame z
// and gradient of the triangle's plane at the exact pixel centre rather than interpolated
// (interpolation error grows with a facet's slope, the plane does not). The plane's normal is
// the triangle's unit normal, computed once in f64 on the host (src/render/gpu_mesh.rs): a
// cross product of a sliver's nearly parallel edges here, in f32, would lose most of its
// digits. The one definition for the graphics path (raster.frag) and the compute rasterizer
// (through triangle_words.glsl), so that both write the same bits: for a view of one draw the
// coverage pass works z out with plane_z as range_pixel_of does (raster.comp, keep), and the
// resolve reads it from the word; for several draws the resolve works it out here.
RangePixel range_pixel(DrawData d, uint t, vec2 pixel) {
    return range_pixel_of(d, mesh_corner(d, t, 0u), mesh_normal(d, t), triangle_label(d, t), pixel);
}

// A pinhole view (src/render/pinhole/): DrawData.grid holds fx, fy, cx, cy of the image it
// draws (cy counted from the top of the attachment, its band's first row added:
// pinhole/witness_set.rs), and
// z_range two constants of its depth, s and s / far, so that a point at depth Z (along the
// optical axis; x right, y down, z forward) has depth s / Z − s / far: 1 at the near plane
// Z = s, 0 at Z = far, larger nearer (its pipelines keep the greater depth). A triangle's
// 1 / Z is affine over its image, so the rasterizer's interpolation of depth is exact; w = Z
// has the clipper cut what lies nearer than s or beyond far.
vec4 pinhole_clip_position(DrawData d, vec3 v) {
    precise vec2 xy = (d.grid.xy * v.xy + (d.grid.zw + 0.5 - d.viewport_centre) * v.z) * d.viewport_inverse_half_side;
    precise float depth = d.z_range.x - d.z_range.y * v.z;
    return vec4(xy, depth, v.z);
}

// What a pinhole view holds at pixel (c, r), given as floats, that triangle t of draw d
// covers: its label, the depth Z where the pixel's ray meets the triangle's plane (n · p =
// n · a), and the gradient (∂Z/∂X, ∂Z/∂Y) of the plane in the view's frame, as exact ray
// casting stores them (src/exact/rig.rs): ±1e30 at most, 0 where indeterminate.
RangePixel pinhole_range_pixel(DrawData d, uint t, vec2 pixel) {
    vec3 n = triangle_normal(d, t);
    vec3 a = triangle_corner(d, t, 0u);
    vec3 ray = pinhole_ray(d.grid, pixel);
    precise float z = (n.x * a.x + n.y * a.y + n.z * a.z) / (n.x * ray.x + n.y * ray.y + n.z * ray.z);
    // NaN first: clamp's result for NaN is undefined (a GPU's min and max may return either).
    vec2 gradient = plane_gradient(n);
    gradient = clamp(mix(gradient, vec2(0.0), isnan(gradient)), vec2(-1e30), vec2(1e30));
    return RangePixel(triangle_label(d, t), z, gradient);
}

// pinhole_tie_depth (below) of a triangle whose unit normal in the view's frame is n, in a
// view of these intrinsics and constant term s / far of its depths: the one definition for
// the graphics path's ties pass (raster.frag) and the compute rasterizer's (raster.comp).
float pinhole_tie_depth_of(vec4 intrinsics, float s_over_far, vec3 n, vec2 pixel, float depth) {
    vec3 ray = pinhole_ray(intrinsics, pixel);
    float across = abs(n.x * ray.x + n.y * ray.y + n.z * ray.z);
    vec2 steepest = TIE_STEEPEST / intrinsics.xy;
    vec2 slope = abs(n.xy) / (intrinsics.xy * across);
    slope = mix(steepest, slope, lessThan(slope, steepest));
    float largest = max(1.0, max(abs(ray.x), abs(ray.y)));
    // s / Z itself: the depth less its constant term s / far.
    precise float tie = (depth + s_over_far) * (TIE_RELATIVE * largest + TIE_SLOPE * (slope.x + slope.y));
    return tie;
}

// tie_depth's allowance for a pinhole view, at a fragment of depth `depth` of triangle t
// through pixel (c, r): the same two roundings, relative to the depth s / Z, which moves by
// δZ / Z of itself. Poses round by TIE_RELATIVE of the view's largest coordinate, Z times the
// ray's largest component (or Z itself); a snapped corner moves the plane's 1 / Z by its
// change over 1/256 pixel, n_x / (f_x · n · ray) of itself a column (TIE_SLOPE, capped at a
// face 89° from the ray: TIE_STEEPEST / f).
float pinhole_tie_depth(DrawData d, uint t, vec2 pixel, float depth) {
    return pinhole_tie_depth_of(d.grid, d.z_range.y, triangle_normal(d, t), pixel, depth);
}
