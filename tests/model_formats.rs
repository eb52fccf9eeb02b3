//! Model files in PLY (ASCII, binary little- and big-endian) and STL (ASCII, binary): the same
//! model in each format is the same mesh and renders the same image as its OBJ; bad files are
//! refused with a message naming the file and the problem, before anything their headers
//! claim is allocated. The files are written here byte by byte, not by the crates that read
//! them.

mod common;

use common::cli::fresh_dir;
use common::*;
use glam::DMat4;
use rangesynth::limits::{Ledger, MemoryBudget};
use rangesynth::mesh::{builtin_mesh, load_model_file, parse_ply, parse_stl, Mesh, SurfaceChoice, SurfaceRule};
use rangesynth::scene::SceneObject;
use rangesynth::shadow::ShadowMode;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The model every format with surfaces writes: the built-in stepped block, eight surfaces.
fn model() -> Mesh {
    builtin_mesh("builtin:step").unwrap()
}

/// The model STL writes, whose planar faces are its surfaces: the built-in box (the stepped
/// block's sides are each two faces meeting at a T-junction, so they are not edge-adjacent).
fn box_model() -> Mesh {
    builtin_mesh("builtin:box").unwrap()
}

fn vertices(mesh: &Mesh) -> Vec<[f32; 3]> {
    (0..mesh.positions.len() as u32).map(|v| mesh.vertex(v).as_vec3().to_array()).collect()
}

/// OBJ with one group per surface, in surface order.
fn obj_text(mesh: &Mesh) -> Vec<u8> {
    let mut text = String::new();
    for [x, y, z] in vertices(mesh) {
        text += &format!("v {x} {y} {z}\n");
    }
    for (s, name) in (1..).zip(&mesh.surface_names) {
        text += &format!("g {name}\n");
        for (t, _) in mesh.triangles.iter().zip(&mesh.triangle_surfaces).filter(|(_, &id)| id == s) {
            text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
        }
    }
    text.into_bytes()
}

#[derive(Clone, Copy)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// PLY with f32 vertices, int index lists (uchar counts) and an int face property
/// `surface` (the surface id times 10, so names show the value, not the id).
fn ply_bytes(mesh: &Mesh, encoding: Encoding) -> Vec<u8> {
    let format = match encoding {
        Encoding::Ascii => "ascii",
        Encoding::Little => "binary_little_endian",
        Encoding::Big => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment written by tests/model_formats.rs\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\n\
         property int surface\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    let f32_bytes = |v: f32| match encoding {
        Encoding::Big => v.to_be_bytes(),
        _ => v.to_le_bytes(),
    };
    let i32_bytes = |v: i32| match encoding {
        Encoding::Big => v.to_be_bytes(),
        _ => v.to_le_bytes(),
    };
    for p in vertices(mesh) {
        match encoding {
            Encoding::Ascii => out.extend(format!("{} {} {}\n", p[0], p[1], p[2]).bytes()),
            _ => p.iter().for_each(|&c| out.extend(f32_bytes(c))),
        }
    }
    for (t, &s) in mesh.triangles.iter().zip(&mesh.triangle_surfaces) {
        let surface = 10 * s as i32;
        match encoding {
            Encoding::Ascii => out.extend(format!("3 {} {} {} {surface}\n", t[0], t[1], t[2]).bytes()),
            _ => {
                out.push(3);
                t.iter().for_each(|&v| out.extend(i32_bytes(v as i32)));
                out.extend(i32_bytes(surface));
            }
        }
    }
    out
}

fn stl_bytes(mesh: &Mesh, binary: bool) -> Vec<u8> {
    let corners = |t: &[u32; 3]| t.map(|v| mesh.vertex(v).as_vec3().to_array());
    if binary {
        let mut out = vec![0u8; 80];
        out.extend((mesh.triangles.len() as u32).to_le_bytes());
        for t in &mesh.triangles {
            out.extend([0u8; 12]); // the normal, which readers recompute
            corners(t).iter().flatten().for_each(|c| out.extend(c.to_le_bytes()));
            out.extend([0u8; 2]);
        }
        out
    } else {
        let mut text = "solid model\n".to_string();
        for t in &mesh.triangles {
            text += "facet normal 0 0 0\nouter loop\n";
            for [x, y, z] in corners(t) {
                text += &format!("vertex {x:e} {y:e} {z:e}\n");
            }
            text += "endloop\nendfacet\n";
        }
        text += "endsolid model\n";
        text.into_bytes()
    }
}

/// `bytes` written as `name` in the test's own directory `d`.
fn written(d: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = d.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn load(path: &Path) -> Mesh {
    load_model_file(path, &Ledger::default()).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The triangles as corner positions (bits), with their surface ids: meshes that list the
/// same triangles with the same surfaces compare equal however their vertices are indexed.
fn triangles(mesh: &Mesh) -> Vec<([[u32; 3]; 3], u32)> {
    mesh.triangles
        .iter()
        .zip(&mesh.triangle_surfaces)
        .map(|(t, &s)| (t.map(|v| mesh.vertex(v).as_vec3().to_array().map(f32::to_bits)), s))
        .collect()
}

#[test]
fn every_ply_encoding_and_the_obj_give_the_same_mesh() {
    let d = fresh_dir("model_formats", "encodings");
    let obj = load(&written(&d, "step.obj", &obj_text(&model())));
    for (encoding, name) in [(Encoding::Ascii, "ascii"), (Encoding::Little, "little"), (Encoding::Big, "big")] {
        let ply = load(&written(&d, &format!("step_{name}.PLY"), &ply_bytes(&model(), encoding)));
        assert_eq!(triangles(&ply), triangles(&obj), "{name}");
        let expected: Vec<String> = (1..=8).map(|s| format!("surface {}", 10 * s)).collect();
        assert_eq!(ply.surface_names, expected, "{name}: named by the property's values");
    }
}

#[test]
fn ascii_and_binary_stl_give_the_same_mesh_with_its_planar_faces() {
    let d = fresh_dir("model_formats", "stl");
    let ascii = load(&written(&d, "box_ascii.stl", &stl_bytes(&box_model(), false)));
    let binary = load(&written(&d, "box_binary.stl", &stl_bytes(&box_model(), true)));
    assert_eq!(triangles(&ascii), triangles(&binary));
    assert_eq!(triangles(&binary), triangles(&box_model()), "the box's triangles, its faces numbered alike");
}

/// The OBJ, a PLY and an STL of one model render the same labels, z bits and shadowed labels
/// (the STL's surfaces are its planar faces, which number as the OBJ's groups do, in order of
/// their first triangle).
#[test]
fn a_model_renders_the_same_image_from_obj_ply_and_stl() {
    let d = fresh_dir("model_formats", "render");
    let paths = [
        written(&d, "render.obj", &obj_text(&box_model())),
        written(&d, "render.ply", &ply_bytes(&box_model(), Encoding::Little)),
        written(&d, "render.stl", &stl_bytes(&box_model(), true)),
    ];
    let pose = DMat4::from_rotation_x(0.3) * DMat4::from_rotation_z(0.5);
    let outputs: Vec<_> = paths
        .iter()
        .map(|path| {
            let mut sc = scene(centred_sensor(96, 96, 2.0 / 96.0, [0.0, 0.0], 40.0), ShadowMode::Depth, &[]);
            sc.objects.push(SceneObject {
                model_ref: path.display().to_string(),
                mesh: Arc::new(load(path)),
                pose,
                reflectivity: None,
            });
            render(&sc)
        })
        .collect();
    assert!(outputs[0].label_unshadowed.iter().filter(|&&l| l != 0).count() > 1000, "the model in view");
    assert!(outputs[0].shadowed_pixels() > 50, "it casts a shadow");
    for (path, out) in paths.iter().zip(&outputs).skip(1) {
        assert_eq!(out.label_unshadowed, outputs[0].label_unshadowed, "{}", path.display());
        assert_eq!(out.label, outputs[0].label, "{}", path.display());
        let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&out.z), bits(&outputs[0].z), "{}", path.display());
    }
}

fn ply_refusal(bytes: &[u8]) -> String {
    parse_ply(bytes, "bad.ply", &Ledger::new(MemoryBudget::new(64 << 20))).unwrap_err().to_string()
}

const TRIANGLE_HEADER: &str =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";

#[test]
fn bad_ply_files_are_refused_naming_the_problem() {
    let with_faces = |faces: &str| format!("{TRIANGLE_HEADER}{faces}end_header\n0 0 0\n1 0 0\n0 1 0\n");
    let face_list = "element face 1\nproperty list uchar int vertex_indices\n";
    for (bytes, expected) in [
        // A header claiming a billion vertices in a file of a hundred bytes: refused before
        // anything is reserved for them.
        (
            format!(
                "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\n\
                 property float z\n{face_list}end_header\n{}",
                "\0".repeat(64)
            ),
            "claims 1000000000 elements \"vertex\"",
        ),
        (format!("{TRIANGLE_HEADER}{face_list}"), "no line `end_header`"),
        (format!("{}\n3 0 1 2\n", with_faces("")), "no element \"face\""),
        (format!("{}3 0 1 -2\n", with_faces(face_list)), "face 0 lists a negative vertex index"),
        (format!("{}2 0 1\n", with_faces(face_list)), "face 0 lists 2 vertices"),
        (format!("{}3 0 1 7\n", with_faces(face_list)), "refers to vertex 7"),
        (
            format!("{}3 0 1 2\n", with_faces("element face 1\nproperty list uchar float vertex_indices\n")),
            "not integers",
        ),
        (format!("{}3 0 1 2\n", with_faces("element face 1\nproperty int vertex_indices\n")), "not a list"),
        (
            format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n{face_list}end_header\n"
            ),
            "no property z",
        ),
        ("solid not a ply\nend_header\n".to_string(), "not a readable PLY header"),
    ] {
        let message = ply_refusal(bytes.as_bytes());
        assert!(message.contains("bad.ply") && message.contains(expected), "expected {expected:?}: {message}");
    }
    let nan_vertex = [
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"
            .as_bytes(),
        &[0.0, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0, 0.0].map(f32::to_le_bytes).concat(),
    ]
    .concat();
    let message = ply_refusal(&nan_vertex);
    assert!(message.contains("vertex 1 has a non-finite coordinate"), "{message}");
    // The parser's error quotes the line; a terminal escape in it is shown escaped.
    let escape = format!("{TRIANGLE_HEADER}{face_list}end_header\n0 0 0\n1 \u{1b}[2J 0\n0 1 0\n3 0 1 2\n");
    let message = ply_refusal(escape.as_bytes());
    assert!(message.contains("unreadable") && !message.contains('\u{1b}'), "{message:?}");
}

/// A comment that mentions `end_header` does not end the header: the whole header, here a
/// megabyte of comments after it, is charged before it is parsed.
#[test]
fn a_ply_header_is_charged_through_its_real_end() {
    let header = format!("ply\nformat ascii 1.0\ncomment end_header\n{}", "comment padding\n".repeat(65_536));
    let text = format!("{header}element vertex 0\nelement face 0\nend_header\n");
    let e = parse_ply(text.as_bytes(), "long.ply", &Ledger::new(MemoryBudget::new(8 << 20))).unwrap_err();
    assert!(e.to_string().contains("parsing the PLY header of long.ply"), "{e}");
}

#[test]
fn bad_stl_files_are_refused_naming_the_problem() {
    let binary = stl_bytes(&box_model(), true);
    let mut claims_more = binary.clone();
    claims_more[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    for (bytes, expected) in [
        (binary[..binary.len() - 10].to_vec(), "unreadable"),
        (claims_more, "unreadable"),
        (b"solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0\n".to_vec(), "triangle 0 unreadable"),
        (vec![0u8; 84], "no (non-degenerate) triangles"),
    ] {
        let e = parse_stl(&bytes, "bad.stl", &Ledger::default()).unwrap_err().to_string();
        assert!(e.contains("bad.stl") && e.contains(expected), "expected {expected:?}: {e}");
    }
}

#[test]
fn a_model_file_is_charged_to_the_budget_before_it_is_parsed() {
    let ply = ply_bytes(&model(), Encoding::Little);
    let stl = stl_bytes(&model(), true);
    for (name, parse) in [
        ("ply", Box::new(|l: &Ledger| parse_ply(&ply, "tight.ply", l).map(drop)) as Box<dyn Fn(&Ledger) -> _>),
        ("stl", Box::new(|l: &Ledger| parse_stl(&stl, "tight.stl", l).map(drop))),
    ] {
        let e = parse(&Ledger::new(MemoryBudget::new(1024))).unwrap_err().to_string();
        assert!(e.contains("tight") && e.contains("budget"), "{name}: {e}");
        parse(&Ledger::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

/// The fuzz targets' seeds (tools/fuzz/seeds/) are the formats' variants, and each loads: a
/// text PLY of doubles with a quad, `uint` indices under `vertex_index`, its surfaces from a
/// `segment` property, an extra vertex property and an extra element; a tetrahedron in binary
/// PLY of both byte orders (surfaces from `surface`) and in text and binary STL.
#[test]
fn the_fuzz_seeds_load_as_the_models_they_are() {
    let seed = |name: &str| load(&PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tools/fuzz/seeds").join(name));
    let corner = seed("ply/ascii_segments.ply");
    assert_eq!(corner.triangles.len(), 4, "the quad is two triangles");
    assert_eq!(corner.surface_names, ["surface 7", "surface 8"]);
    assert_eq!(corner.triangle_surfaces, [1, 1, 2, 2]);
    let little = seed("ply/binary_little_endian.ply");
    assert_eq!(triangles(&seed("ply/binary_big_endian.ply")), triangles(&little));
    assert_eq!(little.surface_names, ["surface 0", "surface 1", "surface 2", "surface 3"]);
    let stl = seed("stl/binary.stl");
    assert_eq!(triangles(&seed("stl/ascii.stl")), triangles(&stl));
    assert_eq!((stl.triangles.len(), stl.surface_count()), (4, 4), "a tetrahedron's four faces");
}

/// The unit box written in millimetres (its coordinates times 1000) and read with `scale =
/// 0.001` is the metre box: the same image in a scene, and the same vertices as a
/// hypothesis' model; a scale that is not a positive number is refused by name.
#[test]
fn a_millimetre_model_at_scale_one_thousandth_is_the_metre_model() {
    let mut millimetres = box_model();
    millimetres.positions.iter_mut().for_each(|p| *p = p.map(|c| c * 1000.0));
    let d = fresh_dir("model_formats", "scale");
    std::fs::write(d.join("box_mm.obj"), obj_text(&millimetres)).unwrap();
    std::fs::write(d.join("box_m.obj"), obj_text(&box_model())).unwrap();
    let scene_of = |model: &str, scale: &str| {
        let text = format!(
            "[sensor]\nkind = \"orthographic\"\nwidth = 64\nheight = 64\npitch = [0.03, 0.03]\n\
             origin = [-0.945, 0.945]\ntheta_deg = 35.0\n[shadow]\nmode = \"depth\"\n[[object]]\n\
             model = \"{model}\"\n{scale}pose = [[0.8, -0.6, 0.0, 0.0], [0.6, 0.8, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], \
             [0.0, 0.0, 0.0, 1.0]]\n[[object]]\nmodel = \"builtin:plane:4\"\n"
        );
        rangesynth::Scene::from_toml(&text, &d, &Ledger::default())
    };
    let metre = render(&scene_of("box_m.obj", "").unwrap());
    let scaled = render(&scene_of("box_mm.obj", "scale = 0.001\n").unwrap());
    assert!(metre.shadowed_pixels() > 20 && metre.label.iter().filter(|&&l| l != 0).count() > 500);
    assert_eq!(scaled.label_unshadowed, metre.label_unshadowed);
    assert_eq!(scaled.label, metre.label);
    let worst = paired(&scaled.z, &metre.z).map(|(a, b)| (a - b).abs()).filter(|e| !e.is_nan()).fold(0.0, f32::max);
    assert!(worst <= 1e-6, "z differs by {worst}");
    for bad in ["0.0", "-0.001", "nan", "inf"] {
        let e = scene_of("box_mm.obj", &format!("scale = {bad}\n")).unwrap_err().to_string();
        assert!(e.contains("box_mm.obj") && e.contains("scale = ") && e.contains("positive finite"), "{bad}: {e}");
    }
    let model = VERIFIER.model_as("box_mm.obj", &d, Default::default(), 0.001).unwrap();
    let unscaled = VERIFIER.model("box_mm.obj", &d).unwrap();
    for v in 0..box_model().positions.len() as u32 {
        assert!((model.mesh.vertex(v) - box_model().vertex(v)).length() < 1e-12, "vertex {v}");
        assert!((unscaled.mesh.vertex(v) - 1000.0 * box_model().vertex(v)).length() < 1e-9, "vertex {v}");
    }
}

/// An L-shaped step (x, z profile (0,0) (2,0) (2,1) (1,1) (1,2) (0,2), 1 deep in y) as an OBJ
/// without groups: its eight faces, each L-shaped side fanned from the inner corner, so that
/// every edge is shared whole (no T-junctions).
fn ungrouped_step() -> String {
    let profile = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)];
    let mut text: String =
        [0, 1].iter().flat_map(|&y| profile.iter().map(move |(x, z)| format!("v {x} {y} {z}\n"))).collect();
    // Sides (y = 0: vertices 1–6, y = 1: 7–12), fanned from the inner corner (vertex 4 / 10).
    for (a, b) in [(6, 1), (1, 2), (2, 3), (5, 6)] {
        text += &format!("f 4 {a} {b}\nf 10 {} {}\n", b + 6, a + 6);
    }
    // The six faces around the profile, each a quad of two triangles.
    for k in 0..6 {
        let (a, b) = (k + 1, (k + 1) % 6 + 1);
        text += &format!("f {a} {b} {}\nf {a} {} {}\n", b + 6, b + 6, a + 6);
    }
    text
}

/// A model without surfaces of its own is `smooth` by default: a box its six faces, a cylinder
/// its top, bottom and side, a sphere one surface, a step its eight faces; `planar`, `whole`
/// and a crease angle regroup them, and `groups` is refused where the file names none.
#[test]
fn a_model_without_surfaces_of_its_own_gets_smooth_ones() {
    let d = fresh_dir("model_formats", "smooth");
    let count = |path: &Path| load(path).surface_names.len();
    // The built-in step's sides are each two faces meeting at a T-junction: joined along it.
    for (model, surfaces) in
        [("builtin:box", 6), ("builtin:cylinder:32", 3), ("builtin:sphere:32", 1), ("builtin:step", 8)]
    {
        let path = written(
            &d,
            &format!("{}.stl", &model[8..].replace(':', "_")),
            &stl_bytes(&builtin_mesh(model).unwrap(), true),
        );
        assert_eq!(count(&path), surfaces, "{model}");
    }
    let step = written(&d, "step.obj", ungrouped_step().as_bytes());
    let mesh = load(&step);
    assert_eq!(mesh.surface_names, (1..=8).map(|i| format!("smooth {i}")).collect::<Vec<_>>());
    assert!(!mesh.surfaces_from_file);
    let choice = |rule: Option<SurfaceRule>, crease: Option<f64>| SurfaceChoice::from_keys(rule, crease, "object 1");
    let regrouped = |path: &Path, rule, crease| load(path).with_surfaces(choice(rule, crease).unwrap());
    let cylinder = d.join("cylinder_32.stl");
    // The cylinder's side facets turn by 11.25°: a crease of 10° parts all 32 of them.
    assert_eq!(regrouped(&cylinder, Some(SurfaceRule::Smooth), Some(10.0)).unwrap().surface_names.len(), 34);
    assert_eq!(regrouped(&cylinder, Some(SurfaceRule::Planar), None).unwrap().surface_names.len(), 34);
    assert_eq!(regrouped(&cylinder, Some(SurfaceRule::Whole), None).unwrap().surface_names, ["whole"]);
    let e = regrouped(&cylinder, Some(SurfaceRule::Groups), None).unwrap_err().to_string();
    assert!(e.contains("cylinder_32.stl") && e.contains("surfaces = \"groups\""), "{e}");
    // A built-in's faces are its own; whole, it is one surface.
    let builtin = builtin_mesh("builtin:step").unwrap();
    assert_eq!(
        builtin.clone().with_surfaces(choice(Some(SurfaceRule::Groups), None).unwrap()).unwrap().surface_names.len(),
        8
    );
    assert_eq!(
        builtin.clone().with_surfaces(choice(Some(SurfaceRule::Whole), None).unwrap()).unwrap().surface_names.len(),
        1
    );
    let smooth = builtin.clone().with_surfaces(choice(Some(SurfaceRule::Smooth), None).unwrap()).unwrap();
    assert_eq!(smooth.surface_names.len(), 8);
    // Its triangles fall into the same eight groups as its own faces.
    let pairs: std::collections::BTreeSet<(u32, u32)> =
        builtin.triangle_surfaces.iter().copied().zip(smooth.triangle_surfaces.iter().copied()).collect();
    assert_eq!(pairs.len(), 8, "{pairs:?}");
    for (rule, crease, expected) in [
        (Some(SurfaceRule::Planar), Some(30.0), "crease_deg applies to surfaces = \"smooth\""),
        (None, Some(0.0), "crease_deg = 0 must lie in (0, 180]"),
        (Some(SurfaceRule::Smooth), Some(f64::NAN), "crease_deg = NaN"),
    ] {
        let e = choice(rule, crease).unwrap_err().to_string();
        assert!(e.contains("object 1: ") && e.contains(expected), "{e}");
    }
}

/// A scene's object and a hypothesis choose their model's surfaces by key, and labels follow:
/// the step whole is one label, its cylinder creased at 10° thirty-four.
#[test]
fn objects_and_hypotheses_choose_their_models_surfaces() {
    let d = fresh_dir("model_formats", "choose");
    std::fs::write(d.join("step.obj"), ungrouped_step()).unwrap();
    let scene = |keys: &str| {
        let text = format!(
            "[sensor]\nkind = \"orthographic\"\nwidth = 8\nheight = 8\npitch = [0.5, 0.5]\norigin = [-1.75, 1.75]\n\
             theta_deg = 0.0\n[[object]]\nmodel = \"step.obj\"\n{keys}"
        );
        rangesynth::Scene::from_toml(&text, &d, &Ledger::default())
    };
    let labels = |keys: &str| scene(keys).unwrap().objects[0].mesh.surface_names.clone();
    assert_eq!(labels("").len(), 8);
    assert_eq!(labels("surfaces = \"whole\"\n"), ["whole"]);
    assert_eq!(labels("surfaces = \"planar\"\n").len(), 8);
    let e = scene("surfaces = \"groups\"\n").unwrap_err().to_string();
    assert!(e.contains("step.obj") && e.contains("groups"), "{e}");
    let e = scene("surfaces = \"planar\"\ncrease_deg = 20\n").unwrap_err().to_string();
    assert!(e.contains("object 1 (\"step.obj\")") && e.contains("crease_deg"), "{e}");
    let e = scene("surfaces = \"curved\"\n").unwrap_err().to_string();
    assert!(e.contains("curved"), "{e}");
    // A crease angle alone asks for smooth surfaces: the cylinder's 11.25° facets part at 10°.
    std::fs::write(d.join("cylinder.stl"), stl_bytes(&builtin_mesh("builtin:cylinder:32").unwrap(), true)).unwrap();
    let creased = scene("crease_deg = 10\n[[object]]\nmodel = \"cylinder.stl\"\ncrease_deg = 10\n").unwrap();
    assert_eq!(creased.objects[1].mesh.surface_names.len(), 34);
    let file = r#"{"hypotheses": [
        {"id": "a", "model": "step.obj", "pose": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
        {"id": "b", "model": "step.obj", "surfaces": "whole", "pose": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]}"#;
    let file = rangesynth::verify::HypothesisFile::from_json(file, &Ledger::default()).unwrap();
    let meshes: Vec<usize> = file
        .hypotheses
        .iter()
        .map(|h| VERIFIER.model_as(&h.model, &d, h.surfaces, h.scale).unwrap().mesh.surface_names.len())
        .collect();
    assert_eq!(meshes, [8, 1]);
    let bad = r#"{"hypotheses": [{"id": "c", "model": "step.obj", "crease_deg": -1, "pose": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]}"#;
    let e = rangesynth::verify::HypothesisFile::from_json(bad, &Ledger::default()).err().unwrap().to_string();
    assert!(e.contains("hypothesis \"c\"") && e.contains("crease_deg = -1"), "{e}");
}
