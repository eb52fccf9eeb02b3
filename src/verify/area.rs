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

    #[test]
    fn a_plane_tilted_45_degrees_has_sqrt_2_times_the_area() {
        // z rises by dx per column: the plane z = x, whose area is √2 × its footprint.
        let (dx, dy) = (0.5f32, 0.5f32);
        let units = block_area_units(0.0, 0.5, 0.0, 0.5, dx, dy, unit_scale(dx, dy));
        let area = units_to_area(units.iter().map(|&u| u64::from(u)).sum(), 0.5, 0.5);
        assert!((area - 0.25 * 2f64.sqrt()).abs() < 1e-5, "{area}");
    }
}
