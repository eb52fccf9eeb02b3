//! Which triangles lie over a point (x, y): the question both of exact mode's vertical casters
//! ask, once per ray (src/exact/mod.rs). A uniform grid over the triangles' xy bounds answers it
//! in a few steps: each cell lists the triangles whose bounds reach it, so a point's candidates
//! are the listed triangles of its cell whose closed bounds hold it. Those are exactly the
//! triangles a hierarchy over the same bounds would give, so the exact tests that follow see
//! the same set, whatever the grid's cells (a point's cell index and a bound's are the same
//! monotone function of x and y, so a bound that holds the point reaches its cell).
//!
//! A grid beats a hierarchy here because it is rebuilt for every hypothesis (the triangles
//! move with the pose): building it is one pass to count and one to fill, with no sorting.
//! It has about as many cells as triangles. Where large triangles would list themselves in
//! more than [`ENTRIES_PER_TRIANGLE`] cells each on average, the grid is made coarser until
//! they do not, which bounds its memory: each time along the axis the triangles span more
//! cells of, so that long thin triangles lying along one axis keep the other axis fine.

use glam::DVec2;

/// The most cell entries the grid holds per triangle, on average.
pub const ENTRIES_PER_TRIANGLE: u64 = 8;

/// Bytes the grid takes per triangle at most: its bounds, its cells' starts (at most two cells
/// a triangle, as `cells_for` rounds) and its entries.
pub const BYTES_PER_TRIANGLE: u64 = 32 + 2 * 8 + 4 * ENTRIES_PER_TRIANGLE;

pub(super) struct ColumnGrid {
    /// Each triangle's xy bounds: min x, min y, max x, max y.
    bounds: Vec<[f64; 4]>,
    cells: Cells,
    /// Where each cell's entries start in `entries`, and where the last ends.
    starts: Vec<usize>,
    /// Triangle indices, cell by cell, each cell's in ascending order.
    entries: Vec<u32>,
}

/// The grid's geometry: `columns` × `rows` cells over the bounds' union.
#[derive(Clone, Copy)]
struct Cells {
    origin: DVec2,
    per_unit: DVec2,
    columns: usize,
    rows: usize,
}

impl Cells {
    /// The cell column and row of (x, y), clamped to the grid: non-decreasing in x and y.
    fn of(&self, x: f64, y: f64) -> (usize, usize) {
        // `as usize` takes negative and NaN values to 0 and saturates above.
        let column = (((x - self.origin.x) * self.per_unit.x) as usize).min(self.columns - 1);
        let row = (((y - self.origin.y) * self.per_unit.y) as usize).min(self.rows - 1);
        (column, row)
    }

    /// The cells a bound reaches: columns and rows, inclusive.
    fn reached(&self, b: &[f64; 4]) -> ((usize, usize), (usize, usize)) {
        let (c0, r0) = self.of(b[0], b[1]);
        let (c1, r1) = self.of(b[2], b[3]);
        ((c0, c1), (r0, r1))
    }

    /// The entries the bounds take in this grid, and the columns and the rows they span.
    fn entries_of(&self, bounds: &[[f64; 4]]) -> (u64, u64, u64) {
        bounds.iter().fold((0, 0, 0), |(entries, columns, rows), b| {
            let ((c0, c1), (r0, r1)) = self.reached(b);
            let (across, down) = ((c1 - c0 + 1) as u64, (r1 - r0 + 1) as u64);
            (entries + across * down, columns + across, rows + down)
        })
    }

    /// This grid with half the columns (`along_x`) or half the rows, at least one; the other
    /// axis as it is, unless it has one cell already.
    fn coarser(self, along_x: bool) -> Self {
        let along_x = (along_x && self.columns > 1) || self.rows == 1;
        let (columns, rows) =
            if along_x { (self.columns.div_ceil(2), self.rows) } else { (self.columns, self.rows.div_ceil(2)) };
        let per_unit = DVec2::new(
            self.per_unit.x * columns as f64 / self.columns as f64,
            self.per_unit.y * rows as f64 / self.rows as f64,
        );
        Self { origin: self.origin, per_unit, columns, rows }
    }
}

impl ColumnGrid {
    /// The grid over triangles whose corners' xy are given, three a triangle.
    pub fn new(corners: impl ExactSizeIterator<Item = [DVec2; 3]>) -> Self {
        let bounds: Vec<[f64; 4]> = corners
            .map(|[a, b, c]| {
                let (low, high) = (a.min(b).min(c), a.max(b).max(c));
                [low.x, low.y, high.x, high.y]
            })
            .collect();
        let mut cells = Self::cells_for(&bounds);
        let limit = ENTRIES_PER_TRIANGLE * bounds.len() as u64;
        while cells.columns * cells.rows > 1 {
            let (entries, columns, rows) = cells.entries_of(&bounds);
            if entries <= limit {
                break;
            }
            // Halve the axis the triangles span more cells of: there halving saves the most.
            cells = cells.coarser(columns >= rows);
        }
        // Each cell's count at its index + 1, then their running sum: where each cell starts.
        let mut starts = vec![0usize; cells.columns * cells.rows + 1];
        for b in &bounds {
            let ((c0, c1), (r0, r1)) = cells.reached(b);
            for row in r0..=r1 {
                for count in &mut starts[row * cells.columns + c0 + 1..=row * cells.columns + c1 + 1] {
                    *count += 1;
                }
            }
        }
        for i in 1..starts.len() {
            starts[i] += starts[i - 1];
        }
        let mut entries = vec![0u32; starts[starts.len() - 1]];
        // Filling a cell moves its start on to its end, the next cell's start; moved back after.
        for (index, b) in (0..).zip(&bounds) {
            let ((c0, c1), (r0, r1)) = cells.reached(b);
            for row in r0..=r1 {
                for cell in row * cells.columns + c0..=row * cells.columns + c1 {
                    entries[starts[cell]] = index;
                    starts[cell] += 1;
                }
            }
        }
        let last = starts.len() - 1;
        starts.copy_within(..last, 1);
        starts[0] = 0;
        Self { bounds, cells, starts, entries }
    }

    /// About as many cells as triangles over the union of the bounds that are finite, shaped
    /// like it.
    fn cells_for(bounds: &[[f64; 4]]) -> Cells {
        let finite = bounds.iter().filter(|b| b.iter().all(|v| v.is_finite()));
        let (low, high) = finite.fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(low, high), b| {
            (low.min(DVec2::new(b[0], b[1])), high.max(DVec2::new(b[2], b[3])))
        });
        let size = high - low;
        if !(size.x.is_finite() && size.y.is_finite()) {
            return Cells { origin: DVec2::ZERO, per_unit: DVec2::ZERO, columns: 1, rows: 1 };
        }
        let target = bounds.len().clamp(1, 1 << 24) as f64;
        let (columns, rows) = match (size.x > 0.0, size.y > 0.0) {
            (true, true) => {
                let columns = (target * size.x / size.y).sqrt().clamp(1.0, target);
                (columns, (target / columns).clamp(1.0, target))
            }
            (true, false) => (target, 1.0),
            (false, true) => (1.0, target),
            (false, false) => (1.0, 1.0),
        };
        let (columns, rows) = (columns.round() as usize, rows.round() as usize);
        // A zero extent has one cell: every point maps to it.
        let per_unit = |cells: usize, extent: f64| if extent > 0.0 { cells as f64 / extent } else { 0.0 };
        Cells { origin: low, per_unit: DVec2::new(per_unit(columns, size.x), per_unit(rows, size.y)), columns, rows }
    }

    /// The triangles whose closed xy bounds hold p, in ascending index order.
    pub fn candidates(&self, p: DVec2) -> impl Iterator<Item = u32> + '_ {
        let (column, row) = self.cells.of(p.x, p.y);
        let cell = row * self.cells.columns + column;
        self.entries[self.starts[cell]..self.starts[cell + 1]].iter().copied().filter(move |&i| {
            let b = &self.bounds[i as usize];
            b[0] <= p.x && p.x <= b[2] && b[1] <= p.y && p.y <= b[3]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_force(bounds: &[[f64; 4]], p: DVec2) -> Vec<u32> {
        (0..bounds.len() as u32)
            .filter(|&i| {
                let b = bounds[i as usize];
                b[0] <= p.x && p.x <= b[2] && b[1] <= p.y && p.y <= b[3]
            })
            .collect()
    }

    /// A triangle of corners drawn from a small lattice, so that bounds and points share
    /// edges and corners exactly.
    fn lattice_triangles(seed: u64, count: usize, spread: f64) -> Vec<[DVec2; 3]> {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 33) % 17) as f64 * spread / 16.0
        };
        (0..count).map(|_| [(); 3].map(|_| DVec2::new(next(), next()))).collect()
    }

    /// The candidates are the triangles whose closed bounds hold the point, for points on
    /// every lattice node (bound edges and corners included) and off the union: small
    /// triangles, large ones that coarsen the grid, a union that is one point, and lattices
    /// moved off the origin (so that a cell index rounds `x − origin`).
    #[test]
    fn candidates_are_the_triangles_whose_bounds_hold_the_point() {
        let cases =
            [(1, 200, 1.0, 0.0), (2, 5000, 1.0, -0.3), (3, 3, 1.0, 1e6), (4, 40, 0.0, 0.0), (5, 300, 1.0, 2.5e5)];
        for (seed, count, spread, offset) in cases {
            let triangles: Vec<[DVec2; 3]> =
                lattice_triangles(seed, count, spread).into_iter().map(|t| t.map(|c| c + offset)).collect();
            let grid = ColumnGrid::new(triangles.iter().copied());
            for i in -2..=19 {
                for j in -2..=19 {
                    let p = DVec2::new(i as f64 / 16.0, j as f64 / 16.0) * spread.max(1.0) + offset;
                    assert_eq!(grid.candidates(p).collect::<Vec<_>>(), brute_force(&grid.bounds, p), "{p}");
                }
            }
            assert!(grid.entries.len() as u64 <= ENTRIES_PER_TRIANGLE * count as u64);
        }
    }

    /// Triangles flat in y (a union of zero height), and long thin triangles along x: the grid
    /// coarsens along x, keeping its rows, until its entries fit the bound.
    #[test]
    fn triangles_long_in_x_coarsen_the_columns() {
        let flat: Vec<[DVec2; 3]> = (0..100)
            .map(|k| [DVec2::new(k as f64, 0.0), DVec2::new(k as f64 + 1.0, 0.0), DVec2::new(k as f64 + 0.5, 0.0)])
            .collect();
        let grid = ColumnGrid::new(flat.iter().copied());
        assert_eq!(grid.cells.rows, 1);
        for p in [DVec2::new(3.0, 0.0), DVec2::new(3.5, 0.0), DVec2::new(3.5, 1e-9)] {
            assert_eq!(grid.candidates(p).collect::<Vec<_>>(), brute_force(&grid.bounds, p), "{p}");
        }
        let long: Vec<[DVec2; 3]> = (0..400)
            .map(|k| {
                let y = k as f64 / 400.0;
                [DVec2::new(0.0, y), DVec2::new(1.0, y), DVec2::new(1.0, y + 0.001)]
            })
            .collect();
        let grid = ColumnGrid::new(long.iter().copied());
        assert!(grid.cells.columns < grid.cells.rows, "{}×{}", grid.cells.columns, grid.cells.rows);
        assert!(grid.entries.len() as u64 <= ENTRIES_PER_TRIANGLE * 400);
        let p = DVec2::new(0.5, 0.2);
        assert_eq!(grid.candidates(p).collect::<Vec<_>>(), brute_force(&grid.bounds, p));
        assert!(grid.candidates(p).count() <= 3);
    }

    /// Triangles spanning the whole union each reach every cell of a fine grid; the grid
    /// coarsens until its entries fit the bound.
    #[test]
    fn large_triangles_coarsen_the_grid() {
        let mut triangles = lattice_triangles(5, 1000, 1.0);
        triangles.extend((0..1000).map(|_| [DVec2::ZERO, DVec2::new(1.0, 0.0), DVec2::ONE]));
        let grid = ColumnGrid::new(triangles.iter().copied());
        assert!(grid.entries.len() as u64 <= ENTRIES_PER_TRIANGLE * 2000);
        let p = DVec2::new(0.75, 0.25);
        assert_eq!(grid.candidates(p).collect::<Vec<_>>(), brute_force(&grid.bounds, p));
    }

    /// NaN and infinite corners do not panic, and the candidates are still those whose bounds
    /// hold the point (whatever glam's min and max make of a NaN corner: the exact test after
    /// rejects the triangle).
    #[test]
    fn non_finite_corners_are_binned_by_their_bounds() {
        let triangles =
            [[DVec2::NAN, DVec2::ONE, DVec2::ZERO], [DVec2::ZERO, DVec2::INFINITY, DVec2::ONE], [DVec2::ZERO; 3]];
        let grid = ColumnGrid::new(triangles.iter().copied());
        for p in [DVec2::ZERO, DVec2::new(0.5, 0.5), DVec2::new(2.0, 2.0), DVec2::NAN] {
            assert_eq!(grid.candidates(p).collect::<Vec<_>>(), brute_force(&grid.bounds, p), "{p}");
        }
        assert_eq!(grid.candidates(DVec2::new(2.0, 2.0)).collect::<Vec<_>>(), vec![1]);
    }
}
