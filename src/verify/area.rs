//! Segment areas (paper §4, footnote 3): each 2×2 pixel block whose four labels agree adds the
//! 3D areas of its two triangles, (P00, P10, P11) and (P00, P11, P01), to that label.
//!
//! Areas must be deterministic whatever the batch order, so each triangle's area is rounded
//! once to a whole number of [`AREA_UNITS_PER_PIXEL`]ths of a pixel's area and summed as an
//! integer. The arithmetic is spelled out in f32 in a fixed order with no fused operations,
//! the same as `shaders/verify/score.comp` (which marks it `precise`): Vulkan rounds additions and
//! multiplications as IEEE 754 does, and the shader rounds its square root as IEEE does where
//! the device's may err (a GPU's; `sqrt_rounded`), so the host and the GPU get the same bits.
//! The sensed image's areas come from the same function, so identical images give a ratio of
//! exactly 1.

use crate::sensor::View;

/// Area quantum: a pixel's area (dx·dy) is this many units.
pub const AREA_UNITS_PER_PIXEL: f32 = 65536.0;
/// A triangle contributes at most this many units (a surface seen nearly edge-on, 65535× a
/// pixel's area per triangle): the largest f32 below 2^32.
pub const MAX_TRIANGLE_UNITS: f32 = 4_294_967_040.0;

/// Multiplier turning a triangle's doubled area (|cross product|) into units: ½ · units / (dx·dy).
pub fn unit_scale(dx: f32, dy: f32) -> f32 {
    0.5 * AREA_UNITS_PER_PIXEL / (dx * dy)
}

/// Units of the two triangles of the block with depths z00 (col c, row r), z10 (c+1, r),
/// z01 (c, r+1), z11 (c+1, r+1); x grows with the column by dx, y falls with the row by dy.
pub fn block_area_units(z00: f32, z10: f32, z01: f32, z11: f32, dx: f32, dy: f32, scale: f32) -> [u32; 2] {
    let a = z10 - z00;
    let b = z11 - z00;
    let c = z01 - z00;
    let dxdy = dx * dy;
    let flat = dxdy * dxdy;
    // (P10 − P00) × (P11 − P00) = (dy·a, dx·(a − b), −dx·dy)
    let p1 = dy * a;
    let q1 = dx * (a - b);
    let first = p1 * p1 + q1 * q1 + flat;
    // (P11 − P00) × (P01 − P00) = (dy·(b − c), −dx·c, −dx·dy)
    let p2 = dy * (b - c);
    let q2 = dx * c;
    let second = p2 * p2 + q2 * q2 + flat;
    [first, second].map(|s| (s.sqrt() * scale).min(MAX_TRIANGLE_UNITS) as u32)
}

/// A pinhole view's point of pixel (col, row) at depth z: z times its ray, with the inverse
/// focal lengths and principal point as the score pass reads them (f32).
fn pinhole_point(col: u32, row: u32, z: f32, inverse_focal: [f32; 2], principal: [f32; 2]) -> [f32; 3] {
    let ray = [(col as f32 - principal[0]) * inverse_focal[0], (row as f32 - principal[1]) * inverse_focal[1]];
    [z * ray[0], z * ray[1], z]
}

/// The squared length of a × b, in this order.
fn squared_cross(a: [f32; 3], b: [f32; 3]) -> f32 {
    let x = a[1] * b[2] - a[2] * b[1];
    let y = a[2] * b[0] - a[0] * b[2];
    let z = a[0] * b[1] - a[1] * b[0];
    x * x + y * y + z * z
}

/// Units of the two triangles of a pinhole view's block whose top-left pixel is (col, row),
/// with depths z00 (col, row), z10 (col + 1, row), z01 (col, row + 1), z11 (col + 1, row + 1):
/// the same triangles, (P00, P10, P11) and (P00, P11, P01), of the points the pixels' rays
/// meet at those depths.
pub fn pinhole_block_area_units(
    (col, row): (u32, u32),
    [z00, z10, z01, z11]: [f32; 4],
    (inverse_focal, principal): ([f32; 2], [f32; 2]),
    scale: f32,
) -> [u32; 2] {
    let point = |c, r, z| pinhole_point(c, r, z, inverse_focal, principal);
    let p00 = point(col, row, z00);
    let minus = |p: [f32; 3]| [p[0] - p00[0], p[1] - p00[1], p[2] - p00[2]];
    let e1 = minus(point(col + 1, row, z10));
    let e2 = minus(point(col + 1, row + 1, z11));
    let e3 = minus(point(col, row + 1, z01));
    [squared_cross(e1, e2), squared_cross(e2, e3)].map(|s| (s.sqrt() * scale).min(MAX_TRIANGLE_UNITS) as u32)
}

/// Where a view's pixels' rays run, as the score pass reads it (f32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BlockRays {
    /// Parallel, over a grid of this pitch.
    Orthographic { dx: f32, dy: f32 },
    /// Through the view's centre: 1/fx, 1/fy and cx, cy.
    Pinhole { inverse_focal: [f32; 2], principal: [f32; 2] },
}

/// How a view's 2×2 blocks turn depths into area: its rays, and the sides of the rectangle
/// whose area is [`AREA_UNITS_PER_PIXEL`] units. An orthographic view's is its pixel; a
/// pinhole view's pixel grows with depth, and its unit is a pixel's footprint at `unit_depth`
/// (verification takes the sensed image's farthest depth: src/verify/sensed.rs, so that no
/// block it holds is far above a unit). The scores take ratios of areas in one unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockGeometry {
    pub rays: BlockRays,
    pub sides: [f64; 2],
}

impl BlockGeometry {
    pub fn of(view: &View, unit_depth: f64) -> Self {
        match view {
            View::Orthographic(o) => {
                Self { rays: BlockRays::Orthographic { dx: o.pitch[0] as f32, dy: o.pitch[1] as f32 }, sides: o.pitch }
            }
            View::Pinhole(p) => {
                let k = &p.intrinsics;
                Self {
                    rays: BlockRays::Pinhole {
                        inverse_focal: [(1.0 / k.fx) as f32, (1.0 / k.fy) as f32],
                        principal: [k.cx as f32, k.cy as f32],
                    },
                    sides: [unit_depth / k.fx, unit_depth / k.fy],
                }
            }
        }
    }

    /// Multiplier turning a triangle's doubled area into units.
    pub fn scale(&self) -> f32 {
        unit_scale(self.sides[0] as f32, self.sides[1] as f32)
    }

    /// Units of the two triangles of the block whose top-left pixel is (col, row), its depths
    /// as [`pinhole_block_area_units`] takes them.
    pub fn block_units(&self, pixel: (u32, u32), z: [f32; 4]) -> [u32; 2] {
        let [z00, z10, z01, z11] = z;
        match self.rays {
            BlockRays::Orthographic { dx, dy } => block_area_units(z00, z10, z01, z11, dx, dy, self.scale()),
            BlockRays::Pinhole { inverse_focal, principal } => {
                pinhole_block_area_units(pixel, z, (inverse_focal, principal), self.scale())
            }
        }
    }

    /// Summed units back in model units².
    pub fn area(&self, units: u64) -> f64 {
        units_to_area(units, self.sides[0], self.sides[1])
    }
}

/// Converts summed units back to model units².
pub fn units_to_area(units: u64, dx: f64, dy: f64) -> f64 {
    units as f64 * dx * dy / f64::from(AREA_UNITS_PER_PIXEL)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_block_is_one_pixel_of_area() {
        let (dx, dy) = (0.02f32, 0.03f32);
        let units = block_area_units(1.0, 1.0, 1.0, 1.0, dx, dy, unit_scale(dx, dy));
        let total: u64 = units.iter().map(|&u| u64::from(u)).sum();
        assert!((units_to_area(total, 0.02, 0.03) - 0.02 * 0.03).abs() < 1e-9);
    }

    /// On the plane z = αx + βy, a block's two triangles each cover half a pixel's footprint
    /// times √(1 + α² + β²): worked out here in f64 for slopes along x, along y and both.
    #[test]
    fn each_triangle_of_a_block_on_a_sloped_plane_has_its_share_of_the_plane_s_area() {
        let (dx, dy) = (0.25f32, 0.5f32);
        for (alpha, beta) in [(0.5, 0.0), (0.0, -0.75), (0.5, -0.25), (-1.5, 2.0)] {
            // Row r + 1 lies dy lower in y.
            let (z00, z10, z01) = (1.0, 1.0 + alpha * dx, 1.0 - beta * dy);
            let z11 = 1.0 + alpha * dx - beta * dy;
            let units = block_area_units(z00, z10, z01, z11, dx, dy, unit_scale(dx, dy));
            let share = 0.5 * f64::from(AREA_UNITS_PER_PIXEL) * (1.0 + f64::from(alpha * alpha + beta * beta)).sqrt();
            for u in units {
                assert!((f64::from(u) - share).abs() <= 1.0, "α {alpha}, β {beta}: {u} units, expected {share}");
            }
        }
    }

    /// A pinhole view facing a plane at depth Z sees, in each block, a Z/fx × Z/fy rectangle:
    /// with the unit at depth Z that is one unit of a pixel, half in each triangle; at depth
    /// 2Z, four. On a plane tilted 60° about the y axis (depth growing by tan 60° × x) a
    /// block's area is its corner points' two triangles', worked out here in f64.
    #[test]
    fn a_pinhole_block_has_the_area_of_its_points_rectangle() {
        let (fx, fy, cx, cy) = (500.0, 400.0, 3.5, 2.5);
        let intrinsics = crate::sensor::Intrinsics { width: 8, height: 6, fx, fy, cx, cy };
        let view = View::Pinhole(crate::sensor::Pinhole { intrinsics, near: 0.0, far: f64::INFINITY });
        let blocks = BlockGeometry::of(&view, 2.0);
        let units = |z: [f32; 4]| blocks.block_units((3, 2), z).iter().map(|&u| u64::from(u)).sum::<u64>();
        let half = f64::from(AREA_UNITS_PER_PIXEL) / 2.0;
        assert!((units([2.0; 4]) as f64 - 2.0 * half).abs() <= 2.0);
        assert!((units([4.0; 4]) as f64 - 8.0 * half).abs() <= 8.0);
        assert!((blocks.area(units([2.0; 4])) - 2.0 / fx * 2.0 / fy).abs() < 1e-9);
        // z = 2 + tan 60° · x, and x = z · (col − cx)/fx: z = 2 / (1 − tan 60° · (col − cx)/fx).
        let t = 3f64.sqrt();
        let depth = |col: u32| 2.0 / (1.0 - t * (f64::from(col) - cx) / fx);
        let z = [depth(3), depth(4), depth(3), depth(4)];
        let point = |col: u32, row: u32, z: f64| [z * (f64::from(col) - cx) / fx, z * (f64::from(row) - cy) / fy, z];
        let (p00, p10, p11, p01) = (point(3, 2, z[0]), point(4, 2, z[1]), point(4, 3, z[3]), point(3, 3, z[2]));
        let cross = |a: [f64; 3], b: [f64; 3], o: [f64; 3]| {
            let (a, b) = (glam::DVec3::from(a) - glam::DVec3::from(o), glam::DVec3::from(b) - glam::DVec3::from(o));
            a.cross(b).length() / 2.0
        };
        let expected = cross(p10, p11, p00) + cross(p11, p01, p00);
        let area = blocks.area(units(z.map(|z| z as f32)));
        assert!((area / expected - 1.0).abs() < 1e-4, "{area} against {expected}");
    }

    #[test]
    fn a_plane_tilted_45_degrees_has_sqrt_2_times_the_area() {
        // z rises by dx per column: the plane z = x, whose area is √2 × its footprint.
        let (dx, dy) = (0.5f32, 0.5f32);
        let units = block_area_units(0.0, 0.5, 0.0, 0.5, dx, dy, unit_scale(dx, dy));
        let area = units_to_area(units.iter().map(|&u| u64::from(u)).sum(), 0.5, 0.5);
        assert!((area - 0.25 * 2f64.sqrt()).abs() < 1e-5, "{area}");
    }
}
