//! Triangle meshes whose triangles are grouped into labelled *surfaces*.
//!
//! The verifier binds scene segments to model surfaces (a planar face or a whole curved
//! patch), never to triangles, so a mesh carries a surface id per triangle
//! (docs/design.md "Surfaces and labels"). Surface ids run from 1; 0 is "no data" everywhere.
//!
//! Every constructor goes through [`Mesh::new`], which is the one place that rejects what
//! cannot be rendered (non-finite coordinates, indices out of range, no triangles) and drops
//! degenerate triangles, counting them so callers can warn.

mod adjacency;
mod builtin;
mod mtl;
mod obj;
mod solid;
mod surfaces;

pub use adjacency::NO_NEIGHBOUR;
pub(crate) use adjacency::{LINK_EDGE_MASK, LINK_INDEX_SHIFT, LINK_SAME_WAY, MAX_LINKED_TRIANGLES};
pub use builtin::{builtin_bytes, builtin_mesh, canonical_builtin_name, BUILTIN_NAMES};
pub use obj::{load_obj, parse_obj};
pub use solid::Solidity;
pub use surfaces::{merge_coplanar_surfaces, COPLANAR_ANGLE_TOLERANCE, COPLANAR_DISTANCE_TOLERANCE};

use crate::error::{Error, Result};
use glam::DVec3;

/// A validated triangle mesh with one surface id (1-based) per triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Where the mesh came from (a path or a `builtin:` name), for messages.
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Surface id of each triangle, in `1..=surface_names.len()`.
    pub triangle_surfaces: Vec<u32>,
    /// Name of surface `i + 1`.
    pub surface_names: Vec<String>,
    /// Reflectivity of surface `i + 1` where its material gives one (the mean of an OBJ
    /// material's `Kd`), for `[effects.reflectivity]`.
    pub surface_reflectivity: Vec<Option<f32>>,
    /// Zero-area triangles removed by [`Mesh::new`].
    pub dropped_degenerate: usize,
}

/// The largest |coordinate| a model's vertex may have: a rotation's sum of three products
/// (shaders/raster/draw.glsl, `to_view`) stays finite in f32 far beyond it.
pub const MAX_COORDINATE: f32 = 1e30;

impl Mesh {
    /// Validates and builds a mesh. Degenerate (zero-area) triangles are dropped and
    /// counted in [`Mesh::dropped_degenerate`]; surfaces left without triangles keep their
    /// label so that numbering stays as the file gave it.
    pub fn new(
        name: impl Into<String>,
        positions: Vec<[f32; 3]>,
        triangles: Vec<[u32; 3]>,
        triangle_surfaces: Vec<u32>,
        surface_names: Vec<String>,
    ) -> Result<Self> {
        let name = name.into();
        let invalid = |reason: String| Error::Mesh { name: name.clone(), reason };
        if let Some(i) = positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(invalid(format!("vertex {i} has a non-finite coordinate {:?}", positions[i])));
        }
        if let Some(i) = positions.iter().position(|p| p.iter().any(|c| c.abs() > MAX_COORDINATE)) {
            return Err(invalid(format!(
                "vertex {i} has the coordinates {:?}: each must lie within ±{MAX_COORDINATE:e} (the GPU rotates them \
                 in f32, which overflows beyond)",
                positions[i]
            )));
        }
        if triangles.len() != triangle_surfaces.len() {
            return Err(invalid("each triangle needs exactly one surface id".into()));
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&v| v as usize >= positions.len()) {
                return Err(invalid(format!(
                    "triangle {t} refers to vertex {bad}, but there are only {} vertices",
                    positions.len()
                )));
            }
        }
        if let Some(t) = triangle_surfaces.iter().position(|&s| s == 0 || s as usize > surface_names.len()) {
            return Err(invalid(format!(
                "triangle {t} has surface id {}, outside 1..={}",
                triangle_surfaces[t],
                surface_names.len()
            )));
        }
        let given = triangles.len();
        let (triangles, triangle_surfaces): (Vec<_>, Vec<_>) =
            triangles.into_iter().zip(triangle_surfaces).filter(|(tri, _)| !is_degenerate(&positions, tri)).unzip();
        let dropped_degenerate = given - triangles.len();
        if triangles.is_empty() {
            return Err(invalid("it has no (non-degenerate) triangles".into()));
        }
        let surface_reflectivity = vec![None; surface_names.len()];
        Ok(Self {
            name,
            positions,
            triangles,
            triangle_surfaces,
            surface_names,
            surface_reflectivity,
            dropped_degenerate,
        })
    }

    pub fn surface_count(&self) -> u32 {
        self.surface_names.len() as u32
    }

    /// Each surface's reflectivity, surface 1 first: its material's, else `default`.
    pub fn surface_reflectivities(&self, default: f64) -> impl Iterator<Item = f64> + '_ {
        (0..self.surface_count() as usize)
            .map(move |s| self.surface_reflectivity.get(s).copied().flatten().map_or(default, f64::from))
    }

    pub fn vertex(&self, index: u32) -> DVec3 {
        let [x, y, z] = self.positions[index as usize];
        DVec3::new(x.into(), y.into(), z.into())
    }

    /// Centre and radius of a sphere holding every vertex. A rigid pose moves the sphere
    /// with the mesh, which is how depth ranges and the shadow view's extent are bounded
    /// without transforming every vertex on the host.
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for i in 0..self.positions.len() as u32 {
            lo = lo.min(self.vertex(i));
            hi = hi.max(self.vertex(i));
        }
        let centre = (lo + hi) * 0.5;
        let radius = (0..self.positions.len() as u32).map(|i| self.vertex(i).distance(centre)).fold(0.0, f64::max);
        (centre, radius)
    }
}

/// The lines of a text model, whichever line ends it uses: `\n`, `\r\n`, or `\r` alone (a
/// file saved with classic Mac line ends would otherwise be one long line).
pub(super) fn text_lines(text: &str) -> impl Iterator<Item = &str> {
    text.split('\n').flat_map(|line| line.strip_suffix('\r').unwrap_or(line).split('\r'))
}

/// A triangle whose area is zero in f64 (repeated vertex or collinear corners) covers no
/// pixel and has no normal; it is dropped.
pub(super) fn is_degenerate(positions: &[[f32; 3]], tri: &[u32; 3]) -> bool {
    let p = tri.map(|i| {
        let [x, y, z] = positions[i as usize];
        DVec3::new(x.into(), y.into(), z.into())
    });
    (p[1] - p[0]).cross(p[2] - p[0]).length_squared() == 0.0
}
