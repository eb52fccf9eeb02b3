//! Shadow modes `exact` and `none` under any rig (src/sensor/): the reference view's ray
//! through each pixel centre finds the first surface point p, and in mode `exact` p is tested
//! against every witness in f64, as the paper's rule says: p is measured only if each witness
//! sees it. A witness sees p when p's surface faces it (the side the reference view sees
//! turns toward it by more than [`FACING_TOLERANCE`]), p lies in its field of view, and
//! nothing lies between them: along its direction for a directional witness (a vertical cast
//! in a frame that turns that direction onto +z, as the scanner's camera is tested), or on the
//! open segment to its centre for a pinhole one (a ray cast in the reference frame). Surfaces
//! within the tie distance of p do not hide it (src/exact/mod.rs). Each view has a caster of its
//! own, which leaves out a solid's triangles facing away from where its rays come from (the
//! reference view's centre or direction, a witness's): a segment from p crosses a solid that
//! does not hold the witness's centre through a face turned toward it.

use super::ray_caster::RayCaster;
use super::{
    cast_image, posed_triangles, Cull, ExactImage, ExactObject, ExactPixel, Triangle, VerticalCaster, FACING_TOLERANCE,
};
use crate::error::{Error, Result};
use crate::sensor::{Direction, PixelRect, Sensor, View, WitnessGeometry};
use crate::shader_contract::TIE_RELATIVE;
use glam::{DMat4, DQuat, DVec2, DVec3};
use rayon::prelude::*;

/// How a witness is tested.
enum WitnessTest {
    /// Parallel rays: the scene in a frame where they run down −z from +z.
    Directional { frame: DMat4, caster: Box<VerticalCaster> },
    /// A centre: segments to it in the reference frame, against the triangles that do not
    /// face away from it, and its field of view (`Witness::in_view`).
    Pinhole(Box<RayCaster>),
}

/// What casts the reference view's rays: down −z (orthographic), or from its centre.
enum ReferenceCaster {
    Vertical(VerticalCaster),
    Rays(RayCaster),
}

/// The frame in which rays arriving from `direction` run down −z: the scanner's `R_y(−θ)`
/// for `theta_deg`, the shortest rotation of `direction` onto +z otherwise.
fn directional_frame(direction: Direction) -> DMat4 {
    match direction {
        Direction::Tilt { theta_deg } => DMat4::from_rotation_y(-theta_deg.to_radians()),
        Direction::Vector(d) => DMat4::from_quat(DQuat::from_rotation_arc(d.normalize(), DVec3::Z)),
    }
}

/// Casts the reference view's ray at every pixel centre of `region` and, where
/// `test_witnesses`, tests each point against every witness. Bit k of the image's `witness` is set where witness k
/// does not see the point.
pub fn render_rig(
    sensor: &Sensor,
    objects: &[ExactObject],
    test_witnesses: bool,
    region: PixelRect,
) -> Result<ExactImage> {
    sensor.validate()?;
    // Each view's caster, built side by side, without the triangles of solids that face away
    // from its rays. The reference view's are posed first: their scale gives the tie distance.
    let reference_cull = match sensor.reference {
        View::Orthographic(_) => Cull::AwayFromZ,
        View::Pinhole(p) => Cull::AwayFrom { centre: DVec3::ZERO, near: Some(p.near) },
    };
    let (reference_triangles, scale) = posed_triangles(objects, DMat4::IDENTITY, reference_cull);
    if !scale.is_finite() {
        return Err(Error::Scene("an object is posed too far away for exact ray casting".into()));
    }
    let tie = TIE_RELATIVE * scale;
    let witnesses: &[_] = if test_witnesses { &sensor.witnesses } else { &[] };
    let reference = move || match sensor.reference {
        View::Orthographic(_) => ReferenceCaster::Vertical(VerticalCaster::new(reference_triangles)),
        View::Pinhole(_) => ReferenceCaster::Rays(RayCaster::new(reference_triangles, tie)),
    };
    let tests = || -> Vec<WitnessTest> {
        witnesses
            .par_iter()
            .map(|w| match w.geometry {
                WitnessGeometry::Directional(direction) => {
                    let frame = directional_frame(direction);
                    let caster = VerticalCaster::new(posed_triangles(objects, frame, Cull::AwayFromZ).0);
                    WitnessTest::Directional { caster: Box::new(caster), frame }
                }
                WitnessGeometry::Pinhole { pose, .. } => {
                    let cull = Cull::AwayFrom { centre: pose.w_axis.truncate(), near: None };
                    WitnessTest::Pinhole(Box::new(RayCaster::new(
                        posed_triangles(objects, DMat4::IDENTITY, cull).0,
                        tie,
                    )))
                }
            })
            .collect()
    };
    let (reference, tests) = rayon::join(reference, tests);
    // What the reference ray of pixel (col, row) meets first: its point, depth and triangle.
    let first_hit = |col: u32, row: u32| -> Option<(DVec3, f64, &Triangle)> {
        match (&sensor.reference, &reference) {
            (View::Orthographic(o), ReferenceCaster::Vertical(vertical)) => {
                let (x, y) = o.pixel_centre(col, row);
                vertical.front(DVec2::new(x, y), tie).map(|(z, t)| (DVec3::new(x, y, z), z, t))
            }
            (View::Pinhole(p), ReferenceCaster::Rays(rays)) => {
                let d = p.intrinsics.ray(col, row);
                // A point on the plane of the view's centre (Z = 0) is not in front of it.
                let near = p.near.max(f64::MIN_POSITIVE);
                rays.front(DVec3::ZERO, d, (near, p.far), tie).map(|(z, t)| (z * d, z, t))
            }
            _ => unreachable!("the reference view's caster is built for its kind above"),
        }
    };
    // The witnesses that do not see p (bits), whose surface has unit normal `lit` on the side
    // the reference view sees.
    let lost_by = |p: DVec3, lit: DVec3| -> u32 {
        let mut bits = 0;
        for (k, (witness, test)) in witnesses.iter().zip(&tests).enumerate() {
            let (toward, distance) = witness.toward(p);
            let seen = lit.dot(toward) > FACING_TOLERANCE
                && match test {
                    WitnessTest::Directional { frame, caster } => {
                        let q = frame.transform_point3(p);
                        !caster.hits(q.truncate()).any(|(above, _, _)| above > q.z + tie)
                    }
                    WitnessTest::Pinhole(rays) => {
                        witness.in_view(p) && !rays.hits(p, toward * distance, 1.0).any(|(t, _, _)| t * distance > tie)
                    }
                };
            if !seen {
                bits |= 1 << k;
            }
        }
        bits
    };
    let toward_reference = |p: DVec3| match sensor.reference {
        View::Orthographic(_) => DVec3::Z,
        View::Pinhole(_) => -p,
    };
    let cast = |col: u32, row: u32| -> ExactPixel {
        let Some((p, z, triangle)) = first_hit(col, row) else {
            return ExactPixel::default();
        };
        let [a, b, c] = triangle.corners;
        let normal = (b - a).cross(c - a).normalize();
        let lit = normal * normal.dot(toward_reference(p)).signum();
        // A face along the reference's rays (n.z = 0), which a pinhole view's off-axis rays can
        // meet, has an infinite gradient, or an indeterminate component where n's other one is
        // 0 too: 0 there, so that no NaN reaches the effects.
        let gradient = [-normal.x / normal.z, -normal.y / normal.z].map(|g| if g.is_nan() { 0.0 } else { g });
        ExactPixel { label: triangle.label, z, gradient, lost_by: lost_by(p, lit) }
    };
    Ok(cast_image((sensor.width(), sensor.height()), region, cast))
}
