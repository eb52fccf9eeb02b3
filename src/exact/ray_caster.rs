//! Rays in any direction, in f64, for the views that do not look down one axis: a pinhole
//! reference view's pixel rays and the segments from a point to a pinhole witness's centre.
//! A hierarchy (parry3d-f64's) over the triangles' bounds finds the candidates along a ray;
//! each is tested exactly: the ray meets a triangle where it passes on the same side of all
//! three edges, edges included (signed volumes, so that two triangles sharing an edge see it
//! with opposite signs and no ray slips between them), at the parameter where it meets the
//! triangle's plane.

use super::Triangle;
use glam::DVec3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Vector as BvhVector;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::query::{Ray, RayCast};

pub(super) struct RayCaster {
    triangles: Vec<Triangle>,
    bvh: Bvh,
}

fn to_bvh(v: DVec3) -> BvhVector {
    BvhVector::new(v.x, v.y, v.z)
}

impl RayCaster {
    /// Triangles in the frame the rays are given in; bounds are widened by `margin` so that a
    /// flat triangle's box has thickness.
    pub fn new(triangles: Vec<Triangle>, margin: f64) -> Self {
        let bounds: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.corners;
                Aabb::new(to_bvh(a.min(b).min(c) - margin), to_bvh(a.max(b).max(c) + margin))
            })
            .collect();
        Self { bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &bounds), triangles }
    }

    /// (t, index, triangle) of every triangle the ray `origin + t·direction` meets with
    /// `t` in [0, `t_max`].
    pub fn hits(
        &self,
        origin: DVec3,
        direction: DVec3,
        t_max: f64,
    ) -> impl Iterator<Item = (f64, u32, &Triangle)> + '_ {
        let ray = Ray::new(to_bvh(origin), to_bvh(direction));
        let leaves: Vec<u32> = self.bvh.leaves(|node| node.aabb().intersects_local_ray(&ray, t_max)).collect();
        leaves.into_iter().filter_map(move |i| {
            let t = &self.triangles[i as usize];
            ray_parameter(&t.corners, origin, direction).filter(|&s| (0.0..=t_max).contains(&s)).map(|s| (s, i, t))
        })
    }

    /// The nearest surface along the ray with t in [`t_min`, `t_max`]: the smallest t; among
    /// those within `tie` of it, the lowest label, and of that label's triangles the first in
    /// scene order (as the vertical caster decides).
    pub fn front(
        &self,
        origin: DVec3,
        direction: DVec3,
        (t_min, t_max): (f64, f64),
        tie: f64,
    ) -> Option<(f64, &Triangle)> {
        let hits: Vec<(f64, u32, &Triangle)> = self.hits(origin, direction, t_max).filter(|h| h.0 >= t_min).collect();
        let nearest = hits.iter().map(|h| h.0).min_by(f64::total_cmp)?;
        let (t, _, triangle) = hits.into_iter().filter(|h| h.0 <= nearest + tie).min_by_key(|h| (h.2.label, h.1))?;
        Some((t, triangle))
    }
}

/// Where the ray `origin + t·direction` meets the triangle, edges included: its t, or `None`
/// where it passes outside or runs parallel to the triangle's plane.
fn ray_parameter(corners: &[DVec3; 3], origin: DVec3, direction: DVec3) -> Option<f64> {
    let [a, b, c] = corners.map(|v| v - origin);
    // The signed volume each edge spans with the ray: its side of the edge.
    let sides = [direction.dot(a.cross(b)), direction.dot(b.cross(c)), direction.dot(c.cross(a))];
    let inside = sides.iter().all(|&s| s >= 0.0) || sides.iter().all(|&s| s <= 0.0);
    let normal = (b - a).cross(c - a);
    let along = normal.dot(direction);
    (inside && along != 0.0).then(|| normal.dot(a) / along)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(z: f64, label: u32) -> Vec<Triangle> {
        let corner = |x: f64, y: f64| DVec3::new(x, y, z);
        vec![
            Triangle { corners: [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0)], label },
            Triangle { corners: [corner(-1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)], label },
        ]
    }

    /// A ray through the square's diagonal, shared by its two triangles, meets both; rays
    /// along the axes (zero direction components) find the square at its depth.
    #[test]
    fn rays_meet_triangles_at_their_plane_edges_included() {
        let caster = RayCaster::new(square(2.0, 7), 1e-12);
        let hits: Vec<f64> = caster.hits(DVec3::ZERO, DVec3::new(0.25, 0.25, 1.0), 10.0).map(|h| h.0).collect();
        assert_eq!(hits, vec![2.0, 2.0]);
        assert_eq!(caster.front(DVec3::ZERO, DVec3::Z, (0.0, f64::INFINITY), 0.0).map(|h| h.0), Some(2.0));
        // Beyond the edge (x = 1 at z = 2 is direction x = 0.5), or beyond t_max: nothing.
        assert_eq!(caster.hits(DVec3::ZERO, DVec3::new(0.5001, 0.0, 1.0), 10.0).count(), 0);
        assert_eq!(caster.hits(DVec3::ZERO, DVec3::new(0.5, 0.0, 1.0), 10.0).count(), 1);
        assert_eq!(caster.hits(DVec3::ZERO, DVec3::Z, 1.9).count(), 0);
        // A ray from the side, parallel to the plane: no hit.
        assert_eq!(caster.hits(DVec3::new(-5.0, 0.0, 2.0), DVec3::X, 10.0).count(), 0);
    }

    /// Of two coincident squares the lower label wins; of two apart the nearer, whatever
    /// its label; a near limit skips what lies before it.
    #[test]
    fn the_front_is_the_nearest_and_ties_go_to_the_lower_label() {
        let both = |z1: f64, z2: f64| RayCaster::new([square(z1, 9), square(z2, 4)].concat(), 1e-12);
        let label =
            |c: &RayCaster, near: f64| c.front(DVec3::ZERO, DVec3::Z, (near, f64::INFINITY), 1e-9).map(|h| h.1.label);
        assert_eq!(label(&both(2.0, 2.0), 0.0), Some(4));
        assert_eq!(label(&both(2.0, 3.0), 0.0), Some(9));
        assert_eq!(label(&both(2.0, 3.0), 2.5), Some(4));
    }
}
