//! Triangle meshes whose triangles are grouped into labelled *surfaces*.
//!
//! The verifier binds scene segments to model surfaces (a planar face or a whole curved
//! patch), never to triangles, so a mesh carries a surface id per triangle
//! (docs/design.md "Surfaces and labels"). Surface ids run from 1; 0 is "no data" everywhere.
//!
//! Every constructor goes through [`Mesh::new`], which is the one place that rejects what
//! cannot be rendered (non-finite coordinates, indices out of range, no triangles) and drops
//! degenerate triangles, counting them so callers can warn.
//!
//! A mesh keeps its vertices as f32 offsets from a point of its own frame ([`Mesh::origin`]):
//! CAD exported in assembly or machine coordinates puts a small part 10^4 or 10^5 units from
//! its origin, where f32 coordinates are 2^-10 or 2^-7 apart, and a pose that brings it back
//! into view would otherwise cancel those large coordinates in f32 on the GPU, moving faces
//! by a sizeable fraction of a pixel. The origin is folded into the pose in f64 instead
//! (src/render/raster/draw.rs), so a model's precision depends on its size, not on where it
//! sits in its frame.

mod adjacency;
mod builtin;
mod hull_faces;
mod mtl;
mod obj;
mod ply;
mod solid;
mod stl;
mod surfaces;

pub use adjacency::NO_NEIGHBOUR;
pub(crate) use adjacency::{LINK_EDGE_MASK, LINK_INDEX_SHIFT, LINK_SAME_WAY, MAX_LINKED_TRIANGLES};
pub use builtin::{builtin_bytes, builtin_mesh, canonical_builtin_name, BUILTIN_NAMES};
pub(crate) use hull_faces::{hull_face_bits, hull_tolerance};
pub use obj::{load_obj, parse_obj};
pub use ply::{load_ply, parse_ply};
pub use solid::Solidity;
pub use stl::{load_stl, parse_stl};
pub use surfaces::{
    SurfaceChoice, SurfaceRule, COPLANAR_ANGLE_TOLERANCE, COPLANAR_DISTANCE_TOLERANCE, DEFAULT_CREASE_DEG,
};

use crate::error::{Error, Result};
use glam::DVec3;

/// A validated triangle mesh with one surface id (1-based) per triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Where the mesh came from (a path or a `builtin:` name), for messages.
    pub name: String,
    /// The point of the model's frame the positions are offsets from (`model_frame_origin`).
    pub origin: DVec3,
    /// Each vertex as an f32 offset from `origin`; [`Mesh::vertex`] gives it in the model's
    /// frame.
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
    /// Whether the surfaces are the model's own (a built-in's faces, OBJ groups, a PLY face
    /// property), which `surfaces = "groups"` reads, rather than derived from its geometry
    /// ([`Mesh::with_surfaces`]).
    pub surfaces_from_file: bool,
}

/// The largest |coordinate| a model's vertex may have: a rotation's sum of three products
/// (shaders/raster/draw.glsl, `to_view`) stays finite in f32 far beyond it.
pub const MAX_COORDINATE: f32 = 1e30;

/// The scale a model is read at unless a scene's object or a hypothesis gives one
/// ([`Mesh::scaled`]).
pub(crate) fn default_model_scale() -> f64 {
    1.0
}

/// Bytes scaling a mesh takes beyond the mesh, at most: each vertex in f64 and stored again,
/// each triangle's corners and surface kept by the new mesh (measured: tests/memory.rs).
const BYTES_PER_SCALED_VERTEX: u64 = 48;
const BYTES_PER_SCALED_TRIANGLE: u64 = 32;

/// The point of a model's frame its vertices are stored as offsets from: the frame's origin
/// itself where the vertices' bounding box lies within its own size of it (a model drawn about
/// its origin is stored exactly as it is read, and renders bit for bit as it always did);
/// otherwise the box's centre snapped to a multiple of the power of two at least the box's
/// size (a copy of the model moved by such a multiple stores the same offsets). Either way
/// no offset exceeds about twice the box's size, so f32 holds the model to its own scale.
fn model_frame_origin(points: &[[f64; 3]]) -> DVec3 {
    let (lo, hi) = points
        .iter()
        .map(|&p| DVec3::from(p))
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let (centre, size) = ((lo + hi) / 2.0, (hi - lo).max_element().max(f64::MIN_POSITIVE));
    if centre.abs().max_element() <= size {
        return DVec3::ZERO;
    }
    let step = size.log2().ceil().exp2();
    (centre / step).round() * step
}

impl Mesh {
    /// Validates and builds a mesh from its vertices in the model's frame, in f64 as a file
    /// gives them. Degenerate (zero-area) triangles, as stored, are dropped and counted in
    /// [`Mesh::dropped_degenerate`]; surfaces left without triangles keep their label so that
    /// numbering stays as the file gave it.
    pub fn new(
        name: impl Into<String>,
        positions: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
        triangle_surfaces: Vec<u32>,
        surface_names: Vec<String>,
    ) -> Result<Self> {
        let name = name.into();
        let invalid = |reason: String| Error::Mesh { name: name.clone(), reason };
        if let Some(i) = positions.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(invalid(format!("vertex {i} has a non-finite coordinate {:?}", positions[i])));
        }
        if let Some(i) = positions.iter().position(|p| p.iter().any(|c| c.abs() > f64::from(MAX_COORDINATE))) {
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
        let (origin, positions) = stored_positions(&positions);
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
            origin,
            positions,
            triangles,
            triangle_surfaces,
            surface_names,
            surface_reflectivity,
            dropped_degenerate,
            surfaces_from_file: true,
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

    /// Vertex `index` in the model's frame.
    pub fn vertex(&self, index: u32) -> DVec3 {
        self.origin + DVec3::from(self.positions[index as usize].map(f64::from))
    }

    /// The mesh with every vertex multiplied by `scale` in its model frame (a uniform change
    /// of units, `[[object]] scale`), charged to `ledger` first; `scale` 1 is the mesh itself.
    pub fn scaled(self, scale: f64, ledger: &crate::limits::Ledger) -> Result<Mesh> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::Mesh {
                name: self.name,
                reason: format!("scale = {scale} must be a positive finite number"),
            });
        }
        if scale == 1.0 {
            return Ok(self);
        }
        ledger.charge(
            format_args!("scaling {} by {scale}", self.name),
            self.positions.len() as u64 * BYTES_PER_SCALED_VERTEX
                + self.triangles.len() as u64 * BYTES_PER_SCALED_TRIANGLE,
        )?;
        let positions = (0..self.positions.len() as u32).map(|v| (self.vertex(v) * scale).to_array()).collect();
        let mut mesh = Mesh::new(
            format!("{} scaled by {scale}", self.name),
            positions,
            self.triangles,
            self.triangle_surfaces,
            self.surface_names,
        )?;
        mesh.surface_reflectivity = self.surface_reflectivity;
        mesh.dropped_degenerate += self.dropped_degenerate;
        mesh.surfaces_from_file = self.surfaces_from_file;
        Ok(mesh)
    }

    /// The least and greatest corners of the box (model frame, axis-aligned) holding every
    /// vertex; infinite and empty without vertices.
    pub fn bounding_box(&self) -> [DVec3; 2] {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for i in 0..self.positions.len() as u32 {
            lo = lo.min(self.vertex(i));
            hi = hi.max(self.vertex(i));
        }
        [lo, hi]
    }

    /// Centre and radius of a sphere holding every vertex. A rigid pose moves the sphere
    /// with the mesh, which is how depth ranges and the shadow view's extent are bounded
    /// without transforming every vertex on the host.
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        let [lo, hi] = self.bounding_box();
        let centre = (lo + hi) * 0.5;
        let radius = (0..self.positions.len() as u32).map(|i| self.vertex(i).distance(centre)).fold(0.0, f64::max);
        (centre, radius)
    }
}

/// Loads a model file by its extension, in any case: `.ply` as PLY, `.stl` as STL, anything
/// else as OBJ.
pub fn load_model_file(path: &std::path::Path, ledger: &crate::limits::Ledger) -> Result<Mesh> {
    let extension = path.extension().map(|e| e.to_ascii_lowercase());
    match extension.as_ref().and_then(|e| e.to_str()) {
        Some("ply") => load_ply(path, ledger),
        Some("stl") => load_stl(path, ledger),
        _ => load_obj(path, ledger),
    }
}

/// The lines of a text model, whichever line ends it uses: `\n`, `\r\n`, or `\r` alone (a
/// file saved with classic Mac line ends would otherwise be one long line).
pub(super) fn text_lines(text: &str) -> impl Iterator<Item = &str> {
    text.split('\n').flat_map(|line| line.strip_suffix('\r').unwrap_or(line).split('\r'))
}

/// Vertices in the model's frame as a mesh stores them: the origin of its offsets
/// (`model_frame_origin`) and each vertex's f32 offset from it.
pub(super) fn stored_positions(points: &[[f64; 3]]) -> (DVec3, Vec<[f32; 3]>) {
    let origin = model_frame_origin(points);
    (origin, points.iter().map(|&p| (DVec3::from(p) - origin).as_vec3().to_array()).collect())
}

/// A triangle whose stored corners span zero area in f64 (repeated vertex or collinear
/// corners) covers no pixel and has no normal; it is dropped.
pub(super) fn is_degenerate(positions: &[[f32; 3]], tri: &[u32; 3]) -> bool {
    let p = tri.map(|i| {
        let [x, y, z] = positions[i as usize];
        DVec3::new(x.into(), y.into(), z.into())
    });
    (p[1] - p[0]).cross(p[2] - p[0]).length_squared() == 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn triangle_at(corners: [[f64; 3]; 3]) -> Mesh {
        Mesh::new("triangle", corners.to_vec(), vec![[0, 1, 2]], vec![1], vec!["s".into()]).unwrap()
    }

    #[test]
    fn a_model_about_its_origin_is_stored_as_read() {
        // Its box [0, 1]³ has its centre 0.5 from the origin, within its size.
        let mesh = triangle_at([[0.0, 0.0, 0.0], [1.0, 0.0, 0.1], [0.0, 1.0, 1.0]]);
        assert_eq!(mesh.origin, DVec3::ZERO);
        assert_eq!(mesh.positions, [[0.0, 0.0, 0.0], [1.0, 0.0, 0.1], [0.0, 1.0, 1.0]]);
    }

    #[test]
    fn a_model_far_from_its_origin_is_stored_to_its_own_scale() {
        // Box x in [10^4 + 0.1, 10^4 + 1.3], y in [-2, -1], z = 0.3: centre (10000.7, -1.5,
        // 0.3), size 1.2, so the snapping step is 2 and the origin (10000, -2, 0): offsets of
        // at most 1.3, which f32 holds to 2^-23 (at 10^4, f32 steps are 2^-10).
        let corners = [[10_000.1, -2.0, 0.3], [10_001.3, -2.0, 0.3], [10_000.1, -1.0, 0.3]];
        let mesh = triangle_at(corners);
        assert_eq!(mesh.origin, DVec3::new(10_000.0, -2.0, 0.0));
        for (v, expected) in corners.iter().enumerate() {
            let error = (mesh.vertex(v as u32) - DVec3::from(*expected)).abs().max_element();
            assert!(error <= 2f64.powi(-23), "vertex {v}: {} for {expected:?}", mesh.vertex(v as u32));
        }
        // Moved by a multiple of the step, the same offsets.
        let moved = triangle_at(corners.map(|[x, y, z]| [x + 1024.0, y, z]));
        assert_eq!(moved.positions, mesh.positions);
        assert_eq!(moved.origin, mesh.origin + DVec3::new(1024.0, 0.0, 0.0));
    }
}
