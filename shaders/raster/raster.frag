#version 460
// Writes the surface label (u32 end to end, never through a float), and:
// - in the range view, the view-frame z of the nearest surface and its gradient (∂z/∂x,
//   ∂z/∂y), from the triangle's plane at the exact pixel centre (range_pixel, draw.glsl;
//   PINHOLE: pinhole_range_pixel, Z along the optical axis where the pixel's ray meets it).
// - in the shadow view (SHADOW_VIEW), which triangle of which draw is nearest: a visibility
//   buffer, from which the depth-mode shadow test intersects the camera ray with the actual
//   triangles (src/shadow.rs).
#include "draw.glsl"

layout(push_constant, std430) uniform Draw {
    DrawData draw;
};

#ifdef SHADOW_VIEW
layout(location = 0) out uvec4 visibility; // label, draw index, triangle, 0
#else
layout(location = 0) out uint label;
layout(location = 1) out float z;
layout(location = 2) out float dz_dx;
layout(location = 3) out float dz_dy;
#endif
#ifdef TIES
// Drawn after a depth-only pass, against its depths: every fragment within the tie tolerance
// of the nearest passes, and the last drawn (the lowest label) stays (src/render/raster/draw.rs).
// A pinhole view keeps the greater depth (draw.glsl, pinhole_clip_position).
#ifdef PINHOLE
layout(depth_greater) out float gl_FragDepth;
#else
layout(depth_less) out float gl_FragDepth;
#endif
#endif

void main() {
    uint t = uint(gl_PrimitiveID);
#ifdef SHADOW_VIEW
    visibility = uvec4(triangle_label(draw, t), draw.draw_index, t, 0u);
#else
    // A fragment exists only where the triangle covers area in the image: in an orthographic
    // view n.z ≠ 0 then (a pinhole view's gradient is kept finite: pinhole_range_pixel); its
    // coordinates are the pixel's centre, (col + ½, row + ½).
#ifdef PINHOLE
    RangePixel range = pinhole_range_pixel(draw, t, gl_FragCoord.xy - 0.5);
#else
    RangePixel range = range_pixel(draw, t, gl_FragCoord.xy - 0.5);
#endif
    label = range.label;
    z = range.z;
    dz_dx = range.gradient.x;
    dz_dy = range.gradient.y;
#endif
#if defined(TIES) && defined(PINHOLE)
    gl_FragDepth = min(gl_FragCoord.z + pinhole_tie_depth(draw, t, gl_FragCoord.xy - 0.5, gl_FragCoord.z), 1.0);
#elif defined(TIES)
    gl_FragDepth = max(gl_FragCoord.z - tie_depth(draw, depth_step(draw, triangle_normal(draw, t))), 0.0);
#endif
}
