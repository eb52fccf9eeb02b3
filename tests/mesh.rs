//! Models: OBJ surfaces from groups, coplanar merging for ungrouped files, built-ins, and the
//! validation every model goes through. CPU only.

use rangesynth::limits::Ledger;
use rangesynth::mesh::{builtin_mesh, load_obj, SurfaceChoice, SurfaceRule};
use rangesynth::Error;
use std::path::PathBuf;

fn obj(name: &str, text: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

const CUBE_VERTICES: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
const CUBE_FACES: [&str; 6] = ["f 1 4 3 2", "f 5 6 7 8", "f 1 2 6 5", "f 2 3 7 6", "f 3 4 8 7", "f 4 1 5 8"];

#[test]
fn groups_are_surfaces_in_file_order() {
    let mut text = CUBE_VERTICES.to_string();
    for (i, f) in CUBE_FACES.iter().enumerate() {
        text += &format!("g face_{i}\n{f}\n");
    }
    let mesh = load_obj(&obj("grouped.obj", &text), &Ledger::default()).unwrap();
    assert_eq!(mesh.surface_names, (0..6).map(|i| format!("face_{i}")).collect::<Vec<_>>());
    assert_eq!(mesh.triangles.len(), 12);
    // Quads are triangulated; both halves keep their group's surface.
    assert_eq!(mesh.triangle_surfaces, vec![1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6]);
}

#[test]
fn an_ungrouped_cube_gets_six_coplanar_surfaces() {
    // Triangles given separately, so merging must find adjacency through shared corners.
    let mut text = CUBE_VERTICES.to_string();
    for f in CUBE_FACES {
        let v: Vec<&str> = f.split_whitespace().skip(1).collect();
        text += &format!("f {} {} {}\nf {} {} {}\n", v[0], v[1], v[2], v[0], v[2], v[3]);
    }
    let mesh = load_obj(&obj("ungrouped.obj", &text), &Ledger::default()).unwrap();
    assert_eq!(mesh.surface_names.len(), 6);
    for pair in mesh.triangle_surfaces.chunks(2) {
        assert_eq!(pair[0], pair[1], "both halves of a face are one surface");
    }
    let mut ids = mesh.triangle_surfaces.clone();
    ids.dedup();
    assert_eq!(ids, vec![1, 2, 3, 4, 5, 6]);
}

#[test]
fn an_ungrouped_quad_pair_folded_by_a_degree_is_one_smooth_surface_and_two_planar_ones() {
    // Two triangles sharing an edge with a 1° fold: not coplanar, far from a 30° crease.
    let fold = 1f64.to_radians();
    let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 {}\nf 1 2 3\nf 1 3 4\n", fold.tan());
    let mesh = load_obj(&obj("folded.obj", &text), &Ledger::default()).unwrap();
    assert_eq!(mesh.surface_names, ["smooth 1"]);
    let planar = SurfaceChoice { rule: Some(SurfaceRule::Planar), ..Default::default() };
    assert_eq!(mesh.with_surfaces(planar).unwrap().surface_names, ["planar 1", "planar 2"]);
}

#[test]
fn builtins_have_their_documented_surfaces() {
    let names = |n: &str| builtin_mesh(n).unwrap().surface_names;
    assert_eq!(names("builtin:box"), ["top", "bottom", "+x", "-x", "+y", "-y"]);
    assert_eq!(names("builtin:step"), ["low_top", "high_top", "riser", "low_end", "high_end", "bottom", "-y", "+y"]);
    assert_eq!(names("builtin:cylinder:5"), ["top", "bottom", "side"]);
    assert_eq!(names("builtin:sphere"), ["sphere"]);
    assert_eq!(builtin_mesh("builtin:cylinder:7").unwrap().triangles.len(), 4 * 7);
    // Sphere: 2 fans of N and N·(N/2 − 2) quads.
    assert_eq!(builtin_mesh("builtin:sphere:8").unwrap().triangles.len(), 2 * 8 + 2 * 8 * 2);
    let (centre, radius) = builtin_mesh("builtin:step").unwrap().bounding_sphere();
    assert_eq!(centre.to_array(), [-0.5, 0.0, 0.75]);
    assert!((radius - (1.5f64 * 1.5 + 0.75 * 0.75 + 0.75 * 0.75).sqrt()).abs() < 1e-12);
}

fn mesh_error(name: &str, text: &str) -> String {
    match load_obj(&obj(name, text), &Ledger::default()) {
        Err(e @ Error::Mesh { .. }) => e.to_string(),
        other => panic!("{name}: expected a mesh error, got {other:?}"),
    }
}

#[test]
fn bad_models_are_refused_with_the_reason() {
    assert!(mesh_error("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n").contains("non-finite"));
    assert!(mesh_error("inf.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n").contains("non-finite"));
    let out_of_range = mesh_error("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert!(out_of_range.contains("vert") || out_of_range.contains("index"), "{out_of_range}");
    assert!(mesh_error("empty.obj", "# nothing\n").contains("no (non-degenerate) triangles"));
    assert!(mesh_error("points.obj", "v 0 0 0\nv 1 0 0\n").contains("no (non-degenerate) triangles"));
    assert!(mesh_error("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").contains("no (non-degenerate) triangles"));
    assert!(matches!(
        load_obj(std::path::Path::new("/nonexistent/model.obj"), &Ledger::default()),
        Err(Error::Io { .. })
    ));
    for bad in ["builtin:teapot", "builtin:cylinder:2", "builtin:sphere:x", "builtin:plane:-1", "builtin:box:3"] {
        assert!(matches!(builtin_mesh(bad), Err(Error::Mesh { .. })), "{bad}");
    }
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n";
    let mesh = load_obj(&obj("degenerate.obj", text), &Ledger::default()).unwrap();
    assert_eq!(mesh.triangles.len(), 1);
    assert_eq!(mesh.dropped_degenerate, 2);
}
