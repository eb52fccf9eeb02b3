//! Independent CPU reference for rigs (docs/sensors-and-rigs.md): every ray tested against
//! every triangle in f64 (Möller–Trumbore, edges included), no hierarchy. Shares nothing with
//! the product but the scene description and the documented tolerances.
//!
//! A pinhole reference view's ray through pixel (c, r) is ((c − cx)/fx, (r − cy)/fy, 1) from
//! its centre, an orthographic one's runs down −z through the pixel centre (x0 + c·dx,
//! y0 − r·dy) from above the scene; its first hit p (the tie rule: hits within the tie distance of the nearest go
//! to the lowest label) is seen by a witness when p's surface faces it (the side the
//! reference sees, by more than the facing tolerance), p projects onto the witness's image
//! (pinhole), and no triangle meets the segment from p to its centre (pinhole) or the ray
//! along its direction (directional) farther than the tie distance from p.

use glam::{DMat3, DVec3};
use rangesynth::sensor::{Direction, View, WitnessGeometry};
use rangesynth::Scene;

/// Distances this close, relative to the scene's largest coordinate, are a tie.
const TIE_RELATIVE: f64 = 1e-9;
/// n · (unit toward the witness) at or below which a surface is turned away from it.
const FACING_TOLERANCE: f64 = 1e-9;

pub struct RigReference {
    pub width: u32,
    pub height: u32,
    /// Label of the first hit, 0 for none.
    pub label: Vec<u32>,
    /// Depth of the first hit (0 for none): along a pinhole view's optical axis, or an
    /// orthographic view's z.
    pub depth: Vec<f64>,
    /// Bit k: witness k does not see the hit.
    pub witness: Vec<u32>,
}

struct Triangle {
    corners: [DVec3; 3],
    label: u32,
}

/// The ray `origin + t·direction` against a triangle: its t, edges included.
fn intersect(t: &Triangle, origin: DVec3, direction: DVec3) -> Option<f64> {
    let [a, b, c] = t.corners;
    let (e1, e2) = (b - a, c - a);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = direction.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then(|| e2.dot(q) / det)
}

/// Renders the scene's rig by brute force.
pub fn rig_reference(scene: &Scene) -> RigReference {
    let (width, height) = match scene.sensor.reference {
        View::Pinhole(view) => (view.intrinsics.width, view.intrinsics.height),
        View::Orthographic(view) => (view.width, view.height),
        _ => panic!("the reference knows no such view"),
    };
    let bases = scene.label_bases().expect("labels fit");
    let mut triangles = Vec::new();
    for (object, base) in scene.objects.iter().zip(bases) {
        for (tri, &surface) in object.mesh.triangles.iter().zip(&object.mesh.triangle_surfaces) {
            let corners = tri.map(|v| object.pose.transform_point3(object.mesh.vertex(v)));
            triangles.push(Triangle { corners, label: base + surface });
        }
    }
    let scale = triangles.iter().flat_map(|t| t.corners).fold(1.0f64, |m, c| m.max(c.abs().max_element()));
    let tie = TIE_RELATIVE * scale;
    let n = (width * height) as usize;
    let mut out = RigReference { width, height, label: vec![0; n], depth: vec![0.0; n], witness: vec![0; n] };
    let top = 2.0 * scale;
    for row in 0..height {
        for col in 0..width {
            // The ray (origin, direction), the range of its parameter t that is seen, and the
            // depth at t: a pinhole view's Z = t; an orthographic view's z, from above the scene.
            let (origin, ray, seen, orthographic) = match scene.sensor.reference {
                View::Pinhole(view) => {
                    let k = view.intrinsics;
                    let ray = DVec3::new((f64::from(col) - k.cx) / k.fx, (f64::from(row) - k.cy) / k.fy, 1.0);
                    (DVec3::ZERO, ray, (view.near, view.far), false)
                }
                View::Orthographic(view) => {
                    let x = view.origin[0] + f64::from(col) * view.pitch[0];
                    let y = view.origin[1] - f64::from(row) * view.pitch[1];
                    (DVec3::new(x, y, top), DVec3::NEG_Z, (0.0, f64::INFINITY), true)
                }
                _ => panic!("the reference knows no such view"),
            };
            let hits: Vec<(f64, &Triangle)> = triangles
                .iter()
                .filter_map(|t| intersect(t, origin, ray).map(|d| (d, t)))
                .filter(|&(d, _)| d >= seen.0 && d <= seen.1)
                .collect();
            let Some(nearest) = hits.iter().map(|h| h.0).min_by(f64::total_cmp) else { continue };
            let (t, hit) = hits.iter().filter(|h| h.0 <= nearest + tie).min_by_key(|h| h.1.label).copied().unwrap();
            let p = origin + t * ray;
            let depth = if orthographic { p.z } else { t };
            let [a, b, c] = hit.corners;
            let normal = (b - a).cross(c - a).normalize();
            let lit = if normal.dot(-ray) > 0.0 { normal } else { -normal };
            let mut bits = 0;
            for (w, witness) in scene.sensor.witnesses.iter().enumerate() {
                let (toward, reach, in_view) = match witness.geometry {
                    WitnessGeometry::Pinhole { pose, intrinsics: wk } => {
                        let centre = pose.w_axis.truncate();
                        let q = DMat3::from_mat4(pose).transpose() * (p - centre);
                        let (u, v) = (wk.fx * q.x / q.z + wk.cx, wk.fy * q.y / q.z + wk.cy);
                        let on_image = q.z > 0.0
                            && u >= -0.5
                            && u < f64::from(wk.width) - 0.5
                            && v >= -0.5
                            && v < f64::from(wk.height) - 0.5;
                        (centre - p, 1.0, on_image)
                    }
                    WitnessGeometry::Directional(d) => {
                        let d = match d {
                            Direction::Vector(d) => d,
                            Direction::Tilt { theta_deg } => {
                                let t = theta_deg.to_radians();
                                DVec3::new(t.sin(), 0.0, t.cos())
                            }
                        };
                        (d, f64::INFINITY, true)
                    }
                    _ => panic!("the reference knows no such witness"),
                };
                let length = toward.length();
                let faces = lit.dot(toward / length) > FACING_TOLERANCE;
                let blocked =
                    triangles.iter().filter_map(|t| intersect(t, p, toward)).any(|s| s * length > tie && s <= reach);
                if !(faces && in_view && !blocked) {
                    bits |= 1 << w;
                }
            }
            let i = (row * width + col) as usize;
            (out.label[i], out.depth[i], out.witness[i]) = (hit.label, depth, bits);
        }
    }
    out
}
