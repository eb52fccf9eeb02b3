//! Independent CPU reference: exact f64 ray casting at pixel centres (docs/design.md "Testing
//! stance"). Shares nothing with the GPU path but the scene description.
//!
//! The primary ray at a pixel centre travels down −z; the first hit is the triangle with
//! the largest z over (x, y). The shadow ray from that point p travels along d_cam; rotated
//! by R_y(−θ) it becomes a vertical ray too, so both are answered by the same caster: "which
//! triangles cover this (x, y), at what z".

use glam::{DMat4, DVec2, DVec3};
use rangesynth::Scene;

pub struct Reference {
    pub width: usize,
    pub height: usize,
    /// Label of the first hit, 0 for none.
    pub label: Vec<u32>,
    /// z of the first hit (range frame).
    pub z: Vec<f64>,
    /// The hit triangle's unit normal on the side the projector lights (n_z ≥ 0): n_z is 1
    /// face-on, 0 edge-on.
    pub lit_normal: Vec<DVec3>,
    /// Range of z over the planes a rasterizer may rightly pick at the pixel centre: the hit
    /// triangle's and those of triangles sharing a vertex with it that come within
    /// [`SNAP_PIXELS`] of the centre (Vulkan's minimum sub-pixel precision is 4 bits).
    pub z_bracket: Vec<(f64, f64)>,
    /// The same over the planes of the hit's surface alone: the z a rasterizer that shows the
    /// reference's label there may hold.
    pub z_bracket_surface: Vec<(f64, f64)>,
    /// Exact triangulation shadow: whether the camera cannot see the point, because a surface
    /// lies along d_cam from it or because the side of its surface the projector lights (+z)
    /// turns away from the camera (n · d_cam ≤ 0, however thin the surface).
    pub occluded: Vec<bool>,
    /// Label of the surface the camera sees at the point's position (the front-most along
    /// the camera ray through it): what an exact shadow buffer holds there, and what the
    /// paper's label test compares with.
    pub camera_label: Vec<u32>,
    /// Whether the camera's view within one shadow-view pixel (±dx across its rows) of the
    /// point shows more than one surface: the point is within one pixel of a silhouette or
    /// surface edge as the camera sees it, which is where shadow boundaries are cast and
    /// where a shadow buffer of that pitch cannot decide.
    pub near_camera_edge: Vec<bool>,
    /// Whether the primary ray meets more than one triangle at the front depth (within the tie
    /// tolerance): the pixel centre lies on an edge or a vertex, or on coincident faces, and
    /// which triangle's plane it takes is a matter of rule.
    pub tied: Vec<bool>,
    /// The scene in the camera's frame (R_y(−θ)), for the tests that read what it sees.
    camera: VerticalCaster,
}

impl Reference {
    /// Labels after exact shadowing.
    pub fn label_shadowed(&self) -> Vec<u32> {
        (0..self.label.len()).map(|i| if self.occluded[i] { 0 } else { self.label[i] }).collect()
    }

    /// Labels after the paper's test (Fig. 4) evaluated exactly: shadowed where the camera
    /// sees another surface at the point. A surface hiding part of itself goes unnoticed.
    pub fn label_paper_shadowed(&self) -> Vec<u32> {
        (0..self.label.len()).map(|i| if self.camera_label[i] != self.label[i] { 0 } else { self.label[i] }).collect()
    }
}

/// How close to a triangle edge a pixel centre may go either way, in pixels.
pub const SNAP_PIXELS: f64 = 1.0 / 16.0;

/// Depths this close, relative to the scene's largest coordinate, are a tie: coincident faces.
const TIE_RELATIVE: f64 = 1e-9;

/// n · d_cam at or below which a surface counts as turned away from the camera: a surface seen
/// exactly edge-on (0 up to rounding of its posed corners) is not measured.
const FACING_TOLERANCE: f64 = 1e-9;

struct Triangle {
    corners: [DVec3; 3],
    /// (object, model-space corner bits), to find neighbours however the mesh shares vertices.
    vertices: [(usize, [u32; 3]); 3],
    label: u32,
    lo: DVec2,
    hi: DVec2,
}

/// Triangles binned on a uniform grid over their xy bounding box.
struct VerticalCaster {
    triangles: Vec<Triangle>,
    lo: DVec2,
    cell: DVec2,
    cells: (usize, usize),
    bins: Vec<Vec<u32>>,
}

impl VerticalCaster {
    fn new(triangles: Vec<Triangle>) -> Self {
        let lo = triangles.iter().fold(DVec2::splat(f64::INFINITY), |m, t| m.min(t.lo));
        let hi = triangles.iter().fold(DVec2::splat(f64::NEG_INFINITY), |m, t| m.max(t.hi));
        let n = ((triangles.len() as f64).sqrt().ceil() as usize).clamp(1, 256);
        let cell = ((hi - lo) / n as f64).max(DVec2::splat(1e-12));
        let mut bins = vec![Vec::new(); n * n];
        for (i, t) in triangles.iter().enumerate() {
            let (c0, r0) = Self::cell_of(lo, cell, n, t.lo);
            let (c1, r1) = Self::cell_of(lo, cell, n, t.hi);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    bins[r * n + c].push(i as u32);
                }
            }
        }
        Self { triangles, lo, cell, cells: (n, n), bins }
    }

    fn cell_of(lo: DVec2, cell: DVec2, n: usize, p: DVec2) -> (usize, usize) {
        let q = ((p - lo) / cell).floor();
        ((q.x.max(0.0) as usize).min(n - 1), (q.y.max(0.0) as usize).min(n - 1))
    }

    /// (z, label, triangle) of every triangle covering (x, y), boundary included.
    fn hits(&self, p: DVec2) -> impl Iterator<Item = (f64, u32, &Triangle)> + '_ {
        let inside_grid = p.cmpge(self.lo).all()
            && p.cmple(self.lo + self.cell * DVec2::new(self.cells.0 as f64, self.cells.1 as f64)).all();
        let bin: &[u32] = if inside_grid {
            let (c, r) = Self::cell_of(self.lo, self.cell, self.cells.0, p);
            &self.bins[r * self.cells.0 + c]
        } else {
            &[]
        };
        bin.iter().filter_map(move |&i| {
            let t = &self.triangles[i as usize];
            if p.cmplt(t.lo).any() || p.cmpgt(t.hi).any() {
                return None;
            }
            height_at(&t.corners, p).map(|z| (z, t.label, t))
        })
    }
}

impl VerticalCaster {
    /// The nearest hit over p: largest z; of hits within `tie` of it (coincident faces), the
    /// lowest label (the documented tie rule).
    fn front(&self, p: DVec2, tie: f64) -> Option<(f64, u32, &Triangle)> {
        let z = self.hits(p).map(|h| h.0).max_by(f64::total_cmp)?;
        self.hits(p).filter(|h| h.0 >= z - tie).min_by_key(|h| h.1)
    }

    /// (z, triangle) of triangles whose xy projection comes within `margin` of p: those in
    /// the bins the square p ± margin overlaps, each once.
    fn near(&self, p: DVec2, margin: f64) -> impl Iterator<Item = (f64, &Triangle)> + '_ {
        let n = self.cells.0;
        let (c0, r0) = Self::cell_of(self.lo, self.cell, n, p - margin);
        let (c1, r1) = Self::cell_of(self.lo, self.cell, n, p + margin);
        let mut candidates: Vec<u32> =
            (r0..=r1).flat_map(|r| (c0..=c1).flat_map(move |c| self.bins[r * n + c].iter().copied())).collect();
        candidates.sort_unstable();
        candidates.dedup();
        candidates.into_iter().filter_map(move |i| {
            let t = &self.triangles[i as usize];
            if (p + margin).cmplt(t.lo).any() || (p - margin).cmpgt(t.hi).any() {
                return None;
            }
            height_within(&t.corners, p, margin).map(|z| (z, t))
        })
    }
}

/// |∂z/∂x|, |∂z/∂y| of the triangle's plane (the triangle not seen edge-on).
fn plane_slope(c: &[DVec3; 3]) -> DVec2 {
    let n = (c[1] - c[0]).cross(c[2] - c[0]);
    DVec2::new(-n.x / n.z, -n.y / n.z).abs()
}

/// z of the triangle's plane over p when p lies inside its xy projection (edges included);
/// None outside or for a triangle seen edge-on.
fn height_at(c: &[DVec3; 3], p: DVec2) -> Option<f64> {
    height_within(c, p, 0.0)
}

/// As [`height_at`], with the triangle grown by `margin` (a distance) on every side.
fn height_within(c: &[DVec3; 3], p: DVec2, margin: f64) -> Option<f64> {
    let [a, b, d] = c.map(|v| v.truncate());
    let area = (b - a).perp_dot(d - a);
    if area == 0.0 {
        return None;
    }
    let w = [(d, b), (a, d), (b, a)].map(|(from, to)| (from - to).perp_dot(p - to) / area);
    let inside = [(d, b), (a, d), (b, a)]
        .iter()
        .zip(w)
        .all(|((from, to), wi)| wi * area.abs() / (*from - *to).length() >= -margin);
    inside.then(|| w[0] * c[0].z + w[1] * c[1].z + w[2] * c[2].z)
}

fn posed_triangles(scene: &Scene, frame: DMat4) -> Vec<Triangle> {
    let bases = scene.label_bases().expect("labels fit");
    let mut out = Vec::new();
    for (k, (object, base)) in scene.objects.iter().zip(bases).enumerate() {
        let m = frame * object.pose;
        for (tri, &surface) in object.mesh.triangles.iter().zip(&object.mesh.triangle_surfaces) {
            let corners = tri.map(|v| m.transform_point3(object.mesh.vertex(v)));
            let lo = corners.iter().fold(DVec2::splat(f64::INFINITY), |m, c| m.min(c.truncate()));
            let hi = corners.iter().fold(DVec2::splat(f64::NEG_INFINITY), |m, c| m.max(c.truncate()));
            let vertices = tri.map(|v| (k, object.mesh.positions[v as usize].map(f32::to_bits)));
            out.push(Triangle { corners, vertices, label: base + surface, lo, hi });
        }
    }
    out
}

pub fn reference_render(scene: &Scene) -> Reference {
    let s = &scene.sensor.scanner().expect("the reference renders the paper's scanner");
    let (width, height) = (s.width as usize, s.height as usize);
    let theta = s.theta_deg.to_radians();
    let range = VerticalCaster::new(posed_triangles(scene, DMat4::IDENTITY));
    let to_camera = DMat4::from_rotation_y(-theta);
    let scale = range.triangles.iter().flat_map(|t| t.corners).fold(1.0f64, |m, c| m.max(c.abs().max_element()));
    let self_hit = 1e-9 * scale;
    let d_cam = s.camera_direction();

    let mut reference = Reference {
        width,
        height,
        label: vec![0; width * height],
        z: vec![0.0; width * height],
        lit_normal: vec![DVec3::ZERO; width * height],
        z_bracket: vec![(0.0, 0.0); width * height],
        z_bracket_surface: vec![(0.0, 0.0); width * height],
        occluded: vec![false; width * height],
        camera_label: vec![0; width * height],
        near_camera_edge: vec![false; width * height],
        tied: vec![false; width * height],
        camera: VerticalCaster::new(posed_triangles(scene, to_camera)),
    };
    let tie = TIE_RELATIVE * scale;
    let first_seen = |p: DVec2| reference.camera.front(p, tie).map_or(0, |(_, l, _)| l);
    for row in 0..height {
        for col in 0..width {
            let i = row * width + col;
            let x = s.origin[0] + col as f64 * s.pitch[0];
            let y = s.origin[1] - row as f64 * s.pitch[1];
            let Some((z, label, t)) = range.front(DVec2::new(x, y), tie) else { continue };
            reference.label[i] = label;
            reference.z[i] = z;
            reference.tied[i] = range.hits(DVec2::new(x, y)).filter(|h| h.0 >= z - tie).count() > 1;
            let [a, b, c] = t.corners;
            let normal = (b - a).cross(c - a).normalize();
            let lit_side = normal * normal.z.signum();
            reference.lit_normal[i] = lit_side;
            let snap = SNAP_PIXELS * s.pitch[0].min(s.pitch[1]);
            let planes: Vec<(f64, u32)> = range
                .near(DVec2::new(x, y), snap)
                .filter(|(_, n)| n.vertices.iter().any(|v| t.vertices.contains(v)))
                .map(|(zn, n)| (zn, n.label))
                .collect();
            let bracket = |planes: &mut dyn Iterator<Item = &(f64, u32)>| {
                planes.fold((z, z), |(lo, hi), &(zn, _)| (lo.min(zn), hi.max(zn)))
            };
            reference.z_bracket[i] = bracket(&mut planes.iter());
            reference.z_bracket_surface[i] = bracket(&mut planes.iter().filter(|p| p.1 == label));
            let p = to_camera.transform_point3(DVec3::new(x, y, z));
            reference.occluded[i] = lit_side.dot(d_cam) <= FACING_TOLERANCE
                || reference.camera.hits(p.truncate()).any(|(zc, _, _)| zc > p.z + self_hit);
            let seen = [-1.0, 0.0, 1.0].map(|k| first_seen(p.truncate() + DVec2::new(k * s.pitch[0], 0.0)));
            reference.camera_label[i] = seen[1];
            reference.near_camera_edge[i] = seen.iter().any(|&l| l != seen[0]);
        }
    }
    reference
}

/// The label test as rangesynth runs it (docs/design.md "The shadow test"), evaluated on the
/// reference's exact geometry: p' = R_y(−θ)·p of each range pixel's point; the shadow view's
/// pixels on the lattice of `Sensor::shadow_grid` (the range view's rows; columns `pitch /
/// columns` apart through the rotated range origin at the local origin's depth); each shadow
/// pixel showing the label of the front surface the camera sees at its centre; a range pixel
/// kept where the nearest shadow pixel (or, with `2x2`, any of the four around p') shows its
/// label. It shares with the GPU's test only the lattice, whose depth it takes from the
/// product's public `depth_bounds` and `ViewGrid::local_origin` (a convention; that a scene
/// moved with its sensor keeps its columns is checked by stability.rs). Columns past the
/// shadow view's (which p' of a range pixel cannot reach: they cover the range image's
/// footprint at every depth of the scene) are read as the camera sees there.
pub struct LabelTest {
    /// The labels the test keeps (0 where it shadows), wherever it is decided.
    pub label: Vec<u32>,
    /// Where it is not decided by exact geometry but by rounding: p' within the f32 error of its
    /// z and arithmetic of a boundary between shadow pixels, or a shadow pixel read whose
    /// centre lies within a rasterizer's sub-pixel snapping of a change of label (or on
    /// coincident faces) — unless every way it may go gives the same answer.
    pub undecided: Vec<bool>,
}

/// How far, in shadow pixels, the GPU's f32 arithmetic may move p' (offsets from the local
/// origin of at most a few hundred pixels, a few roundings each: ~1e-5), with a margin: for
/// images up to about a thousand pixels a side.
const LATTICE_SLACK_PIXELS: f64 = 1e-4;

/// Relative error of the range view's z the conformance suite allows across the surface (its
/// `Z_TOLERANCE`, times |n_z|): how far the GPU's p' may lie from the reference's.
const Z_SLACK_RELATIVE: f64 = 1e-5;

/// The label test of `scene`'s shadow settings on the reference's geometry ([`LabelTest`]).
pub fn label_test(scene: &Scene, reference: &Reference) -> LabelTest {
    use rangesynth::shadow::Neighbourhood;
    let s = &scene.sensor.scanner().expect("the reference renders the paper's scanner");
    let theta = s.theta_deg.to_radians();
    let (c, sn) = (theta.cos(), theta.sin());
    let camera = &reference.camera;
    let scale = camera.triangles.iter().flat_map(|t| t.corners).fold(1.0f64, |m, c| m.max(c.abs().max_element()));
    // The GPU's ties (shaders/raster/draw.glsl tie_depth) give a surface up to TIE_RELATIVE of
    // the view's scale behind the nearest to the lower label: both may show, with a margin.
    let tie = 2.0 * rangesynth::exact::TIE_RELATIVE * scale;
    let (w, h) = (reference.width, reference.height);

    // The lattice: through the rotated range origin at the depth of the range view's local
    // origin, itself the centre of the depth bounds of the objects the range view can show.
    let full_range = s.range_grid((0.0, 0.0));
    let spheres = scene.objects.iter().map(|o| {
        let (centre, radius) = o.mesh.bounding_sphere();
        (o.pose.transform_point3(centre), radius)
    });
    let seen = spheres.filter(|&(centre, radius)| full_range.footprint(centre, radius, 1).is_some());
    let lattice_z = s.range_grid(rangesynth::sensor::depth_bounds(seen)).local_origin().z;
    let anchor = c * s.origin[0] - sn * lattice_z;
    let dx = s.pitch[0] / f64::from(scene.shadow.columns);
    let dy = s.pitch[1];

    // The labels a shadow pixel may show, once a rasterizer has snapped the corners of the
    // triangles about its centre: those of the triangles that may cover the centre and may
    // then lie in front of every triangle that surely covers it (covers the whole square of
    // the snapping), each plane's z there uncertain by its slope times the snapping; and no
    // surface (0) where none surely covers it.
    let shows = |column: i64, row: i64| -> Vec<u32> {
        let centre = DVec2::new(anchor + column as f64 * dx, s.origin[1] - row as f64 * dy);
        let snap = DVec2::new(dx, dy) * SNAP_PIXELS;
        let square =
            [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)].map(|(kx, ky)| centre + snap * DVec2::new(kx, ky));
        let candidates: Vec<(f64, f64, u32, bool)> = camera
            .near(centre, snap.length())
            .map(|(z, t)| {
                let slope = plane_slope(&t.corners);
                let e = slope.x * snap.x + slope.y * snap.y + tie;
                let covers = square.iter().all(|&p| height_at(&t.corners, p).is_some());
                (z - e, z + e, t.label, covers)
            })
            .collect();
        let front = candidates.iter().filter(|c| c.3).map(|c| c.0).max_by(f64::total_cmp);
        let mut labels: Vec<u32> = candidates.iter().filter(|c| front.is_none_or(|f| c.1 >= f)).map(|c| c.2).collect();
        if front.is_none() {
            labels.push(0);
        }
        labels.sort_unstable();
        labels.dedup();
        labels
    };
    // Some(true) where a shadow pixel surely shows `label`, Some(false) where it surely does not.
    // Rows outside the image are outside the shadow view, which shows nothing there.
    let surely_shows = |column: i64, row: i64, label: u32| {
        if !(0..h as i64).contains(&row) {
            return Some(false);
        }
        let labels = shows(column, row);
        match (labels.contains(&label), labels.len()) {
            (true, 1) => Some(true),
            (false, _) => Some(false),
            _ => None,
        }
    };
    // The answers every way the test may go agree: that answer, else None.
    let agreed = |answers: &mut dyn Iterator<Item = Option<bool>>| {
        let mut all = None;
        for a in answers {
            match (a, all) {
                (None, _) => return None,
                (Some(a), Some(b)) if a != b => return None,
                (Some(a), _) => all = Some(a),
            }
        }
        all
    };

    let mut test = LabelTest { label: vec![0; w * h], undecided: vec![false; w * h] };
    for row in 0..h {
        for col in 0..w {
            let i = row * w + col;
            let label = reference.label[i];
            if label == 0 {
                continue;
            }
            let x = s.origin[0] + col as f64 * s.pitch[0];
            // The shadow-frame column p' may fall on, over the z the GPU may rightly hold where
            // it shows the reference's surface (the only pixels the test is checked on).
            let (lo, hi) = reference.z_bracket_surface[i];
            let slack = Z_SLACK_RELATIVE * reference.z[i].abs().max(1.0) / reference.lit_normal[i].z.max(1e-6);
            let at = |z: f64| (c * x - sn * z - anchor) / dx;
            let (u0, u1) = (at(hi + slack), at(lo - slack));
            let (u0, u1) = (u0.min(u1) - LATTICE_SLACK_PIXELS, u0.max(u1) + LATTICE_SLACK_PIXELS);
            let row = row as i64;
            let lit = match scene.shadow.neighbourhood {
                Neighbourhood::Nearest => {
                    let columns = (u0 + 0.5).floor() as i64..=(u1 + 0.5).floor() as i64;
                    agreed(&mut columns.map(|k| surely_shows(k, row, label)))
                }
                // The four around p': its row lies on a row of centres, so the GPU's f32 row
                // may put the square's first row at either.
                Neighbourhood::Square2 => {
                    let corners = (u0.floor() as i64..=u1.floor() as i64)
                        .flat_map(|k| [(k, row - 1), (k, row)])
                        .collect::<Vec<_>>();
                    agreed(&mut corners.into_iter().map(|(k, r)| {
                        let four =
                            [(k, r), (k + 1, r), (k, r + 1), (k + 1, r + 1)].map(|(k, r)| surely_shows(k, r, label));
                        if four.contains(&Some(true)) {
                            Some(true)
                        } else if four.iter().all(|&a| a == Some(false)) {
                            Some(false)
                        } else {
                            None
                        }
                    }))
                }
            };
            match lit {
                Some(lit) => test.label[i] = if lit { label } else { 0 },
                None => test.undecided[i] = true,
            }
        }
    }
    test
}
