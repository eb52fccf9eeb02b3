//! A model's surfaces, as an object or a hypothesis asks for them (`surfaces`): the file's own
//! groups (OBJ groups, a PLY face property), or the triangles grouped by their geometry —
//! `planar`, edge-adjacent triangles whose planes agree; `smooth`, edge-adjacent triangles whose
//! normals differ by less than the crease angle (a cylinder is its top, bottom and side; a sphere
//! one surface); `whole`, one surface. A model whose file names no surfaces is `smooth` unless
//! asked otherwise, since a scanned or curved part would otherwise be thousands of one-facet
//! surfaces that no scene segment can be bound to.
//!
//! Grouping is a union-find over shared edges, vertices welded by exact position first (OBJ and
//! STL files repeat a corner per face). Two triangles are coplanar when their unit normals
//! differ by less than [`COPLANAR_ANGLE_TOLERANCE`] radians (either orientation) and the far
//! corner of each lies within [`COPLANAR_DISTANCE_TOLERANCE`] × the model's bounding radius of
//! the other's plane; they are smooth neighbours when their normals differ by less than the
//! crease angle, oriented alike where they run their shared edge opposite ways (consistent
//! winding), in either orientation where they run it the same way (wound inconsistently, or
//! stacked).

use super::adjacency::weld_vertices;
use super::Mesh;
use crate::error::{Error, Result};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Largest angle between the normals of two merged triangles, in radians (about 0.06°).
pub const COPLANAR_ANGLE_TOLERANCE: f64 = 1e-3;
/// Largest distance from a triangle's corner to its neighbour's plane, relative to the
/// model's bounding radius.
pub const COPLANAR_DISTANCE_TOLERANCE: f64 = 1e-6;
/// The crease angle of `smooth` unless `crease_deg` says otherwise, degrees.
pub const DEFAULT_CREASE_DEG: f64 = 30.0;

/// How a model's triangles are grouped into surfaces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum SurfaceRule {
    /// The file's own: OBJ groups, a PLY face property `surface`, `segment` or `label`.
    Groups,
    /// Edge-adjacent coplanar triangles, named `planar 1`, `planar 2`, ….
    Planar,
    /// Edge-adjacent triangles whose normals differ by less than the crease angle, named
    /// `smooth 1`, `smooth 2`, ….
    Smooth,
    /// One surface, named `whole`.
    Whole,
}

impl SurfaceRule {
    pub fn as_str(self) -> &'static str {
        match self {
            SurfaceRule::Groups => "groups",
            SurfaceRule::Planar => "planar",
            SurfaceRule::Smooth => "smooth",
            SurfaceRule::Whole => "whole",
        }
    }
}

/// The surfaces asked of a model: a rule, or by default the file's own groups where it has
/// them and `smooth` elsewhere; and the crease angle of `smooth`, degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceChoice {
    pub rule: Option<SurfaceRule>,
    pub crease_deg: f64,
}

impl Default for SurfaceChoice {
    fn default() -> Self {
        Self { rule: None, crease_deg: DEFAULT_CREASE_DEG }
    }
}

impl SurfaceChoice {
    /// The choice of a file's `surfaces` and `crease_deg` keys, refused by name (`owner`
    /// starts the message) where the crease angle is outside (0, 180] or given to a rule
    /// other than `smooth`. A crease angle alone asks for `smooth`.
    pub fn from_keys(rule: Option<SurfaceRule>, crease_deg: Option<f64>, owner: &str) -> Result<Self> {
        if let Some(crease) = crease_deg {
            if !(crease > 0.0 && crease <= 180.0) {
                return Err(Error::Scene(format!("{owner}: crease_deg = {crease} must lie in (0, 180]")));
            }
            if let Some(other @ (SurfaceRule::Groups | SurfaceRule::Planar | SurfaceRule::Whole)) = rule {
                return Err(Error::Scene(format!(
                    "{owner}: crease_deg applies to surfaces = \"smooth\", not \"{}\"",
                    other.as_str()
                )));
            }
        }
        let rule = rule.or(crease_deg.map(|_| SurfaceRule::Smooth));
        Ok(Self { rule, crease_deg: crease_deg.unwrap_or(DEFAULT_CREASE_DEG) })
    }

    /// What tells two choices apart in a cache's key.
    pub fn key(&self) -> (Option<SurfaceRule>, u64) {
        (self.rule, self.crease_deg.to_bits())
    }
}

/// The surfaces a model file's reader gives a mesh whose file names none: `smooth` at the
/// default crease angle (the default of [`SurfaceChoice`]).
pub(super) fn default_surfaces(mesh: Mesh) -> Mesh {
    let mut mesh = merge_surfaces(mesh, "smooth", Neighbours::Smooth(DEFAULT_CREASE_DEG.to_radians().cos()));
    mesh.surfaces_from_file = false;
    mesh
}

impl Mesh {
    /// The same mesh with the surfaces `choice` asks for. Each new surface takes the material
    /// of its first triangle's surface before.
    pub fn with_surfaces(self, choice: SurfaceChoice) -> Result<Mesh> {
        let derived = |mesh: Mesh, kind, neighbours| {
            let before = (mesh.triangle_surfaces.clone(), mesh.surface_reflectivity.clone());
            let mut mesh = merge_surfaces(mesh, kind, neighbours);
            for (t, &s) in mesh.triangle_surfaces.iter().enumerate().rev() {
                mesh.surface_reflectivity[s as usize - 1] = before.1[before.0[t] as usize - 1];
            }
            mesh.surfaces_from_file = false;
            mesh
        };
        let smooth = Neighbours::Smooth(choice.crease_deg.to_radians().cos());
        match (choice.rule, self.surfaces_from_file) {
            (Some(SurfaceRule::Groups), false) => Err(Error::Mesh {
                name: self.name.clone(),
                reason: "it names no surfaces (no more than one OBJ group, no PLY surface property), which \
                         surfaces = \"groups\" reads; choose \"planar\", \"smooth\" or \"whole\""
                    .into(),
            }),
            (Some(SurfaceRule::Groups) | None, true) => Ok(self),
            // A file without surfaces was read with the default already.
            (None, false) => Ok(self),
            (Some(SurfaceRule::Smooth), _) => Ok(derived(self, "smooth", smooth)),
            (Some(SurfaceRule::Planar), _) => Ok(derived(self, "planar", Neighbours::Coplanar)),
            (Some(SurfaceRule::Whole), _) => Ok(derived(self, "whole", Neighbours::All)),
        }
    }
}

/// The flag of an edge two triangles share, beside its first triangle's word.
const SHARED: u64 = 1 << 63;

/// Most open edges at one vertex whose pairs are compared for T-junctions: beyond it (a fan of
/// open edges, as a triangle soup's vertex may have) they are left apart, so that grouping
/// never takes quadratic time.
const MAX_OPEN_EDGES_COMPARED: usize = 16;

/// Which edge-adjacent triangles share a surface.
#[derive(Clone, Copy)]
enum Neighbours {
    Coplanar,
    /// Normals (oriented alike where the triangles run their edge opposite ways) whose dot
    /// product exceeds this cosine.
    Smooth(f64),
    /// Every triangle, adjacent or not.
    All,
}

/// Replaces the mesh's surfaces by the patches of edge-adjacent `neighbours`, named
/// `{kind} 1`, `{kind} 2`, … in order of their first triangle (`{kind}` alone for one patch of
/// every triangle).
fn merge_surfaces(mut mesh: Mesh, kind: &str, neighbours: Neighbours) -> Mesh {
    if let Neighbours::All = neighbours {
        mesh.triangle_surfaces.iter_mut().for_each(|s| *s = 1);
        mesh.surface_names = vec![kind.to_string()];
        mesh.surface_reflectivity = vec![None];
        return mesh;
    }
    let welded = weld_vertices(&mesh.positions);
    let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.map(|v| welded[v as usize])).collect();
    let normals: Vec<DVec3> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.vertex(v));
            (b - a).cross(c - a).normalize()
        })
        .collect();
    let (_, radius) = mesh.bounding_sphere();
    let max_distance = COPLANAR_DISTANCE_TOLERANCE * radius.max(f64::MIN_POSITIVE);

    let mut parent: Vec<usize> = (0..tris.len()).collect();
    // Whether triangles t and u, which run a shared edge or line the same way (`same_way`),
    // belong to one surface. Alike-oriented neighbours run it opposite ways; two that run it
    // the same way are wound inconsistently or stacked, and either orientation counts.
    let joined = |t: usize, u: usize, same_way: bool| match neighbours {
        Neighbours::All => true,
        Neighbours::Coplanar => coplanar(&mesh, &normals, t, u, max_distance),
        Neighbours::Smooth(cos_crease) => {
            let cos = normals[t].dot(normals[u]);
            (if same_way { cos.abs() } else { cos }) > cos_crease
        }
    };
    // Each edge's first triangle t and whether it ran the edge from its lower vertex, as
    // 2·t + 1 or 2·t, and whether another triangle shares it ([`SHARED`]).
    let mut edge_owner: HashMap<(u32, u32), u64> = HashMap::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let edge = (a.min(b), a.max(b));
            match edge_owner.get_mut(&edge) {
                Some(owner) => {
                    *owner |= SHARED;
                    let (other, other_forward) = ((*owner & !SHARED) / 2, *owner % 2 == 1);
                    if joined(t, other as usize, (a < b) == other_forward) {
                        union(&mut parent, t, other as usize);
                    }
                }
                None => {
                    edge_owner.insert(edge, 2 * t as u64 + u64::from(a < b));
                }
            }
        }
    }
    // T-junctions: an edge no other triangle shares whole may run along part of another such
    // edge (a vertex of one face on an edge of its neighbour, as the built-in step's sides are
    // made). Such open edges meet at a common end and leave it in one direction; at each vertex
    // with at most MAX_OPEN_EDGES_COMPARED of them, each pair is compared.
    // Each open edge at each of its ends: (vertex, the other end, triangle), sorted by vertex.
    let mut open: Vec<(u32, u32, u32)> = Vec::new();
    for (&(a, b), &owner) in edge_owner.iter().filter(|(_, &owner)| owner & SHARED == 0) {
        let t = (owner / 2) as u32;
        open.extend([(a, b, t), (b, a, t)]);
    }
    drop(edge_owner);
    open.sort_unstable();
    let position = |v: u32| mesh.vertex(v);
    // Whether triangle t runs its edge from v to end (rather than back).
    let leaves =
        |t: u32, v: u32, end: u32| (0..3).any(|k| tris[t as usize][k] == v && tris[t as usize][(k + 1) % 3] == end);
    for at_vertex in open.chunk_by(|e, f| e.0 == f.0).filter(|edges| edges.len() <= MAX_OPEN_EDGES_COMPARED) {
        for (i, &(v, end, t)) in at_vertex.iter().enumerate() {
            for &(_, other_end, u) in &at_vertex[i + 1..] {
                let (along, other_along) = (position(end) - position(v), position(other_end) - position(v));
                let collinear = along.cross(other_along).length() <= 1e-9 * along.length() * other_along.length();
                let same_way = leaves(t, v, end) == leaves(u, v, other_end);
                let (t, u) = (t as usize, u as usize);
                if t != u && collinear && along.dot(other_along) > 0.0 && joined(t, u, same_way) {
                    union(&mut parent, t, u);
                }
            }
        }
    }

    let mut surface_of_root: HashMap<usize, u32> = HashMap::new();
    mesh.triangle_surfaces = (0..tris.len())
        .map(|t| {
            let root = find(&mut parent, t);
            let next = surface_of_root.len() as u32 + 1;
            *surface_of_root.entry(root).or_insert(next)
        })
        .collect();
    mesh.surface_names = (1..=surface_of_root.len()).map(|i| format!("{kind} {i}")).collect();
    // The caller knows the triangles' materials (obj.rs).
    mesh.surface_reflectivity = vec![None; surface_of_root.len()];
    mesh
}

fn coplanar(mesh: &Mesh, normals: &[DVec3], a: usize, b: usize, max_distance: f64) -> bool {
    let (na, nb) = (normals[a], normals[b]);
    if na.cross(nb).length() > COPLANAR_ANGLE_TOLERANCE.sin() {
        return false;
    }
    let off_plane = |t: usize, n: DVec3, origin: DVec3| {
        mesh.triangles[t].iter().map(|&v| (mesh.vertex(v) - origin).dot(n).abs()).fold(0.0, f64::max)
    };
    let origin_a = mesh.vertex(mesh.triangles[a][0]);
    let origin_b = mesh.vertex(mesh.triangles[b][0]);
    off_plane(b, na, origin_a) <= max_distance && off_plane(a, nb, origin_b) <= max_distance
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

fn union(parent: &mut [usize], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    parent[ra.max(rb)] = ra.min(rb);
}
