//! Which rasterizer renders a view (docs/design.md "Raster paths"): the graphics pipeline, the
//! compute rasterizer (src/render/raster/compute/), or `auto`, which picks per view from the
//! [`Crossover`] measured for the device's kind. Kept apart from the rasterizer itself because
//! the CLI, the library's settings and the summaries all name the choice, and the rule rests on
//! measurements (docs/compute-rasterizer.md), not on how either rasterizer works.

use crate::shader_contract::COVERAGE_MEMBERS;

/// Which rasterizer renders the views.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[non_exhaustive]
pub enum Raster {
    /// Per view: compute where the device's [`Crossover`] says so, else graphics.
    #[default]
    Auto,
    /// The graphics pipeline (the prescribed path).
    Graphics,
    /// The compute rasterizer, for views of up to [`COVERAGE_MEMBERS`] draws whose visibility
    /// words the device can bind; needs 64-bit buffer atomics.
    Compute,
}

/// Where `auto` takes the compute rasterizer for a view: its triangles, and their density, the
/// triangles per pixel of its footprint (each object's bounding sphere's pixels, with a 2-pixel
/// margin). One measured on each kind of device (`bench_verify -- --rasters`: compute against
/// graphics in the same run, batches taken in turn; docs/compute-rasterizer.md), as the two
/// kinds part the work differently: a CPU device runs every triangle of either rasterizer on
/// its few cores, where a GPU's graphics pipeline is fastest for few mid-sized triangles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossover {
    /// At least this many triangles and at least `min_density` take the compute rasterizer
    /// (one of the two bounds is 0)...
    min_triangles: u64,
    min_density: f64,
    /// ...and so does a density under this one, however few the triangles (large triangles,
    /// which the compute rasterizer's workgroups share out).
    sparse_below: f64,
}

impl Crossover {
    /// A CPU device's: there the compute rasterizer runs as fast as the graphics pipeline or
    /// faster at every density measured down to the box filling a 256² image (0.00018
    /// triangles per footprint pixel), and slower only sparser still (the box filling 512²,
    /// 0.000046): the bound lies between. The measured points: docs/performance-history.md.
    pub const CPU: Crossover = Crossover { min_triangles: 0, min_density: 0.0001, sparse_below: 0.0 };

    /// A GPU's (every GPU takes it until others are measured). What parts the two rasterizers
    /// there is the triangle count, not the density: a few hundred triangles leave most of a
    /// GPU's cores idle in the compute rasterizer, which gives one invocation to each, while its
    /// large triangles' workgroups beat the graphics pipeline's few rasterizers. The bounds lie
    /// between the measured points, near their geometric means (960 triangles, slower by
    /// compute, and 2,208, faster; 0.001 and 0.015 triangles per footprint pixel). The measured
    /// points: docs/performance-history.md.
    pub const GPU: Crossover = Crossover { min_triangles: 1_500, min_density: 0.0, sparse_below: 0.004 };

    /// A CPU device's for a rig's views (src/render/raster/compute/rig.rs) but those of one
    /// object in the depth test: there the compute rasterizer's label test reads a label
    /// through the mesh at every witness pixel it reads, and the views of several objects are
    /// resolved into their attachments before the test, so that a sparse model's many pixels
    /// cost it more. `bench_verify -- --rigs` (its model swapped) and `bench_bop` on lavapipe,
    /// compute against graphics in the same run: slower at 0.0009 and 0.0025 triangles per
    /// footprint pixel (the box, 0.44–0.77× before a job of one object read the words; 0.71–0.75×
    /// in the label test after) and even at 0.0196 (cylinder:48, 0.77–0.89× before; 0.79–1.04×
    /// after), faster at 0.047 (sphere:16, 1.09–1.18× before; 1.59–1.77× after), 0.20
    /// (sphere:32, 1.24–1.79×), 0.9 (a 3,990-triangle sphere at 640×480, 1.09–1.24×) and 2.06
    /// (sphere:100, 1.75–4×): the bound lies near the geometric mean of the nearest two.
    pub const CPU_RIG: Crossover = Crossover { min_triangles: 0, min_density: 0.03, sparse_below: 0.0 };

    /// The crossover measured for a CPU device (`is_cpu`) or a GPU.
    pub fn for_device(is_cpu: bool) -> Self {
        if is_cpu {
            Self::CPU
        } else {
            Self::GPU
        }
    }

    /// The crossover for a rig's views on a CPU device (`is_cpu`) or a GPU (the scanner's
    /// until rigs are measured on one). A CPU device takes the scanner's for the views of one
    /// object in the depth test (`depth_test_of_one_object`), which the compute rasterizer
    /// tests from its words as it tests the scanner's: faster than the graphics pipeline at
    /// every density measured, down to the box (0.0025 triangles per footprint pixel:
    /// 1.72–1.73×; cylinder:48, 0.0196: 1.57–2.30×; `bench_verify -- --rigs` with its model
    /// swapped, lavapipe); else [`Crossover::CPU_RIG`].
    pub fn for_rig(is_cpu: bool, depth_test_of_one_object: bool) -> Self {
        match (is_cpu, depth_test_of_one_object) {
            (false, _) => Self::GPU,
            (true, true) => Self::CPU,
            (true, false) => Self::CPU_RIG,
        }
    }

    /// Whether a view of `triangles` over `footprint_pixels` takes the compute rasterizer.
    pub fn takes_compute(self, triangles: u64, footprint_pixels: u64) -> bool {
        let (triangles_f, pixels) = (triangles as f64, footprint_pixels as f64);
        let dense = triangles >= self.min_triangles && triangles_f >= self.min_density * pixels;
        dense || triangles_f < self.sparse_below * pixels
    }
}

/// The rule as the summaries print it: "at least 0.0001 triangles per footprint pixel".
impl std::fmt::Display for Crossover {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let mut parts = Vec::new();
        if self.min_triangles > 0 {
            parts.push(format!("{} triangles", self.min_triangles));
        }
        if self.min_density > 0.0 {
            parts.push(format!("{} triangles per footprint pixel", self.min_density));
        }
        write!(f, "at least {}", parts.join(" and "))?;
        if self.sparse_below > 0.0 {
            write!(f, ", or under {} triangles per footprint pixel", self.sparse_below)?;
        }
        Ok(())
    }
}

impl Raster {
    pub fn as_str(self) -> &'static str {
        match self {
            Raster::Auto => "auto",
            Raster::Graphics => "graphics",
            Raster::Compute => "compute",
        }
    }

    /// Whether this choice renders a view of `draws` draws, with `triangles` triangles in all
    /// over a footprint of `footprint_pixels`, with the compute rasterizer, on a device that
    /// `has_compute` (64-bit buffer atomics) or not, whose `crossover` `auto` follows: 1 to
    /// [`COVERAGE_MEMBERS`] draws, the members of one coverage dispatch. `Compute` on a
    /// device without them is refused where its pipelines are built.
    pub fn computes(
        self,
        (has_compute, crossover): (bool, Crossover),
        draws: usize,
        triangles: u64,
        footprint_pixels: u64,
    ) -> bool {
        let members = (1..=COVERAGE_MEMBERS).contains(&draws);
        match self {
            Raster::Graphics => false,
            Raster::Compute => members,
            Raster::Auto => has_compute && members && crossover.takes_compute(triangles, footprint_pixels),
        }
    }
}

impl std::str::FromStr for Raster {
    type Err = String;

    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text {
            "auto" => Ok(Raster::Auto),
            "graphics" => Ok(Raster::Graphics),
            "compute" => Ok(Raster::Compute),
            other => Err(format!("unknown rasterizer {other:?}: expected auto, graphics or compute")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each device's rule against the measured points it rests on (docs/performance-history.md,
    /// `Crossover`): (triangles, footprint pixels, whether the rule should pick compute there:
    /// where it ran faster, or even).
    #[test]
    fn each_devices_crossover_picks_the_rasterizer_measured_faster() {
        let cpu = [
            (12, 12_000, true),         // box, 0.001 (even: 0.94–1.17×)
            (48, 3_200, true),          // sphere:8, 0.015
            (960, 3_137, true),         // sphere:32, 0.31
            (101_760, 3_140, true),     // sphere:320, 32
            (12, 66_000, true),         // box filling 256², 0.00018 (even)
            (12, 262_000, false),       // box filling 512², 0.000046
            (101_760, 1_048_576, true), // sphere:320 filling 1024², 0.1
        ];
        let gpu = [
            (12, 12_000, true),         // box, 0.001 (even: 0.94–1.16×)
            (48, 3_200, false),         // sphere:8, 0.015: 0.65–0.89×
            (224, 3_150, false),        // sphere:16, 0.071
            (960, 3_137, false),        // sphere:32, 0.31
            (2_208, 3_136, true),       // sphere:48, 0.70: 1.01–1.45×
            (9_800, 3_136, true),       // sphere:100, 3.1
            (12, 66_000, true),         // box filling 256², 0.00018: 1.72–2.14×
            (101_760, 65_536, true),    // sphere:320 filling 256²
            (101_760, 1_048_576, true), // sphere:320 filling 1024², 0.1: 12.24–13.16×
        ];
        // A rig's views on a CPU device (lavapipe, 2026-11-28; the label test of one object
        // and views of several, 2026-11-29).
        let cpu_rig = [
            (12, 13_300, false),  // box, BOP's 640×480, 0.0009: 0.63–0.77×
            (12, 4_761, false),   // box, 0.0025: 0.44–0.75×; the label test 0.71–0.75×
            (192, 9_801, false),  // cylinder:48, 0.0196: 0.77–0.89×; the label test 0.79–1.04×
            (224, 4_761, true),   // sphere:16, 0.047: 1.09–1.18×
            (960, 4_761, true),   // sphere:32, 0.20: 1.24–1.79×
            (3_990, 4_400, true), // BOP's sphere, 0.9: 1.09–1.24×
            (9_800, 4_761, true), // sphere:100, 2.06: 1.75–4×
        ];
        // The depth test of one object under a rig on a CPU device (lavapipe, 2026-11-29).
        let cpu_rig_depth = [
            (12, 4_761, true),  // box, 0.0025: 1.72–1.73×
            (192, 9_801, true), // cylinder:48, 0.0196: 1.57–2.30×
            (224, 4_761, true), // sphere:16, 0.047: 3.12–3.71×
        ];
        let rules = [
            (Crossover::CPU, &cpu[..]),
            (Crossover::GPU, &gpu[..]),
            (Crossover::CPU_RIG, &cpu_rig[..]),
            (Crossover::for_rig(true, true), &cpu_rig_depth[..]),
        ];
        for (crossover, points) in rules {
            for &(triangles, pixels, faster) in points {
                assert_eq!(
                    crossover.takes_compute(triangles, pixels),
                    faster,
                    "{crossover}: {triangles} over {pixels}"
                );
            }
        }
        assert_eq!(Crossover::for_device(true), Crossover::CPU);
        assert_eq!(Crossover::for_device(false), Crossover::GPU);
        assert_eq!(Crossover::for_rig(true, false), Crossover::CPU_RIG);
        assert_eq!(Crossover::for_rig(false, true), Crossover::GPU);
        assert_eq!(Crossover::for_rig(false, false), Crossover::GPU);
        assert_eq!(Crossover::CPU.to_string(), "at least 0.0001 triangles per footprint pixel");
        assert_eq!(Crossover::GPU.to_string(), "at least 1500 triangles, or under 0.004 triangles per footprint pixel");
    }
}
