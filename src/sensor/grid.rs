//! A rendered view's pixel grid as the GPU path holds it (orthographic, looking down −z), and
//! the depth bounds of a set of spheres along its z.

use glam::DVec3;

/// One rendered view: an orthographic grid looking down −z, and the depth range mapped onto
/// the depth buffer (larger z is closer, so it maps to smaller depth; shaders/raster/raster.vert).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewGrid {
    pub origin: [f64; 2],
    pub pitch: [f64; 2],
    pub width: u32,
    pub height: u32,
    pub z_range: (f64, f64),
}

/// A rectangle of pixels: columns `col..col + width`, rows `row..row + height`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelRect {
    pub col: u32,
    pub row: u32,
    pub width: u32,
    pub height: u32,
}

impl PixelRect {
    /// No pixels.
    pub const EMPTY: PixelRect = PixelRect { col: 0, row: 0, width: 0, height: 0 };

    /// How many pixels it holds.
    pub fn pixels(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height)
    }

    /// Whether pixel (col, row) lies in the rectangle.
    pub fn contains(&self, col: u32, row: u32) -> bool {
        col.wrapping_sub(self.col) < self.width && row.wrapping_sub(self.row) < self.height
    }

    /// The least rectangle holding both (an empty one holds no pixel).
    pub fn union(self, other: PixelRect) -> PixelRect {
        let empty = |r: &PixelRect| r.width == 0 || r.height == 0;
        match (empty(&self), empty(&other)) {
            (true, _) => other,
            (_, true) => self,
            _ => {
                let (col, row) = (self.col.min(other.col), self.row.min(other.row));
                let end = |a: u32, n: u32, b: u32, m: u32| (a + n).max(b + m);
                let width = end(self.col, self.width, other.col, other.width) - col;
                let height = end(self.row, self.height, other.row, other.height) - row;
                PixelRect { col, row, width, height }
            }
        }
    }
}

impl ViewGrid {
    /// Every pixel of the grid.
    pub fn full(&self) -> PixelRect {
        PixelRect { col: 0, row: 0, width: self.width, height: self.height }
    }

    /// The point (this view's frame) the GPU measures from, so that the same geometry keeps
    /// the same f32 precision wherever it sits: coordinates sent to shaders are offsets from
    /// it, composed in f64. It is the grid's centre snapped to a multiple of the power of two
    /// at least the view's extent, so a view near the frame's origin keeps the origin (and
    /// its images bit for bit), and it is exact in f32, so adding it back to an f32 offset is
    /// one correctly rounded f32 addition on the host or the GPU alike.
    pub fn local_origin(&self) -> DVec3 {
        let [x0, y0] = self.origin;
        let [dx, dy] = self.pitch;
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (z0, z1) = self.z_range;
        let centre = DVec3::new(x0 + (w - 1.0) / 2.0 * dx, y0 - (h - 1.0) / 2.0 * dy, (z0 + z1) / 2.0);
        let extent = (w * dx).max(h * dy).max(z1 - z0).max(f64::MIN_POSITIVE);
        let step = extent.log2().ceil().exp2();
        ((centre / step).round() * step).as_vec3().as_dvec3()
    }

    /// How far a sphere (centre in this view's frame) reaches from the grid's first pixel
    /// centre, in pixels along a row or a column, whichever is farther.
    pub fn reach(&self, centre: DVec3, radius: f64) -> f64 {
        let [x0, y0] = self.origin;
        let [dx, dy] = self.pitch;
        (((centre.x - x0).abs() + radius) / dx).max(((y0 - centre.y).abs() + radius) / dy)
    }

    /// The pixels whose centres may fall on a sphere's orthographic footprint (centre in this
    /// view's frame), grown by `margin` pixels on every side and clipped to the grid; `None`
    /// when it misses the grid.
    pub fn footprint(&self, centre: DVec3, radius: f64, margin: u32) -> Option<PixelRect> {
        let [x0, y0] = self.origin;
        let [dx, dy] = self.pitch;
        let m = f64::from(margin);
        let cols = (((centre.x - radius - x0) / dx).floor() - m, ((centre.x + radius - x0) / dx).ceil() + m);
        let rows = (((y0 - centre.y - radius) / dy).floor() - m, ((y0 - centre.y + radius) / dy).ceil() + m);
        let clip = |(lo, hi): (f64, f64), n: u32| {
            let (lo, hi) = (lo.max(0.0), hi.min(f64::from(n) - 1.0));
            (lo <= hi).then(|| (lo as u32, (hi - lo) as u32 + 1))
        };
        let ((col, width), (row, height)) = (clip(cols, self.width)?, clip(rows, self.height)?);
        Some(PixelRect { col, row, width, height })
    }
}

/// Depth bounds along z of spheres (centre, radius), widened by 1% and a small absolute
/// margin so nothing sits on the near or far plane. An empty set gives (−1, 1).
pub fn depth_bounds(spheres: impl IntoIterator<Item = (DVec3, f64)>) -> (f64, f64) {
    let (lo, hi) = spheres
        .into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (c, r)| (lo.min(c.z - r), hi.max(c.z + r)));
    if lo > hi {
        return (-1.0, 1.0);
    }
    let margin = depth_margin(lo, hi);
    (lo - margin, hi + margin)
}

/// How far a view's depth range reaches beyond the depths `lo`..`hi` of what it draws: 1% of
/// their span, and f32's rounding of coordinates far from the frame's origin.
pub fn depth_margin(lo: f64, hi: f64) -> f64 {
    0.01 * (hi - lo) + 1e-6 * (1.0 + lo.abs().max(hi.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A union holds both rectangles' pixels and no more than their bounding box; an empty one
    /// adds nothing; `contains` says which pixels a rectangle holds, edges included.
    #[test]
    fn a_union_is_the_bounding_box_of_its_rectangles() {
        let a = PixelRect { col: 2, row: 3, width: 4, height: 2 };
        let b = PixelRect { col: 5, row: 0, width: 3, height: 2 };
        assert_eq!(a.union(b), PixelRect { col: 2, row: 0, width: 6, height: 5 });
        assert_eq!(a.union(PixelRect::EMPTY), a);
        assert_eq!(PixelRect::EMPTY.union(b), b);
        let u = a.union(b);
        for (col, row) in [(2, 3), (5, 4), (5, 0), (7, 1)] {
            assert!(a.contains(col, row) || b.contains(col, row), "({col}, {row})");
            assert!(u.contains(col, row), "({col}, {row})");
        }
        assert!(!a.contains(6, 3) && !a.contains(1, 3) && !a.contains(2, 5) && !u.contains(8, 0));
        assert!(!PixelRect::EMPTY.contains(0, 0));
    }

    fn grid() -> ViewGrid {
        ViewGrid { origin: [0.0, 0.0], pitch: [0.1, 0.1], width: 100, height: 50, z_range: (-1.0, 1.0) }
    }

    #[test]
    fn a_local_origin_is_the_grids_centre_on_a_lattice_of_its_extent() {
        // Centre (1001.5, 1999.5, 11), extent 4 (the width): the multiples of 4 nearest.
        let far = ViewGrid { origin: [1000.0, 2000.0], pitch: [1.0, 1.0], width: 4, height: 2, z_range: (10.0, 12.0) };
        assert_eq!(far.local_origin(), DVec3::new(1000.0, 2000.0, 12.0));
        // A grid about the frame's origin keeps it.
        assert_eq!(grid().local_origin(), DVec3::ZERO);
        // Two rows of pitch 1 from y = 9.7: the centre's y, 9.2, is 4.6 steps of 2 (the
        // extent), nearer 10 than 8.
        let rows = ViewGrid { origin: [0.0, 9.7], pitch: [1.0, 1.0], width: 1, height: 2, z_range: (0.0, 1.0) };
        assert_eq!(rows.local_origin(), DVec3::new(0.0, 10.0, 0.0));
        // A pixel 20 deep: the depth is the extent (step 32), and the centre (5, 7, 20) is
        // nearest (0, 0, 32).
        let deep = ViewGrid { origin: [5.0, 7.0], pitch: [1.0, 1.0], width: 1, height: 1, z_range: (10.0, 30.0) };
        assert_eq!(deep.local_origin(), DVec3::new(0.0, 0.0, 32.0));
    }

    #[test]
    fn a_spheres_reach_counts_pixels_along_the_farther_axis() {
        // Centre (2, −1), radius 0.35, pitch 0.1: 23.5 columns, 13.5 rows from pixel (0, 0).
        assert!((grid().reach(DVec3::new(2.0, -1.0, 0.0), 0.35) - 23.5).abs() < 1e-9);
        assert!((grid().reach(DVec3::new(1.0, -3.0, 0.0), 0.35) - 33.5).abs() < 1e-9);
        // From a first pixel at (1, 2): 11.5 columns or 43.5 rows.
        let moved = ViewGrid { origin: [1.0, 2.0], ..grid() };
        assert!((moved.reach(DVec3::new(2.0, -2.0, 0.0), 0.35) - 43.5).abs() < 1e-9);
        assert!((moved.reach(DVec3::new(5.0, 1.0, 0.0), 0.35) - 43.5).abs() < 1e-9);
        assert!((moved.reach(DVec3::new(4.0, 1.5, 0.0), 0.35) - 33.5).abs() < 1e-9);
    }

    #[test]
    fn a_footprint_is_measured_from_the_grids_first_pixel() {
        // The first pixel at (1, 2): centre (3, 1) is pixel (20, 10), as (2, −1) is from (0, 0).
        let moved = ViewGrid { origin: [1.0, 2.0], ..grid() };
        let r = moved.footprint(DVec3::new(3.0, 1.0, 0.0), 0.35, 1).unwrap();
        assert_eq!(r, PixelRect { col: 15, row: 5, width: 11, height: 11 });
    }

    proptest::proptest! {
        /// Wherever a grid lies, its local origin is a multiple of the power of two at least
        /// its extent, within half of it of the grid's centre on every axis.
        #[test]
        fn a_local_origin_lies_on_its_lattice_beside_the_centre(
            x0 in -1e4f64..1e4, y0 in -1e4f64..1e4, z0 in -1e4f64..1e4,
            dx in 1e-3f64..1.0, dy in 1e-3f64..1.0, depth in 1e-3f64..10.0,
            width in 1u32..2000, height in 1u32..2000,
        ) {
            let g = ViewGrid { origin: [x0, y0], pitch: [dx, dy], width, height, z_range: (z0, z0 + depth) };
            let (w, h) = (f64::from(width), f64::from(height));
            let centre = DVec3::new(x0 + (w - 1.0) / 2.0 * dx, y0 - (h - 1.0) / 2.0 * dy, z0 + depth / 2.0);
            let step = (w * dx).max(h * dy).max(depth).log2().ceil().exp2();
            let local = g.local_origin();
            for axis in 0..3 {
                proptest::prop_assert_eq!((local[axis] / step).fract(), 0.0);
                proptest::prop_assert!((local[axis] - centre[axis]).abs() <= step / 2.0 + 1e-9 * step);
            }
        }
    }

    #[test]
    fn depth_bounds_widen_the_spheres_extent_by_its_hundredth_and_a_millionth() {
        // Depths 1 to 5.5: a margin of 0.045 and 6.5e-6.
        let (lo, hi) = depth_bounds([(DVec3::new(0.0, 0.0, 2.0), 1.0), (DVec3::new(3.0, 0.0, 5.0), 0.5)]);
        let margin = 0.045 + 1e-6 * 6.5;
        assert!((lo - 1.0 + margin).abs() < 1e-12 && (hi - 5.5 - margin).abs() < 1e-12, "({lo}, {hi})");
        // A point: the absolute margin alone.
        let (lo, hi) = depth_bounds([(DVec3::new(0.0, 0.0, 5.0), 0.0)]);
        assert!((lo - 5.0 + 6e-6).abs() < 1e-12 && (hi - 5.0 - 6e-6).abs() < 1e-12, "({lo}, {hi})");
        assert_eq!(depth_bounds([]), (-1.0, 1.0));
    }

    #[test]
    fn a_footprint_covers_the_sphere_with_its_margin() {
        // Centre (2, −1) is pixel (20, 10); radius 0.35 spans 3.5 pixels each way.
        let r = grid().footprint(DVec3::new(2.0, -1.0, 0.0), 0.35, 1).unwrap();
        assert_eq!(r, PixelRect { col: 15, row: 5, width: 11, height: 11 });
    }

    #[test]
    fn a_footprint_is_clipped_to_the_grid_or_absent() {
        let r = grid().footprint(DVec3::new(-0.05, 0.0, 0.0), 0.2, 1).unwrap();
        assert_eq!((r.col, r.row), (0, 0));
        assert_eq!(grid().footprint(DVec3::new(50.0, 0.0, 0.0), 1.0, 1), None);
        assert_eq!(grid().footprint(DVec3::new(5.0, 3.0, 0.0), 1.0, 1), None);
    }
}
