//! Built-in models, named `builtin:NAME[:PARAMETER]`, for the demo, the tests and quick
//! experiments without files. Every one rests on the table plane z = 0, centred on the z
//! axis, in model units:
//!
//! | name | shape | surfaces |
//! |---|---|---|
//! | `builtin:box` | unit cube, x, y ∈ [−0.5, 0.5], z ∈ [0, 1] | `top`, `bottom`, `+x`, `-x`, `+y`, `-y` |
//! | `builtin:step` | stepped block: L-shaped profile in xz, low part x ∈ [−2, 0] with top at z = 0.5, tall part x ∈ [0, 1] with top at z = 1.5, y ∈ [−0.75, 0.75] | `low_top`, `high_top`, `riser`, `low_end`, `high_end`, `bottom`, `-y`, `+y` |
//! | `builtin:cylinder[:N]` | radius 0.5, z ∈ [0, 1], N sides (default 32, at most 4096) | `top`, `bottom`, `side` |
//! | `builtin:sphere[:N]` | radius 0.5 centred at z = 0.5, N segments around, N/2 rings (default 32, 4 to 1024) | `sphere` |
//! | `builtin:plane[:SIZE]` | square table top of side SIZE (default 4) at z = 0 | `plane` |
//!
//! The stepped block's riser (x = 0, from z = 0.5 to 1.5) faces −x: with the camera toward
//! +x (θ > 0) it shadows the low top over x ∈ [−tan θ, 0].

use super::Mesh;
use crate::error::{Error, Result};
use glam::DVec3;
use std::f64::consts::TAU;

/// The built-in names, for help texts.
pub const BUILTIN_NAMES: &[&str] =
    &["builtin:box", "builtin:step", "builtin:cylinder[:N]", "builtin:sphere[:N]", "builtin:plane[:SIZE]"];

/// Sides of `builtin:cylinder:N`: 4N triangles, at most 16,384.
const CYLINDER_SIDES: std::ops::RangeInclusive<u32> = 3..=4096;
/// Segments of `builtin:sphere:N`: about N² triangles, at most about a million.
const SPHERE_SEGMENTS: std::ops::RangeInclusive<u32> = 4..=1024;

/// A built-in model with its parameter parsed and checked.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Builtin {
    Box,
    Step,
    Cylinder(u32),
    Sphere(u32),
    Plane(f64),
}

impl Builtin {
    fn parse(name: &str) -> Result<Self> {
        let invalid = |reason: String| Error::Mesh { name: name.to_string(), reason };
        let unknown = || invalid(format!("unknown built-in model; known: {}", BUILTIN_NAMES.join(", ")));
        let rest = name.strip_prefix("builtin:").ok_or_else(unknown)?;
        let (shape, parameter) = match rest.split_once(':') {
            Some((shape, p)) => (shape, Some(p)),
            None => (rest, None),
        };
        let count = |default: u32, range: std::ops::RangeInclusive<u32>| match parameter {
            None => Ok(default),
            Some(p) => p.parse::<u32>().ok().filter(|n| range.contains(n)).ok_or_else(|| {
                invalid(format!("the parameter `{p}` must be a whole number from {} to {}", range.start(), range.end()))
            }),
        };
        Ok(match shape {
            "box" if parameter.is_none() => Builtin::Box,
            "step" if parameter.is_none() => Builtin::Step,
            "cylinder" => Builtin::Cylinder(count(32, CYLINDER_SIDES)?),
            "sphere" => Builtin::Sphere(count(32, SPHERE_SEGMENTS)?),
            "plane" => Builtin::Plane(match parameter {
                None => 4.0,
                Some(p) => p
                    .parse::<f64>()
                    .ok()
                    .filter(|s| s.is_finite() && *s > 0.0)
                    .ok_or_else(|| invalid(format!("the size `{p}` must be a positive number")))?,
            }),
            _ => return Err(unknown()),
        })
    }

    /// One name per model: `builtin:sphere:032`, `builtin:sphere:+32` and `builtin:sphere`
    /// are all `builtin:sphere:32`, so a cache keyed by it builds each model once.
    fn canonical_name(self) -> String {
        match self {
            Builtin::Box => "builtin:box".into(),
            Builtin::Step => "builtin:step".into(),
            Builtin::Cylinder(n) => format!("builtin:cylinder:{n}"),
            Builtin::Sphere(n) => format!("builtin:sphere:{n}"),
            Builtin::Plane(size) => format!("builtin:plane:{size}"),
        }
    }
}

/// The canonical form of a built-in model's name (see [`builtin_mesh`]), or why it is none.
pub fn canonical_builtin_name(name: &str) -> Result<String> {
    Builtin::parse(name).map(Builtin::canonical_name)
}

/// Bytes building a built-in model holds at most, per triangle: the builder's corners (three
/// f64 vertices of its own each), its indices and surface ids with room for their vectors'
/// doubling, then the mesh's stored positions and derived tables (measured by
/// tests/memory.rs: 168 for the largest sphere and cylinder).
const BYTES_PER_TRIANGLE: u64 = 208;

/// Bytes building the built-in model `name` holds at most, to charge before building it.
pub fn builtin_bytes(name: &str) -> Result<u64> {
    let triangles = match Builtin::parse(name)? {
        Builtin::Box => 12,
        Builtin::Step => 16,
        Builtin::Cylinder(sides) => 4 * u64::from(sides),
        Builtin::Sphere(segments) => 2 * u64::from(segments) * u64::from(segments / 2 - 1),
        Builtin::Plane(_) => 2,
    };
    Ok(triangles * BYTES_PER_TRIANGLE)
}

/// Builds the built-in model `name` (with its `builtin:` prefix); the mesh is named by the
/// canonical form of `name`.
pub fn builtin_mesh(name: &str) -> Result<Mesh> {
    let model = Builtin::parse(name)?;
    let mut b = Builder::default();
    match model {
        Builtin::Box => b.cuboid([-0.5, -0.5, 0.0], [0.5, 0.5, 1.0]),
        Builtin::Step => b.step(),
        Builtin::Cylinder(sides) => b.cylinder(sides),
        Builtin::Sphere(segments) => b.sphere(segments),
        Builtin::Plane(size) => {
            let h = size / 2.0;
            b.quad("plane", [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]]);
        }
    }
    Mesh::new(model.canonical_name(), b.positions, b.triangles, b.triangle_surfaces, b.surface_names)
}

#[derive(Default)]
struct Builder {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    triangle_surfaces: Vec<u32>,
    surface_names: Vec<String>,
}

impl Builder {
    /// The id of surface `name`, created on first use.
    fn surface(&mut self, name: &str) -> u32 {
        match self.surface_names.iter().position(|n| n == name) {
            Some(i) => i as u32 + 1,
            None => {
                self.surface_names.push(name.to_string());
                self.surface_names.len() as u32
            }
        }
    }

    fn vertex(&mut self, p: impl Into<DVec3>) -> u32 {
        self.positions.push(p.into().to_array());
        self.positions.len() as u32 - 1
    }

    fn triangle(&mut self, surface: &str, corners: [DVec3; 3]) {
        let id = self.surface(surface);
        let t = corners.map(|c| self.vertex(c));
        self.triangles.push(t);
        self.triangle_surfaces.push(id);
    }

    /// A planar quad given counter-clockwise as seen from outside.
    fn quad(&mut self, surface: &str, [a, b, c, d]: [[f64; 3]; 4]) {
        let [a, b, c, d] = [a, b, c, d].map(DVec3::from);
        self.triangle(surface, [a, b, c]);
        self.triangle(surface, [a, c, d]);
    }

    fn cuboid(&mut self, lo: [f64; 3], hi: [f64; 3]) {
        let ([x0, y0, z0], [x1, y1, z1]) = (lo, hi);
        self.quad("top", [[x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]]);
        self.quad("bottom", [[x0, y0, z0], [x0, y1, z0], [x1, y1, z0], [x1, y0, z0]]);
        self.quad("+x", [[x1, y0, z0], [x1, y1, z0], [x1, y1, z1], [x1, y0, z1]]);
        self.quad("-x", [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]]);
        self.quad("+y", [[x0, y1, z0], [x0, y1, z1], [x1, y1, z1], [x1, y1, z0]]);
        self.quad("-y", [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]]);
    }

    fn step(&mut self) {
        let (xl, xm, xh) = (-2.0, 0.0, 1.0);
        let (zl, zh) = (0.5, 1.5);
        let (y0, y1) = (-0.75, 0.75);
        self.quad("low_top", [[xl, y0, zl], [xm, y0, zl], [xm, y1, zl], [xl, y1, zl]]);
        self.quad("high_top", [[xm, y0, zh], [xh, y0, zh], [xh, y1, zh], [xm, y1, zh]]);
        self.quad("riser", [[xm, y0, zl], [xm, y0, zh], [xm, y1, zh], [xm, y1, zl]]);
        self.quad("low_end", [[xl, y0, 0.0], [xl, y0, zl], [xl, y1, zl], [xl, y1, 0.0]]);
        self.quad("high_end", [[xh, y0, 0.0], [xh, y1, 0.0], [xh, y1, zh], [xh, y0, zh]]);
        self.quad("bottom", [[xl, y0, 0.0], [xl, y1, 0.0], [xh, y1, 0.0], [xh, y0, 0.0]]);
        for (name, y) in [("-y", y0), ("+y", y1)] {
            self.quad(name, [[xl, y, 0.0], [xm, y, 0.0], [xm, y, zl], [xl, y, zl]]);
            self.quad(name, [[xm, y, 0.0], [xh, y, 0.0], [xh, y, zh], [xm, y, zh]]);
        }
    }

    fn cylinder(&mut self, sides: u32) {
        for name in ["top", "bottom", "side"] {
            self.surface(name);
        }
        let r = 0.5;
        let rim = |i: u32, z: f64| {
            let a = TAU * f64::from(i % sides) / f64::from(sides);
            DVec3::new(r * a.cos(), r * a.sin(), z)
        };
        for i in 0..sides {
            let (a0, a1, b0, b1) = (rim(i, 0.0), rim(i + 1, 0.0), rim(i, 1.0), rim(i + 1, 1.0));
            self.triangle("side", [a0, a1, b1]);
            self.triangle("side", [a0, b1, b0]);
            self.triangle("top", [DVec3::new(0.0, 0.0, 1.0), b0, b1]);
            self.triangle("bottom", [DVec3::ZERO, a1, a0]);
        }
    }

    fn sphere(&mut self, segments: u32) {
        let rings = segments / 2;
        let r = 0.5;
        let point = |ring: u32, seg: u32| {
            let polar = std::f64::consts::PI * f64::from(ring) / f64::from(rings);
            let azimuth = TAU * f64::from(seg % segments) / f64::from(segments);
            // sin π is 1.2e-16, not 0: each pole is one point, so that the surface is closed.
            let across = if ring == rings { 0.0 } else { r * polar.sin() };
            DVec3::new(across * azimuth.cos(), across * azimuth.sin(), 0.5 + r * polar.cos())
        };
        for ring in 0..rings {
            for seg in 0..segments {
                let (a, b) = (point(ring, seg), point(ring, seg + 1));
                let (c, d) = (point(ring + 1, seg), point(ring + 1, seg + 1));
                if ring > 0 {
                    self.triangle("sphere", [a, c, b]);
                }
                if ring + 1 < rings {
                    self.triangle("sphere", [b, c, d]);
                }
            }
        }
    }
}
