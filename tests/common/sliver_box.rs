//! A unit box whose faces are cut into slivers, and the faces a ray meets on the box by its
//! geometry alone (a slab test), as independent of the tessellation as of the renderer: the
//! oracle for the slivers tests (tests/stability.rs, tests/rigs.rs).

use glam::{DMat4, DVec3};
use rangesynth::mesh::Mesh;

/// The unit cube of `builtin:box` with each face cut into `strips` strips along one side, so
/// every triangle is a sliver of aspect ratio about `strips`. Surfaces are its six faces, in
/// builtin:box's order; returns the mesh and each face's outward normal.
pub fn sliver_box(strips: u32) -> (Mesh, Vec<DVec3>) {
    let (lo, hi) = (DVec3::new(-0.5, -0.5, 0.0), DVec3::new(0.5, 0.5, 1.0));
    let corner = |x: usize, y: usize, z: usize| DVec3::new([lo.x, hi.x][x], [lo.y, hi.y][y], [lo.z, hi.z][z]);
    // Faces as (name, counter-clockwise corners seen from outside, normal).
    let faces = [
        ("top", [corner(0, 0, 1), corner(1, 0, 1), corner(1, 1, 1), corner(0, 1, 1)], DVec3::Z),
        ("bottom", [corner(0, 0, 0), corner(0, 1, 0), corner(1, 1, 0), corner(1, 0, 0)], -DVec3::Z),
        ("+x", [corner(1, 0, 0), corner(1, 1, 0), corner(1, 1, 1), corner(1, 0, 1)], DVec3::X),
        ("-x", [corner(0, 0, 0), corner(0, 0, 1), corner(0, 1, 1), corner(0, 1, 0)], -DVec3::X),
        ("+y", [corner(0, 1, 0), corner(0, 1, 1), corner(1, 1, 1), corner(1, 1, 0)], DVec3::Y),
        ("-y", [corner(0, 0, 0), corner(1, 0, 0), corner(1, 0, 1), corner(0, 0, 1)], -DVec3::Y),
    ];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut surfaces = Vec::new();
    for (s, (_, [a, b, c, d], _)) in faces.iter().enumerate() {
        let vertex = |p: DVec3, positions: &mut Vec<[f64; 3]>| {
            positions.push(p.to_array());
            positions.len() as u32 - 1
        };
        for k in 0..strips {
            let t = |k: u32| f64::from(k) / f64::from(strips);
            let p0 = vertex(a.lerp(*b, t(k)), &mut positions);
            let p1 = vertex(a.lerp(*b, t(k + 1)), &mut positions);
            let q1 = vertex(d.lerp(*c, t(k + 1)), &mut positions);
            let q0 = vertex(d.lerp(*c, t(k)), &mut positions);
            triangles.extend([[p0, p1, q1], [p0, q1, q0]]);
            surfaces.extend([s as u32 + 1; 2]);
        }
    }
    let names = faces.iter().map(|f| f.0.to_string()).collect();
    let mesh =
        Mesh::new(format!("sliver box ({strips} strips a face)"), positions, triangles, surfaces, names).unwrap();
    (mesh, faces.iter().map(|f| f.2).collect())
}

/// The face of `sliver_box` (its surface index, 0-based, in its order: top, bottom, +x, −x,
/// +y, −y) that the ray `origin + t·direction` (t > 0) enters first, and that t, the box
/// posed by `pose`: the slab method in the box's frame, where it spans [−½, ½]² × [0, 1].
pub fn box_face_hit(pose: DMat4, origin: DVec3, direction: DVec3) -> Option<(usize, f64)> {
    let to_box = pose.inverse();
    let (origin, direction) = (to_box.transform_point3(origin), to_box.transform_vector3(direction));
    let (lo, hi) = (DVec3::new(-0.5, -0.5, 0.0), DVec3::new(0.5, 0.5, 1.0));
    let (mut near, mut far, mut face) = (f64::NEG_INFINITY, f64::INFINITY, None);
    for (axis, (low_face, high_face)) in [(2, (1, 0)), (0, (3, 2)), (1, (5, 4))] {
        let (o, d) = (origin[axis], direction[axis]);
        if d.abs() < 1e-12 {
            if o < lo[axis] || o > hi[axis] {
                return None;
            }
            continue;
        }
        let (t_lo, t_hi) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
        let (entry, entry_face) = if t_lo < t_hi { (t_lo, low_face) } else { (t_hi, high_face) };
        if entry > near {
            (near, face) = (entry, Some(entry_face));
        }
        far = far.min(t_lo.max(t_hi));
    }
    face.filter(|_| near <= far && near > 0.0).map(|face| (face, near))
}
