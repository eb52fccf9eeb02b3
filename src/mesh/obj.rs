//! OBJ loading through tobj. Each OBJ group (`g`) or object (`o`), in file order, is one
//! surface labelled from 1 (DESIGN.md "Interfaces"); a file with a single group says nothing
//! about its surfaces, so they are found by merging edge-adjacent coplanar triangles.

use super::{merge_coplanar_surfaces, Mesh};
use crate::error::{Error, Result};
use std::path::Path;

pub fn load_obj(path: &Path) -> Result<Mesh> {
    let name = path.display().to_string();
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => Error::Io {
            path: path.to_path_buf(),
            source: std::fs::File::open(path).err().unwrap_or_else(|| std::io::Error::other(e)),
        },
        other => Error::Mesh { name: name.clone(), reason: format!("not a readable OBJ file ({other})") },
    })?;

    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut triangle_surfaces = Vec::new();
    let mut surface_names = Vec::new();
    for model in &models {
        let base = (positions.len()) as u32;
        let coords = &model.mesh.positions;
        positions.extend(coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let surface = surface_names.len() as u32 + 1;
        surface_names.push(if model.name.is_empty() { format!("surface{surface}") } else { model.name.clone() });
        for tri in model.mesh.indices.chunks_exact(3) {
            triangles.push([tri[0], tri[1], tri[2]].map(|i| i.saturating_add(base)));
            triangle_surfaces.push(surface);
        }
    }
    let mesh = Mesh::new(name, positions, triangles, triangle_surfaces, surface_names)?;
    Ok(if models.len() == 1 { merge_coplanar_surfaces(mesh) } else { mesh })
}
