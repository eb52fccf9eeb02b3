//! The models of `rangesynth experiment`: four built-ins and ten generated parts, each a
//! prism (a polygon, with holes where it has them, extruded along an axis) resting on the
//! table plane z = 0, with one surface per cap and per wall, or one curved side for the
//! cylinders. They are written as OBJ files (one `g` group per surface), so `rangesynth verify`
//! reads the very models the experiment rendered and verified.

use crate::error::{Error, Result};
use crate::io::write_atomically;
use crate::mesh::Mesh;
use earcut::Earcut;
use glam::DVec3;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// The axis a profile is extruded along, and so the plane it is drawn in.
#[derive(Clone, Copy)]
enum Along {
    /// A profile (x, y) extruded from z = 0 up to the depth: blocks, plates, prisms.
    Z,
    /// A profile (x, z) extruded across y ∈ [−depth/2, depth/2]: steps, wedges, brackets.
    Y,
}

/// A generated part: a closed polygon (counter-clockwise), holes (clockwise), an axis and a
/// depth along it. `smooth` walls form one surface (a cylinder's side).
struct Prism {
    outline: Vec<[f64; 2]>,
    holes: Vec<Vec<[f64; 2]>>,
    along: Along,
    depth: f64,
    smooth: bool,
}

/// The generated parts, by name.
fn prisms() -> Vec<(&'static str, Prism)> {
    let rect =
        |w: f64, h: f64| vec![[-w / 2.0, -h / 2.0], [w / 2.0, -h / 2.0], [w / 2.0, h / 2.0], [-w / 2.0, h / 2.0]];
    let profile = |points: &[[f64; 2]], depth: f64| Prism {
        outline: points.to_vec(),
        holes: vec![],
        along: Along::Y,
        depth,
        smooth: false,
    };
    let base = |outline: Vec<[f64; 2]>, depth: f64, smooth: bool| Prism {
        outline,
        holes: vec![],
        along: Along::Z,
        depth,
        smooth,
    };
    let polygon = |sides: u32, radius: f64| -> Vec<[f64; 2]> {
        (0..sides)
            .map(|k| {
                let a = std::f64::consts::TAU * f64::from(k) / f64::from(sides);
                [radius * a.cos(), radius * a.sin()]
            })
            .collect()
    };
    let mut hole = rect(0.6, 0.4);
    hole.reverse();
    vec![
        ("block", base(rect(1.6, 0.8), 0.5, false)),
        ("pillar", base(rect(0.6, 0.6), 1.2, false)),
        (
            "stairs",
            profile(
                &[[-1.2, 0.0], [1.2, 0.0], [1.2, 1.2], [0.4, 1.2], [0.4, 0.8], [-0.4, 0.8], [-0.4, 0.4], [-1.2, 0.4]],
                1.2,
            ),
        ),
        ("wedge", profile(&[[-1.0, 0.0], [1.0, 0.0], [1.0, 0.9]], 1.2)),
        ("l-bracket", profile(&[[-0.9, 0.0], [0.9, 0.0], [0.9, 1.1], [0.65, 1.1], [0.65, 0.25], [-0.9, 0.25]], 1.0)),
        (
            "t-block",
            profile(
                &[[-0.3, 0.0], [0.3, 0.0], [0.3, 0.7], [0.9, 0.7], [0.9, 1.0], [-0.9, 1.0], [-0.9, 0.7], [-0.3, 0.7]],
                0.8,
            ),
        ),
        ("holed plate", Prism { holes: vec![hole], ..base(rect(1.6, 1.2), 0.3, false) }),
        ("hex prism", base(polygon(6, 0.6), 0.7, false)),
        ("disc", base(polygon(32, 0.7), 0.4, true)),
        ("rod", base(polygon(24, 0.3), 1.4, true)),
    ]
}

/// The built-ins the experiment uses beside the generated parts.
pub const BUILTIN_PARTS: [&str; 4] = ["builtin:box", "builtin:step", "builtin:cylinder:32", "builtin:sphere:32"];

impl Prism {
    fn point(&self, [u, v]: [f64; 2], w: f64) -> DVec3 {
        match self.along {
            Along::Z => DVec3::new(u, v, w),
            Along::Y => DVec3::new(u, w - self.depth / 2.0, v),
        }
    }

    fn mesh(&self, name: &str) -> Result<Mesh> {
        let mut positions: Vec<[f64; 3]> = Vec::new();
        let mut triangles = Vec::new();
        let mut surfaces = Vec::new();
        let mut names: Vec<String> = Vec::new();
        let mut add = |name: String, corners: [DVec3; 3]| {
            let id = match names.iter().position(|n| *n == name) {
                Some(i) => i as u32 + 1,
                None => {
                    names.push(name);
                    names.len() as u32
                }
            };
            let first = positions.len() as u32;
            positions.extend(corners.map(|c| c.to_array()));
            triangles.push([first, first + 1, first + 2]);
            surfaces.push(id);
        };
        // Both caps, triangulated with their holes.
        let mut ring: Vec<[f64; 2]> = self.outline.clone();
        let mut hole_starts = Vec::new();
        for hole in &self.holes {
            hole_starts.push(ring.len() as u32);
            ring.extend(hole);
        }
        let mut cap: Vec<u32> = Vec::new();
        Earcut::new().earcut(ring.iter().copied(), &hole_starts, &mut cap);
        let (low, high) = match self.along {
            Along::Z => ("bottom", "top"),
            Along::Y => ("back", "front"),
        };
        for t in cap.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| ring[i as usize]);
            add(low.to_string(), [self.point(a, 0.0), self.point(c, 0.0), self.point(b, 0.0)]);
            add(high.to_string(), [self.point(a, self.depth), self.point(b, self.depth), self.point(c, self.depth)]);
        }
        // The walls: a quad per edge of the outline and of each hole.
        let mut wall = 0;
        for polygon in std::iter::once(&self.outline).chain(&self.holes) {
            for k in 0..polygon.len() {
                let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
                wall += 1;
                let name = if self.smooth { "side".to_string() } else { format!("wall-{wall}") };
                let [p, q, r, s] =
                    [self.point(a, 0.0), self.point(b, 0.0), self.point(b, self.depth), self.point(a, self.depth)];
                add(name.clone(), [p, q, r]);
                add(name, [p, r, s]);
            }
        }
        Mesh::new(name, positions, triangles, surfaces, names)
    }
}

/// Writes `mesh` as an OBJ file: its vertices, then one `g` group per surface, in order.
pub fn write_obj(path: &Path, mesh: &Mesh) -> Result<()> {
    let mut text = format!("# {} (rangesynth experiment)\n", mesh.name);
    for [x, y, z] in (0..mesh.positions.len() as u32).map(|v| mesh.vertex(v).to_array()) {
        writeln!(text, "v {x} {y} {z}").expect("writing to a String");
    }
    for (s, name) in (1..).zip(&mesh.surface_names) {
        writeln!(text, "g {name}").expect("writing to a String");
        for (t, _) in mesh.triangles.iter().zip(&mesh.triangle_surfaces).filter(|(_, &id)| id == s) {
            writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).expect("writing to a String");
        }
    }
    write_atomically(path, |file| file.write_all(text.as_bytes()).map_err(|e| Error::io(path, e)))
}

/// The generated parts' meshes, by file-safe name.
pub fn generated_parts() -> Result<Vec<(String, Mesh)>> {
    prisms().into_iter().map(|(name, prism)| Ok((name.replace(' ', "-"), prism.mesh(name)?))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twice the signed area of the cap triangles of a surface, projected on the plane normal
    /// to the extrusion.
    fn area(mesh: &Mesh, surface: &str, along: Along) -> f64 {
        let id = mesh.surface_names.iter().position(|n| n == surface).unwrap() as u32 + 1;
        mesh.triangles
            .iter()
            .zip(&mesh.triangle_surfaces)
            .filter(|(_, &s)| s == id)
            .map(|(t, _)| {
                let [a, b, c] = t.map(|v| mesh.vertex(v));
                let n = (b - a).cross(c - a);
                match along {
                    Along::Z => n.z.abs(),
                    Along::Y => n.y.abs(),
                }
            })
            .sum::<f64>()
            / 2.0
    }

    #[test]
    fn parts_have_the_caps_walls_and_areas_of_their_profiles() {
        let parts = generated_parts().unwrap();
        assert_eq!(parts.len(), 10);
        let part = |name: &str| &parts.iter().find(|(n, _)| n == name).unwrap().1;
        // Hand-computed profile areas: the plate 1.6 × 1.2 less its 0.6 × 0.4 hole; the stairs
        // 2.4 × 0.4 + 1.6 × 0.4 + 0.8 × 0.4; the wedge ½ · 2 · 0.9.
        assert!((area(part("holed-plate"), "top", Along::Z) - (1.92 - 0.24)).abs() < 1e-6);
        assert!((area(part("stairs"), "front", Along::Y) - 1.92).abs() < 1e-6);
        assert!((area(part("wedge"), "back", Along::Y) - 0.9).abs() < 1e-6);
        assert_eq!(part("holed-plate").surface_count(), 2 + 4 + 4);
        assert_eq!(part("stairs").surface_count(), 2 + 8);
        assert_eq!(part("disc").surface_count(), 3, "caps and one curved side");
        for (name, mesh) in &parts {
            let lowest = (0..mesh.positions.len() as u32).map(|v| mesh.vertex(v).z).fold(f64::INFINITY, f64::min);
            assert_eq!(lowest, 0.0, "{name} rests on the table");
        }
    }
}
