#version 460
// The compute rasterizer's coverage pass (src/render/compute_raster.rs): one invocation per
// triangle of one draw. Corners go to window coordinates as raster.vert and the viewport
// transform put them, are snapped to 1/256 pixel (lavapipe's sub-pixel precision), and a
// pixel is covered when its centre is inside every edge, or on a top or left edge (the
// top-left rule, framebuffer y down), in exact 64-bit integer arithmetic. Each covered pixel
// keeps the nearest triangle by atomicMin on its visibility word.
layout(local_size_x = 64) in;
#define FIRST_BUFFER 0
#include "raster_compute.glsl"

// Window coordinates of a view-frame point, operation for operation as raster.vert and the
// viewport transform compute them.
vec3 window(DrawData d, vec3 v) {
    precise vec2 pixel = vec2((v.x - d.grid.x) / d.grid.z, (d.grid.y - v.y) / d.grid.w) + 0.5;
    precise vec2 ndc = 2.0 * pixel / d.size - 1.0;
    precise vec2 w = ndc * (0.5 * d.size) + 0.5 * d.size;
    precise float depth = (d.z_range.y - v.z) / (d.z_range.y - d.z_range.x);
    return vec3(w, depth);
}

i64vec2 snap(vec2 w) {
    return i64vec2(roundEven(w * 256.0));
}

// Twice the signed area of (a, b, p), in 1/256² pixel units.
int64_t edge(i64vec2 a, i64vec2 b, i64vec2 p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Whether a point on edge a → b (interior on its positive side) is covered: the edge is a top
// edge (horizontal, interior below) or a left edge (interior to its right).
bool top_left(i64vec2 a, i64vec2 b) {
    i64vec2 e = b - a;
    return e.y < 0 || (e.y == 0 && e.x > 0);
}

void main() {
    // Dispatched as up to 65,535 workgroups per row (src/render/compute_raster.rs).
    uint t = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (t >= r.triangles) {
        return;
    }
    DrawData d = draws[r.draw];
    precise vec3 v0 = window(d, triangle_corner(d, t, 0u));
    precise vec3 v1 = window(d, triangle_corner(d, t, 1u));
    precise vec3 v2 = window(d, triangle_corner(d, t, 2u));
    i64vec2 a = snap(v0.xy), b = snap(v1.xy), c = snap(v2.xy);
    int64_t area = edge(a, b, c);
    if (area == 0) {
        return;
    }
    if (area < 0) {
        i64vec2 swap = b;
        b = c;
        c = swap;
    }
    bool ab = top_left(a, b), bc = top_left(b, c), ca = top_left(c, a);
    // Pixel centres (col + ½, row + ½) inside the bounding box and the area.
    vec2 lo = min(min(v0.xy, v1.xy), v2.xy), hi = max(max(v0.xy, v1.xy), v2.xy);
    ivec2 first = max(ivec2(floor(lo - 0.5)), ivec2(r.area.xy));
    ivec2 last = min(ivec2(ceil(hi - 0.5)), ivec2(r.area.xy + r.area.zw) - 1);
    for (int row = first.y; row <= last.y; row++) {
        for (int col = first.x; col <= last.x; col++) {
            i64vec2 p = i64vec2(col, row) * 256 + 128;
            int64_t e0 = edge(b, c, p), e1 = edge(c, a, p), e2 = edge(a, b, p);
            bool inside = (e0 > 0 || (e0 == 0 && bc)) && (e1 > 0 || (e1 == 0 && ca)) && (e2 > 0 || (e2 == 0 && ab));
            if (!inside) {
                continue;
            }
            ivec2 pixel = ivec2(col, row);
            float z = plane_z(d, t, pixel);
            precise float depth = (d.z_range.y - z) / (d.z_range.y - d.z_range.x);
            // Clipped as the graphics pipeline clips, and the depth clear value 1 is never less.
            if (!(depth >= 0.0 && depth < 1.0)) {
                continue;
            }
            uint64_t word = (uint64_t(floatBitsToUint(depth)) << 32) | uint64_t(t);
            atomicMin(nearest[uint(row) * r.stride + uint(col)], word);
        }
    }
}
