//! OBJ loading through tobj, from bytes read safely (io/input_file.rs).
//!
//! Surfaces (docs/design.md "Interfaces"): every group (`g`) or object (`o`) statement is one
//! surface, numbered from 1 in the order the statements appear in the file, whether or not
//! it holds faces, so the numbering is the one a reader counts in the file (an empty group
//! keeps its number and simply has no pixels). Faces that come before any statement form a
//! surface of their own, numbered first. A file with at most one surface says nothing about
//! its surfaces, so they are found by merging edge-adjacent coplanar triangles.
//!
//! tobj only sees text this file has checked ([`Checked`]), so that it reads the geometry as
//! written and cannot panic on it: a leading byte-order mark is dropped (else the first
//! vertex would be lost and every index shifted), comments are cut (tobj would read them as
//! vertex colours), every face's vertex indices are checked against the vertices before it,
//! and only the statements the product uses pass: vertices, faces, groups, materials. Lines
//! (`l`) and points (`p`) are never faces, and texture coordinates and normals are unused
//! (tobj's arithmetic on their huge indices overflows). Each group statement is replaced by
//! one whose name is the statement's number, so tobj's models map back to statements exactly
//! (tobj drops empty groups and may split one at a `usemtl`). The checks also count what
//! parsing will allocate, so the run's budget is charged before tobj allocates it.
//!
//! Materials give each surface a reflectivity (`[effects.reflectivity]`): the mean of the
//! `Kd` of the material its first face uses. A file loaded from a path reads its `mtllib`
//! libraries from its directory, each file once however many lines or spellings name it, as
//! every input is read (regular files, charged to the run's budget, mesh/mtl.rs); a library
//! that cannot be read is skipped, and its surfaces take the effect's default, but one the
//! budget refuses, or whose `Kd` is no reflectance, stops the load (mesh/mtl.rs). Text parsed
//! without a path reads no library.

use super::mtl::{checked_library, parse_checked_library};
use super::surfaces::default_surfaces;
use super::{is_degenerate, stored_positions, text_lines, Mesh};
use crate::error::{guard_parser, Error, Result};
use crate::io::{read_identified_file, read_input_file};
use crate::limits::{FileId, Ledger};
use crate::untrusted::quoted;
use std::path::Path;

/// Bytes loading an OBJ takes, at most, per element of the checked text (measured with a
/// counting allocator over files made of each element alone: tests/memory.rs): per byte of
/// text (the text, its checked copy), per vertex, per face corner (tobj's vertex map and
/// per-model copy of positions, the triangles, their surfaces and materials, the mesh), per
/// face, and per group statement (its name, tobj's model, the surface's entries).
const BYTES_PER_TEXT_BYTE: u64 = 3;
const BYTES_PER_VERTEX: u64 = 64;
const BYTES_PER_CORNER: u64 = 128;
const BYTES_PER_FACE: u64 = 64;
const BYTES_PER_STATEMENT: u64 = 320;

/// Bytes parsing takes per material of a library (tobj's `Material`), at most.
const BYTES_PER_MATERIAL: u64 = 512;

pub fn load_obj(path: &Path, ledger: &Ledger) -> Result<Mesh> {
    let bytes = read_input_file(path, "model", ledger)?;
    let name = path.display().to_string();
    let checked = Checked::new(&bytes, &name, ledger)?;
    drop(bytes);
    checked.charge(&name, ledger)?;
    // Each library file once (by identity), however many lines or spellings name it.
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut seen: Vec<FileId> = Vec::new();
    let mut libraries = Vec::new();
    for library in &checked.libraries {
        let library_path = dir.join(library);
        // Known by identity before it is read, so a second line naming it reads nothing.
        let id = std::fs::metadata(&library_path).map(|m| FileId::of(&m));
        if id.as_ref().is_ok_and(|id| seen.contains(id)) {
            libraries.push(None);
            continue;
        }
        let what = format!("material library {}", quoted(library));
        match read_identified_file(&library_path, &what, ledger) {
            Ok((bytes, id)) => {
                seen.push(id);
                let text = checked_library(&String::from_utf8_lossy(&bytes), &library_path)?;
                let materials = text.lines().filter(|l| l.starts_with("newmtl")).count() as u64;
                ledger.charge(format_args!("parsing {}", library_path.display()), materials * BYTES_PER_MATERIAL)?;
                libraries.push(Some((text, library_path.display().to_string())));
            }
            Err(e @ Error::TooLarge { .. }) => return Err(e),
            Err(_) => libraries.push(None),
        }
    }
    parse(&checked, &name, &libraries)
}

/// Parses OBJ text; `name` is the mesh's name in messages. Material libraries are not read.
/// What parsing takes is charged to `ledger`.
pub fn parse_obj(bytes: &[u8], name: &str, ledger: &Ledger) -> Result<Mesh> {
    let checked = Checked::new(bytes, name, ledger)?;
    checked.charge(name, ledger)?;
    parse(&checked, name, &vec![None; checked.libraries.len()])
}

/// OBJ text as tobj is given it, with what the checks counted.
struct Checked {
    /// The statements tobj reads; a library's `mtllib` line names it by its index in
    /// `libraries`.
    text: String,
    /// Each group statement's name (`None` when it has none), index 0 being the implicit
    /// group's.
    statement_names: Vec<Option<String>>,
    /// Each `mtllib` line's library, in file order.
    libraries: Vec<String>,
    text_bytes: u64,
    vertices: u64,
    faces: u64,
    corners: u64,
}

/// How much the estimate may grow between two checks against the budget while the text is
/// checked (the checked text and the group names are the check's own allocations).
const CHECK_EVERY_BYTES: u64 = 1 << 20;

impl Checked {
    /// Checks `bytes`, refusing as soon as what parsing them would take exceeds what `ledger`
    /// has left, without charging it (see [`Checked::charge`]).
    fn new(bytes: &[u8], name: &str, ledger: &Ledger) -> Result<Self> {
        let text = String::from_utf8_lossy(bytes);
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let mut checked = Self {
            text: String::with_capacity(text.len() + 4),
            statement_names: vec![None],
            libraries: Vec::new(),
            text_bytes: text.len() as u64,
            vertices: 0,
            faces: 0,
            corners: 0,
        };
        checked.text.push_str("g 0\n");
        let mut next_check = CHECK_EVERY_BYTES;
        for (number, line) in text_lines(text).enumerate() {
            checked.add(line).map_err(|reason| Error::Mesh {
                name: name.to_string(),
                reason: format!("line {}: {reason}", number + 1),
            })?;
            if checked.bytes() > next_check {
                ledger.check(checked.describe(name), checked.bytes())?;
                next_check = checked.bytes() + CHECK_EVERY_BYTES;
            }
        }
        Ok(checked)
    }

    fn add(&mut self, line: &str) -> std::result::Result<(), String> {
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.splitn(2, char::is_whitespace);
        let keyword = words.next().unwrap_or("");
        let rest = words.next().map(str::trim).filter(|rest| !rest.is_empty());
        match keyword {
            "v" => {
                self.vertices += 1;
                self.text.push_str(line);
                self.text.push('\n');
            }
            "f" => {
                self.text.push('f');
                let mut corners = 0;
                for corner in rest.unwrap_or("").split_whitespace() {
                    let vertex = corner.split('/').next().unwrap_or("");
                    self.check_vertex_index(vertex)?;
                    self.text.push(' ');
                    self.text.push_str(vertex);
                    corners += 1;
                }
                if corners < 3 {
                    return Err(format!("a face needs at least 3 vertices, this one has {corners}"));
                }
                self.faces += 1;
                self.corners += corners;
                self.text.push('\n');
            }
            "g" | "o" => {
                self.text.push_str(&format!("g {}\n", self.statement_names.len()));
                self.statement_names.push(rest.map(str::to_string));
            }
            // A `usemtl` without a name is an error to tobj and names no material.
            "usemtl" => {
                if let Some(material) = rest {
                    self.text.push_str("usemtl ");
                    self.text.push_str(material);
                    self.text.push('\n');
                }
            }
            "mtllib" => {
                if let Some(library) = rest {
                    self.text.push_str(&format!("mtllib {}\n", self.libraries.len()));
                    self.libraries.push(library.to_string());
                }
            }
            // Lines, points, curves and surfaces are not faces; texture coordinates, normals,
            // smoothing groups and the rest change nothing the product renders.
            _ => {}
        }
        Ok(())
    }

    /// A face's vertex index: 1 to the number of vertices so far, or -1 back to the first.
    fn check_vertex_index(&self, index: &str) -> std::result::Result<(), String> {
        let valid = match index.parse::<i64>() {
            Ok(i) if i > 0 => i as u64 <= self.vertices,
            Ok(i) if i < 0 => i.unsigned_abs() <= self.vertices,
            _ => false,
        };
        match valid {
            true => Ok(()),
            false => Err(format!(
                "the face's vertex index {} is not one of the {} vertices before it",
                quoted(index),
                self.vertices
            )),
        }
    }

    /// What parsing the text checked so far takes.
    fn bytes(&self) -> u64 {
        self.text_bytes * BYTES_PER_TEXT_BYTE
            + self.vertices * BYTES_PER_VERTEX
            + self.corners * BYTES_PER_CORNER
            + self.faces * BYTES_PER_FACE
            + self.statement_names.len() as u64 * BYTES_PER_STATEMENT
    }

    fn describe(&self, name: &str) -> String {
        let groups = self.statement_names.len() - 1;
        format!("parsing the model {name} ({} vertices, {} faces, {groups} groups)", self.vertices, self.faces)
    }

    /// Charges what parsing will take to `ledger`.
    fn charge(&self, name: &str, ledger: &Ledger) -> Result<()> {
        ledger.charge(self.describe(name), self.bytes())
    }
}

/// The mesh of checked text; `libraries[k]` is the checked text and name of the library the
/// k-th `mtllib` line names, where it was read (and not read before).
fn parse(checked: &Checked, name: &str, libraries: &[Option<(String, String)>]) -> Result<Mesh> {
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let library = |line: &Path| {
        let index: usize = line.to_str().and_then(|k| k.parse().ok()).ok_or(tobj::LoadError::OpenFileFailed)?;
        match libraries.get(index).and_then(Option::as_ref) {
            Some((text, name)) => parse_checked_library(text, name).unwrap_or(Err(tobj::LoadError::MaterialParseError)),
            None => Ok((Vec::new(), Default::default())),
        }
    };
    let (models, materials) = guard_parser(name, "tobj's OBJ parser", || {
        tobj::load_obj_buf(&mut checked.text.as_bytes(), &options, library)
            .map_err(|e| Error::Mesh { name: name.to_string(), reason: format!("not a readable OBJ file ({e})") })
    })?;
    let materials = materials.unwrap_or_default();
    let statement_names = &checked.statement_names;

    // Statement 0 is the implicit group before any statement; it is a surface only when it
    // holds faces.
    let group_of = |model: &tobj::Model| model.name.parse::<usize>().unwrap_or(0);
    let implicit = usize::from(models.iter().any(|m| group_of(m) == 0 && !m.mesh.indices.is_empty()));
    let surface_of = |group: usize| (group + implicit) as u32;
    let surface_names: Vec<String> = (1 - implicit..statement_names.len())
        .map(|group| match &statement_names[group] {
            Some(n) => n.clone(),
            None => format!("surface{}", surface_of(group)),
        })
        .collect();

    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut triangle_surfaces = Vec::new();
    let mut triangle_reflectivity = Vec::new();
    for model in &models {
        let base = positions.len() as u32;
        positions.extend(model.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let material = model.mesh.material_id.and_then(|id| materials.get(id)).and_then(reflectivity);
        for tri in model.mesh.indices.chunks_exact(3) {
            triangles.push([tri[0], tri[1], tri[2]].map(|i| i.saturating_add(base)));
            triangle_surfaces.push(surface_of(group_of(model)));
            triangle_reflectivity.push(material);
        }
    }
    // Aligned with the triangles Mesh::new keeps, which it decides on the positions it stores.
    let kept_reflectivity: Vec<Option<f32>> = {
        let (_, stored) = stored_positions(&positions);
        triangles
            .iter()
            .zip(triangle_reflectivity)
            .filter(|(tri, _)| !is_degenerate(&stored, tri))
            .map(|(_, r)| r)
            .collect()
    };
    let single_surface = surface_names.len() <= 1;
    let mesh = Mesh::new(name, positions, triangles, triangle_surfaces, surface_names)?;
    let mut mesh = if single_surface { default_surfaces(mesh) } else { mesh };
    // Each surface takes its first face's material.
    let mut seen = vec![false; mesh.surface_names.len()];
    for (&surface, &material) in mesh.triangle_surfaces.iter().zip(&kept_reflectivity) {
        let s = surface as usize - 1;
        if !std::mem::replace(&mut seen[s], true) {
            mesh.surface_reflectivity[s] = material;
        }
    }
    Ok(mesh)
}

/// A material's reflectivity: the mean of its diffuse colour `Kd` (each component finite and
/// at least 0: mesh/mtl.rs), at most 1.
fn reflectivity(material: &tobj::Material) -> Option<f32> {
    let kd = material.diffuse?;
    Some((kd.iter().map(|&k| k as f32).sum::<f32>() / 3.0).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::Ledger;

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

    #[test]
    fn surfaces_follow_the_statements_in_file_order_empty_ones_included() {
        let text = format!("{SQUARE}g empty\no first\nf 1 2 3\ng\ng second\nf 1 3 4\n");
        let mesh = parse_obj(text.as_bytes(), "t", &Ledger::default()).unwrap();
        assert_eq!(mesh.surface_names, ["empty", "first", "surface3", "second"]);
        assert_eq!(mesh.triangle_surfaces, [2, 4]);
    }

    #[test]
    fn faces_before_any_statement_are_the_first_surface() {
        let text = format!("{SQUARE}f 1 2 3\ng top\nf 1 3 4\n");
        let mesh = parse_obj(text.as_bytes(), "t", &Ledger::default()).unwrap();
        assert_eq!(mesh.surface_names, ["surface1", "top"]);
        assert_eq!(mesh.triangle_surfaces, [1, 2]);
    }

    #[test]
    fn materials_give_each_surface_the_mean_of_its_kd() {
        let dir = crate::io::scratch_dir("obj_materials");
        std::fs::write(dir.join("m.mtl"), "newmtl dark\nKd 0.1 0.2 0.3\nnewmtl bright\nKd 0.9 0.9 0.6\n").unwrap();
        let text = format!(
            "mtllib m.mtl\nmtllib missing.mtl\n{SQUARE}g a\nusemtl bright\nf 1 2 3\ng b\nf 1 3 4\n\
             g c\nusemtl dark\nf 1 2 4\nusemtl bright\nf 2 3 4\ng d\nusemtl unknown\nf 1 2 3\n"
        );
        std::fs::write(dir.join("m.obj"), text).unwrap();
        let mesh = load_obj(&dir.join("m.obj"), &Ledger::default()).unwrap();
        assert_eq!(mesh.surface_names, ["a", "b", "c", "d"]);
        // b keeps using the material set before it; c takes its first face's.
        let expected = [Some(0.8), Some(0.8), Some(0.2), None];
        // Tabs after the keywords, and an ungrouped file with two materials: its merged faces
        // each take their own triangle's.
        let ungrouped = "mtllib\tm.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\n\
                         usemtl\tdark\nf 1 2 3\nusemtl bright\nf 1 2 5 4\n";
        std::fs::write(dir.join("u.obj"), ungrouped).unwrap();
        let merged = load_obj(&dir.join("u.obj"), &Ledger::default()).unwrap();
        assert_eq!(merged.surface_names.len(), 2);
        let rounded: Vec<_> = merged.surface_reflectivity.iter().map(|r| r.map(|r| (r * 1e5).round() / 1e5)).collect();
        assert_eq!(rounded, [Some(0.2), Some(0.8)]);
        for (got, want) in mesh.surface_reflectivity.iter().zip(expected) {
            assert_eq!(got.map(|r| (r * 1e5).round() / 1e5), want);
        }
        let parsed = parse_obj(&std::fs::read(dir.join("m.obj")).unwrap(), "text", &Ledger::default()).unwrap();
        assert!(parsed.surface_reflectivity.iter().all(Option::is_none), "text alone reads no library");
    }

    #[test]
    fn geometry_is_read_as_written_whatever_the_encoding_details() {
        // A byte-order mark, CRLF and CR-only line ends: the same one triangle at the same place.
        let plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n";
        let expected = parse_obj(plain.as_bytes(), "t", &Ledger::default()).unwrap();
        assert_eq!(expected.positions[..3], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        for text in [format!("\u{feff}{plain}"), plain.replace('\n', "\r\n"), plain.replace('\n', "\r")] {
            let mesh = parse_obj(text.as_bytes(), "t", &Ledger::default()).unwrap();
            assert_eq!((&mesh.positions, &mesh.triangles), (&expected.positions, &expected.triangles), "{text:?}");
        }
    }

    #[test]
    fn lines_and_points_are_never_faces() {
        let text = format!("{SQUARE}l 1 2 3 4\np 1 2 3\nl 1 2\nf 1 2 3\n");
        let mesh = parse_obj(text.as_bytes(), "t", &Ledger::default()).unwrap();
        assert_eq!(mesh.triangles, [[0, 1, 2]]);
    }

    #[test]
    fn a_face_index_outside_the_vertices_before_it_is_named_with_its_line() {
        for (face, index) in [("f 1 2 5", "5"), ("f 1 2 0", "0"), ("f 1 2 -5", "-5"), ("f 1 2 x/1", "x")] {
            let text = format!("{SQUARE}{face}\n");
            let e = parse_obj(text.as_bytes(), "t", &Ledger::default()).unwrap_err().to_string();
            assert!(
                e.contains(&format!("line 5: the face's vertex index \"{index}\" is not one of the 4 vertices")),
                "{e}"
            );
        }
        let e = parse_obj(format!("{SQUARE}f 1 2\n").as_bytes(), "t", &Ledger::default()).unwrap_err().to_string();
        assert!(e.contains("line 5: a face needs at least 3 vertices, this one has 2"), "{e}");
    }

    #[test]
    fn a_library_is_read_once_however_many_lines_and_spellings_name_it() {
        let dir = crate::io::scratch_dir("obj_library_once");
        std::fs::write(dir.join("m.mtl"), format!("newmtl grey\nKd 0.5\n{}", "# padding\n".repeat(10_000))).unwrap();
        let lines = ["mtllib m.mtl", "mtllib ./m.mtl", "mtllib ../obj_library_once/m.mtl"].repeat(4).join("\n");
        std::fs::write(dir.join("m.obj"), format!("{lines}\n{SQUARE}g a\nusemtl grey\nf 1 2 3\ng b\nf 1 3 4\n"))
            .unwrap();
        let ledger = Ledger::default();
        let mesh = load_obj(&dir.join("m.obj"), &ledger).unwrap();
        assert_eq!(mesh.surface_reflectivity, [Some(0.5), Some(0.5)], "b keeps the material set before it");
        let library_bytes = std::fs::metadata(dir.join("m.mtl")).unwrap().len();
        assert!(
            ledger.held() < 2 * library_bytes,
            "the library was charged more than once: {} bytes held",
            ledger.held()
        );
    }

    #[test]
    fn a_model_over_the_budget_is_refused_while_it_is_checked_not_after() {
        // 2 MB of empty groups would take about 320 MB to parse: refused once its estimate
        // passes the 16 MiB left, long before the end of the text.
        let text = format!("{SQUARE}f 1 2 3\n{}", "g\n".repeat(1_000_000));
        let ledger = Ledger::new(crate::limits::MemoryBudget::new(16 << 20));
        let e = parse_obj(text.as_bytes(), "t", &ledger).unwrap_err().to_string();
        let groups: usize = e.split(" groups)").next().and_then(|s| s.rsplit(' ').next()).unwrap().parse().unwrap();
        assert!(groups < 100_000, "refused only after {groups} groups: {e}");
        assert_eq!(ledger.held(), 0, "nothing charged for a refused model");
    }

    #[test]
    fn trailing_comments_and_materials_are_ignored() {
        let text = "mtllib /dev/zero\nv 0 1 0 # a comment\nv 1 1 0#another\nv 0 0 0\nusemtl x\nf 1 2 3 # face\n";
        let mesh = parse_obj(text.as_bytes(), "t", &Ledger::default()).unwrap();
        assert_eq!(mesh.positions[0], [0.0, 1.0, 0.0]);
        assert_eq!(mesh.triangles.len(), 1);
    }
}
