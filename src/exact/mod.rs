//! Shadow mode `exact` (src/shadow.rs): the range image by two rays in f64 at every pixel
//! centre, on the CPU. The product's own ground truth, against which `rangesynth accuracy`
//! measures the GPU modes, and the slow end of that curve.
//!
//! The first ray travels down −z from the pixel centre; the nearest surface it meets gives the
//! pixel's label, z and plane. The second travels from that point p toward the camera, along
//! d_cam; rotated by R_y(−θ) it travels down −z too, so both rays ask one question of a
//! `VerticalCaster`: which triangles lie over (x, y), and at what heights. Each caster
//! answers it from a grid over the triangles' xy bounds (src/exact/column_grid.rs), with an
//! exact f64 point-in-triangle test, edges included. A solid's triangles that face away from
//! a caster's rays are left out of it, as the GPU's rasterizers cull them: a closed solid is
//! met first through a triangle that faces the ray, so about half of a solid's triangles need
//! neither posing into a grid nor testing.
//!
//! The point is shadowed when its surface's lit side turns away from the camera (n · d_cam ≤ 0,
//! however thin the surface, as in depth mode) or when any surface lies above p on the camera
//! ray. Coincident faces follow the product's tie rule (README "the tie rule"): surfaces within
//! [`TIE_RELATIVE`] of the scene's largest coordinate of the nearest are a tie, won by the
//! lowest label, and they do not shadow each other (the GPU paths' allowance for depths
//! worked out from snapped corners has no cause here). Rows are cast in parallel (rayon).

mod column_grid;
mod ray_caster;
mod rig;

use crate::error::{Error, Result};
use crate::mesh::{Mesh, Solidity};
use crate::scene::Scene;
use crate::sensor::{PixelRect, Scanner, Sensor};
use crate::shadow::ShadowMode;
use column_grid::ColumnGrid;
use glam::{DMat4, DVec2, DVec3};
use rayon::prelude::*;

pub use crate::shader_contract::TIE_RELATIVE;

/// n · d_cam (unit normal) at or below which a surface counts as turned away from the camera:
/// one seen exactly edge-on, up to the rounding of its posed corners, is not measured.
pub(crate) const FACING_TOLERANCE: f64 = 1e-9;

/// Bytes a caster takes per triangle: corners and label, and a hierarchy over their bounds
/// (src/exact/ray_caster.rs) or a grid (src/exact/column_grid.rs), whichever is larger (more
/// than the mesh's posed vertices, at most three a triangle, which posing holds before either
/// is built: `posed_triangles`).
pub const CASTER_BYTES_PER_TRIANGLE: u64 = 3 * 24 + 8 + {
    let hierarchy = 48 + 96;
    if column_grid::BYTES_PER_TRIANGLE > hierarchy {
        column_grid::BYTES_PER_TRIANGLE
    } else {
        hierarchy
    }
};
// The posed vertices (three a triangle, 24 bytes each) fit in the bytes the hierarchy or
// grid takes later.
const _: () = assert!(CASTER_BYTES_PER_TRIANGLE - (3 * 24 + 8) >= 3 * 24);
/// Bytes exact mode takes per triangle under the paper's scanner (its two casters) and per
/// pixel (the image it returns), for memory budgets.
pub const BYTES_PER_TRIANGLE: u64 = 2 * CASTER_BYTES_PER_TRIANGLE;
pub const BYTES_PER_PIXEL: u64 = 4 + 4 + 8 + 16 + 4;

/// Casters exact mode builds for a sensor, at most: the scanner's two, or under a rig one
/// for the reference view's rays and one for each witness.
pub fn casters(sensor: &Sensor) -> u64 {
    2 + sensor.witnesses.len() as u64
}

/// One object of the scene: a mesh, its pose (model → range frame), the label of its
/// surface 0 (its surface s is labelled `label_base + s`), and whether it bounds a solid
/// ([`Mesh::solidity`], which a caller that casts the same mesh again keeps: finding it costs
/// more than casting a small image).
#[derive(Clone, Copy)]
pub struct ExactObject<'a> {
    pub mesh: &'a Mesh,
    pub pose: DMat4,
    pub label_base: u32,
    pub solidity: Solidity,
}

/// The range image exact ray casting sees, unshadowed and shadowed.
#[derive(Debug, Clone, PartialEq)]
pub struct ExactImage {
    pub width: u32,
    pub height: u32,
    /// Label of the first surface along −z at each pixel centre, 0 for none.
    pub label: Vec<u32>,
    /// `label`, with 0 where the camera cannot see the point.
    pub shadowed: Vec<u32>,
    /// z of the first hit (range frame); 0 where there is none.
    pub z: Vec<f64>,
    /// (∂z/∂x, ∂z/∂y) of the hit triangle's plane (the reference frame's), which effects such
    /// as grazing read; 0 where there is no hit.
    pub gradient: Vec<[f64; 2]>,
    /// Bit k set where witness k does not see the point; 0 where there is no hit.
    pub witness: Vec<u32>,
}

#[derive(Clone)]
struct Triangle {
    corners: [DVec3; 3],
    label: u32,
}

/// Triangles in one frame, with a grid over their xy bounds: answers which triangles lie
/// over a point (x, y), and at what heights.
struct VerticalCaster {
    triangles: Vec<Triangle>,
    grid: ColumnGrid,
}

impl VerticalCaster {
    fn new(triangles: Vec<Triangle>) -> Self {
        let grid = ColumnGrid::new(triangles.iter().map(|t| t.corners.map(DVec3::truncate)));
        Self { triangles, grid }
    }

    /// (height, index, triangle) of every triangle whose xy projection holds p, edges included.
    fn hits(&self, p: DVec2) -> impl Iterator<Item = (f64, u32, &Triangle)> + '_ {
        self.grid.candidates(p).filter_map(move |i| {
            let t = &self.triangles[i as usize];
            height_over(&t.corners, p).map(|z| (z, i, t))
        })
    }

    /// The nearest surface over p and its height: the largest height; among heights within
    /// `tie` of it, the lowest label, and of that label's triangles (a point on an edge, or a
    /// vertex) the first in scene order, whose plane gives z and which way the surface faces.
    fn front(&self, p: DVec2, tie: f64) -> Option<(f64, &Triangle)> {
        let hits: smallvec::SmallVec<[(f64, u32, &Triangle); 4]> = self.hits(p).collect();
        let top = hits.iter().map(|h| h.0).max_by(f64::total_cmp)?;
        let (z, _, triangle) = hits.into_iter().filter(|h| h.0 >= top - tie).min_by_key(|h| (h.2.label, h.1))?;
        Some((z, triangle))
    }
}

/// The height of the triangle over p, interpolated from its corners, when p lies inside its xy
/// projection (edges included); `None` outside, or for a triangle seen exactly edge-on.
fn height_over(c: &[DVec3; 3], p: DVec2) -> Option<f64> {
    let [a, b, d] = c.map(|v| v.truncate());
    let area = (b - a).perp_dot(d - a);
    if area == 0.0 {
        return None;
    }
    let w = [(b - p).perp_dot(d - p), (d - p).perp_dot(a - p), (a - p).perp_dot(b - p)].map(|w| w / area);
    w.iter().all(|&w| w >= 0.0).then(|| w[0] * c[0].z + w[1] * c[1].z + w[2] * c[2].z)
}

/// Which of a solid's triangles a caster leaves out (src/mesh/solid.rs): those facing away
/// from where its rays come from. A ray entering the solid from there meets one facing it
/// first; one leaving it toward there (a segment from a point to a witness) leaves through one
/// facing it. The answers stay those of the whole mesh but where a ray passes within the tie
/// distance of a silhouette edge: there a face turned away and one turned toward the view tie,
/// and the one turned toward it now always wins (as it does on the GPU, which culls them too),
/// where before the first in the mesh did. `frame` is rigid, so it keeps a triangle's winding.
#[derive(Clone, Copy)]
enum Cull {
    /// Rays run down −z: those facing away from +z.
    AwayFromZ,
    /// Rays run from or toward `centre`: those facing away from it, of solids that do not hold
    /// the centre (from inside, a solid's far side is what a ray meets) and lie wholly beyond
    /// `near` in z where one is given (a near limit cuts a solid open). Both by a margin
    /// ([`SPHERE_MARGIN`]), so that a centre on a solid's surface keeps it whole.
    AwayFrom { centre: DVec3, near: Option<f64> },
}

/// How much larger than its bounding sphere a solid counts for [`Cull::AwayFrom`], relative
/// to the sphere's radius and its centre's distance from the origin: more than a pose's
/// departure from rigid ([`crate::pose::RIGIDITY_TOLERANCE`]) and the f64 rounding of posing.
const SPHERE_MARGIN: f64 = 1e-5;

/// Every object's triangles in `frame`, less those `cull` leaves out of solids, and the
/// largest |coordinate| of every triangle's corners, those left out included (at least 1):
/// the scene's scale, which the tie distance is relative to, whatever a caster keeps.
fn posed_triangles(objects: &[ExactObject], frame: DMat4, cull: Cull) -> (Vec<Triangle>, f64) {
    let mut out = Vec::with_capacity(objects.iter().map(|object| object.mesh.triangles.len()).sum());
    let mut largest = 1.0f64;
    for object in objects {
        let m = frame * object.pose;
        let mesh = object.mesh;
        let away = match object.solidity {
            Solidity::Open => 0.0,
            Solidity::Outward => -1.0,
            Solidity::Inward => 1.0,
        };
        let (away, from) = match cull {
            Cull::AwayFromZ => (away, None),
            Cull::AwayFrom { centre, near } => {
                let (c, r) = mesh.bounding_sphere();
                let c = m.transform_point3(c);
                let r = r + SPHERE_MARGIN * (r + c.length());
                let clear = c.distance(centre) > r && near.is_none_or(|near| c.z - r > near);
                (if clear { away } else { 0.0 }, Some(centre))
            }
        };
        // Each vertex posed once, where the mesh has no more vertices than its triangles have
        // corners (a caster's bytes a triangle hold them: its grid is not built yet); else
        // each corner.
        let pose = |v: u32| m.transform_point3(mesh.vertex(v));
        let posed: Option<Vec<DVec3>> = (mesh.positions.len() <= 3 * mesh.triangles.len())
            .then(|| (0..mesh.positions.len() as u32).map(pose).collect());
        for (triangle, &surface) in mesh.triangles.iter().zip(&mesh.triangle_surfaces) {
            let corners = match &posed {
                Some(vertices) => triangle.map(|v| vertices[v as usize]),
                None => triangle.map(pose),
            };
            largest = corners.iter().fold(largest, |l, c| l.max(c.abs().max_element()));
            let [a, b, c] = corners;
            let normal = (b - a).cross(c - a);
            let facing = from.map_or(normal.z, |centre| normal.dot(centre - a));
            if away * facing > 0.0 {
                continue;
            }
            out.push(Triangle { corners, label: object.label_base + surface });
        }
    }
    (out, largest)
}

fn scene_objects(scene: &Scene) -> Result<Vec<ExactObject<'_>>> {
    Ok(scene
        .objects
        .iter()
        .zip(scene.label_bases()?)
        .map(|(object, label_base)| ExactObject {
            mesh: &object.mesh,
            pose: object.pose,
            label_base,
            solidity: object.mesh.solidity(),
        })
        .collect())
}

/// Casts the rays of shadow mode `exact` at every pixel centre of the scene's image, its
/// objects labelled as the GPU modes label them (`Scene::label_bases`).
pub fn render_scene_exact(scene: &Scene) -> Result<ExactImage> {
    render_exact(&scene.sensor, &scene_objects(scene)?)
}

/// The scene's image under a rig other than the paper's scanner (src/exact/rig.rs), in
/// shadow mode `mode` (`render_rig`).
pub fn render_rig_exact(scene: &Scene) -> Result<ExactImage> {
    let full = PixelRect { col: 0, row: 0, width: scene.sensor.width(), height: scene.sensor.height() };
    render_rig(&scene.sensor, &scene_objects(scene)?, scene.shadow.mode, full)
}

/// The image of `objects` under a rig other than the paper's scanner, cast on the CPU within
/// `region` (the rest meets nothing): in shadow modes `exact` and `depth` each point is tested
/// against every witness (depth mode asks, up to its bias, the question exact mode answers,
/// and under a rig the CPU answers it exactly: src/shadow.rs); in mode `none` the reference
/// view's rays alone are cast. Mode `label` is not cast (it reads the witnesses' label
/// images, which the GPU renders).
pub fn render_rig(sensor: &Sensor, objects: &[ExactObject], mode: ShadowMode, region: PixelRect) -> Result<ExactImage> {
    let test_witnesses = match mode {
        ShadowMode::Exact | ShadowMode::Depth => true,
        ShadowMode::None => false,
        ShadowMode::Label => {
            sensor.require_scanner("[shadow] mode = \"label\"")?;
            true
        }
    };
    rig::render_rig(sensor, objects, test_witnesses, region)
}

/// Casts the rays of shadow mode `exact` at every pixel centre of the sensor's image.
pub fn render_exact(sensor: &Sensor, objects: &[ExactObject]) -> Result<ExactImage> {
    let full = PixelRect { col: 0, row: 0, width: sensor.width(), height: sensor.height() };
    match sensor.scanner() {
        Some(scanner) => render_scanner(&scanner, objects),
        None => rig::render_rig(sensor, objects, true, full),
    }
}

/// The paper's scanner: a ray down −z at each pixel centre, then one toward the camera.
fn render_scanner(sensor: &Scanner, objects: &[ExactObject]) -> Result<ExactImage> {
    sensor.validate()?;
    let to_camera = sensor.to_shadow_frame();
    // The two casters are built side by side: for a dense model at a small image, building
    // them is most of the work.
    let caster = |frame| {
        let (triangles, largest) = posed_triangles(objects, frame, Cull::AwayFromZ);
        (VerticalCaster::new(triangles), largest)
    };
    let ((range, scale), (camera, camera_largest)) = rayon::join(|| caster(DMat4::IDENTITY), || caster(to_camera));
    // The camera's frame too: turning corners near f64's largest values can take them beyond.
    if !(scale.is_finite() && camera_largest.is_finite()) {
        return Err(Error::Scene("an object is posed too far away for exact ray casting".into()));
    }
    let tie = TIE_RELATIVE * scale;
    let d_cam = sensor.camera_direction();
    let (width, height) = (sensor.width, sensor.height);
    let cast = |col: u32, row: u32| -> ExactPixel {
        let (x, y) = sensor.pixel_centre(col, row);
        let Some((z, triangle)) = range.front(DVec2::new(x, y), tie) else {
            return ExactPixel::default();
        };
        let [a, b, c] = triangle.corners;
        let normal = (b - a).cross(c - a).normalize();
        let gradient = [-normal.x / normal.z, -normal.y / normal.z];
        let lit_side = normal * normal.z.signum();
        let p = to_camera.transform_point3(DVec3::new(x, y, z));
        let occluded =
            lit_side.dot(d_cam) <= FACING_TOLERANCE || camera.hits(p.truncate()).any(|(above, _, _)| above > p.z + tie);
        // The camera is witness 0.
        ExactPixel { label: triangle.label, z, gradient, lost_by: u32::from(occluded) }
    };
    Ok(cast_image((width, height), PixelRect { col: 0, row: 0, width, height }, cast))
}

/// What exact ray casting finds at one pixel centre.
#[derive(Clone, Copy, Default)]
struct ExactPixel {
    /// The first surface's label, 0 for none.
    label: u32,
    z: f64,
    gradient: [f64; 2],
    /// Bit k: witness k does not see the point.
    lost_by: u32,
}

/// Casts the pixels of `region` in a `width`×`height` image, rows in parallel; the others
/// meet nothing.
fn cast_image(
    (width, height): (u32, u32),
    region: PixelRect,
    cast: impl Fn(u32, u32) -> ExactPixel + Sync,
) -> ExactImage {
    let cols = region.col..region.col + region.width;
    let rows = region.row..region.row + region.height;
    let pixels: Vec<ExactPixel> = (0..height)
        .into_par_iter()
        .flat_map_iter(|row| (0..width).map(move |col| (col, row)))
        .map(|(col, row)| match cols.contains(&col) && rows.contains(&row) {
            true => cast(col, row),
            false => ExactPixel::default(),
        })
        .collect();
    ExactImage {
        width,
        height,
        label: pixels.iter().map(|p| p.label).collect(),
        shadowed: pixels.iter().map(|p| if p.lost_by == 0 { p.label } else { 0 }).collect(),
        z: pixels.iter().map(|p| p.z).collect(),
        gradient: pixels.iter().map(|p| p.gradient).collect(),
        witness: pixels.iter().map(|p| p.lost_by).collect(),
    }
}
