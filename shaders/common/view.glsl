// The views' geometry, one definition for every pass that projects (src/sensor/: View,
// ViewGrid, Intrinsics): the point of a pixel, the ray through it, and the pixel a point
// projects to. Pixel (c, r), given as floats, has its centre at image coordinates (c, r).
// - VIEW_ORTHOGRAPHIC: the view's `grid` is (x0, y0, dx, dy), pixel (0, 0)'s centre and the
//   pitch; x right, y up, looking down −z (larger z is nearer).
// - VIEW_PINHOLE: the view's `grid` is its intrinsics (fx, fy, cx, cy); x right, y down, z
//   forward, a pixel's points at depth Z (along the optical axis) Z times its ray.
// A new view kind is one more case in each function here and one arm of the Rust side's View.
// Each computation is `precise`: the graphics pipeline's stages, the compute rasterizer and the
// mask passes must compute the same bits.
#ifndef VIEW_GLSL
#define VIEW_GLSL
#include "contract.glsl"

// The centre of an orthographic view's pixel, in its frame's x and y.
vec2 orthographic_centre(vec4 grid, vec2 pixel) {
    precise vec2 centre = vec2(grid.x + pixel.x * grid.z, grid.y - pixel.y * grid.w);
    return centre;
}

// The pixel (as floats: centres at whole numbers) an orthographic view sees at x, y.
vec2 orthographic_pixel(vec4 grid, vec2 xy) {
    precise vec2 pixel = vec2((xy.x - grid.x) / grid.z, (grid.y - xy.y) / grid.w);
    return pixel;
}

// The ray through a pinhole view's pixel, scaled so that its z is 1.
vec3 pinhole_ray(vec4 intrinsics, vec2 pixel) {
    precise vec2 xy = (pixel - intrinsics.zw) / intrinsics.xy;
    return vec3(xy, 1.0);
}

// The pixel (as floats: centres at whole numbers) where a point q of a pinhole view's frame
// projects (q.z > 0).
vec2 pinhole_pixel(vec4 intrinsics, vec3 q) {
    precise vec2 uv = intrinsics.xy * q.xy / q.z + intrinsics.zw;
    return uv;
}

// The point, in the view's frame, on the ray of a pixel at z: the range frame's z of an
// orthographic view, the depth along the optical axis of a pinhole one (View::point).
vec3 view_point(uint kind, vec4 grid, vec2 pixel, float z) {
    if (kind == VIEW_PINHOLE) {
        precise vec3 p = z * pinhole_ray(grid, pixel);
        return p;
    }
    return vec3(orthographic_centre(grid, pixel), z);
}

#endif
