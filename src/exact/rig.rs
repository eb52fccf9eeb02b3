//! Shadow modes `exact` and `none` under any rig (src/sensor/): the reference view's ray
//! through each pixel centre finds the first surface point p, and in mode `exact` p is tested
//! against every witness in f64, as the paper's rule says: p is measured only if each witness
//! sees it. A witness sees p when p's surface faces it (the side the reference view sees
//! turns toward it by more than [`FACING_TOLERANCE`]), p lies in its field of view, and
//! nothing lies between them: along its direction for a directional witness (a vertical cast
//! in a frame that turns that direction onto +z, as the scanner's camera is tested), or on the
//! open segment to its centre for a pinhole one (a ray cast in the reference frame). Surfaces
//! within the tie distance of p do not hide it (src/exact/mod.rs). A directional witness's
//! caster leaves out a solid's triangles facing away from it, as the scanner's casters do; the
//! reference view's triangles serve every pinhole view at once, whose rays each turn a
//! different side of a triangle away, and keep them all.

use super::ray_caster::RayCaster;
use super::{
    cast_image, posed_triangles, ExactImage, ExactObject, ExactPixel, Triangle, VerticalCaster, FACING_TOLERANCE,
};
use crate::error::{Error, Result};
use crate::sensor::{Direction, PixelRect, Sensor, View, WitnessGeometry};
use crate::shader_contract::TIE_RELATIVE;
use glam::{DMat4, DQuat, DVec2, DVec3};

/// How a witness is tested.
enum WitnessTest {
    /// Parallel rays: the scene in a frame where they run down −z from +z.
    Directional { frame: DMat4, caster: Box<VerticalCaster> },
    /// A centre: segments to it in the reference frame, and its field of view
    /// (`Witness::in_view`).
    Pinhole,
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
    let triangles = posed_triangles(objects, DMat4::IDENTITY, false);
    let scale = triangles.iter().flat_map(|t| t.corners).fold(1.0f64, |m, c| m.max(c.abs().max_element()));
    if !scale.is_finite() {
        return Err(Error::Scene("an object is posed too far away for exact ray casting".into()));
    }
    let tie = TIE_RELATIVE * scale;
    let witnesses: &[_] = if test_witnesses { &sensor.witnesses } else { &[] };
    let pinhole_witness = witnesses.iter().any(|w| matches!(w.geometry, WitnessGeometry::Pinhole { .. }));
    let pinhole_reference = matches!(sensor.reference, View::Pinhole(_));
    let rays = (pinhole_reference || pinhole_witness).then(|| RayCaster::new(triangles.clone(), tie));
    let vertical = (!pinhole_reference).then(|| VerticalCaster::new(triangles));
    let tests: Vec<WitnessTest> = witnesses
        .iter()
        .map(|w| match w.geometry {
            WitnessGeometry::Directional(direction) => {
                let frame = directional_frame(direction);
                WitnessTest::Directional {
                    caster: Box::new(VerticalCaster::new(posed_triangles(objects, frame, true))),
                    frame,
                }
            }
            WitnessGeometry::Pinhole { .. } => WitnessTest::Pinhole,
        })
        .collect();
    // What the reference ray of pixel (col, row) meets first: its point, depth and triangle.
    let first_hit = |col: u32, row: u32| -> Option<(DVec3, f64, &Triangle)> {
        match (&sensor.reference, &vertical, &rays) {
            (View::Orthographic(o), Some(vertical), _) => {
                let (x, y) = o.pixel_centre(col, row);
                vertical.front(DVec2::new(x, y), tie).map(|(z, t)| (DVec3::new(x, y, z), z, t))
            }
            (View::Pinhole(p), _, Some(rays)) => {
                let d = p.intrinsics.ray(col, row);
                // A point on the plane of the view's centre (Z = 0) is not in front of it.
                let near = p.near.max(f64::MIN_POSITIVE);
                rays.front(DVec3::ZERO, d, (near, p.far), tie).map(|(z, t)| (z * d, z, t))
            }
            _ => unreachable!("the reference view's caster is built above"),
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
                    WitnessTest::Pinhole => {
                        let in_view = witness.in_view(p);
                        let rays = rays.as_ref().expect("built for pinhole witnesses");
                        in_view && !rays.hits(p, toward * distance, 1.0).any(|(t, _, _)| t * distance > tie)
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
