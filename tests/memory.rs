//! The expansion factors the memory budget charges are measured, not assumed: each input
//! below is made of one kind of element alone (the worst case for that element's factor), and
//! a counting allocator measures the most memory its parse held at once, which must not
//! exceed what the parse charged to its ledger. A factor set too low fails here, naming the
//! input; docs/limits.md gives the factors and these measurements.

mod common;

use common::counting::{thread_peak_during, Counting};
use rangesynth::limits::{Ledger, MemoryBudget};
use rangesynth::mesh::{parse_obj, parse_ply, parse_stl, Mesh};
use rangesynth::scene::load_model;
use rangesynth::verify::HypothesisFile;
use rangesynth::Scene;
use std::path::Path;

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The most bytes `parse` held at once beyond what was live before it, and what it charged
/// to its ledger (the input text itself, held by the caller, is charged but not counted).
fn measure(input_bytes: usize, parse: impl FnOnce(&Ledger)) -> (usize, u64) {
    let ledger = Ledger::new(MemoryBudget::new(64 << 30));
    let peak = thread_peak_during(|| parse(&ledger));
    (peak + input_bytes, ledger.held())
}

fn assert_charged(what: &str, input: &str, parse: impl FnOnce(&Ledger)) {
    let (peak, charged) = measure(input.len(), parse);
    println!(
        "{what}: {} bytes of text, {peak} bytes at most ({:.1}× the text), {charged} charged ({:.1}×)",
        input.len(),
        peak as f64 / input.len() as f64,
        charged as f64 / input.len() as f64
    );
    assert!(peak as u64 <= charged, "{what}: parsing held {peak} bytes but charged only {charged}");
}

fn obj(what: &str, text: &str) {
    assert_charged(what, text, |ledger| {
        let _ = parse_obj(text.as_bytes(), what, ledger).expect(what);
    });
}

const N: usize = 100_000;

#[test]
fn obj_parsing_holds_no_more_than_it_charges() {
    let grid = |n: usize| {
        let mut text = String::new();
        for i in 0..=n {
            for j in 0..=n {
                text += &format!("v {i} {j} 0\n");
            }
        }
        for i in 0..n {
            for j in 0..n {
                let a = i * (n + 1) + j + 1;
                text += &format!("f {a} {} {}\nf {} {} {a}\n", a + 1, a + n + 2, a + n + 2, a + n + 1);
            }
        }
        text
    };
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    obj(
        "vertices",
        &format!("{}f 1 2 3\n", "v 0 0 0\n".repeat(N) + triangle)
            .replace("f 1 2 3", &format!("f {} {} {}", N + 1, N + 2, N + 3)),
    );
    obj("triangles", &format!("{triangle}{}", "f 1 2 3\n".repeat(N)));
    obj(
        "polygons",
        &format!(
            "v 0 0 0\n{}{}",
            "v 1 0 0\nv 0 1 0\n".repeat(50),
            format!("f 1 {}\n", (2..=101).map(|i| i.to_string()).collect::<Vec<_>>().join(" ")).repeat(N / 50)
        ),
    );
    obj("empty groups", &format!("{triangle}f 1 2 3\n{}", "g\n".repeat(N)));
    obj("named groups", &format!("{triangle}f 1 2 3\n{}", "g a\n".repeat(N)));
    obj("a face a group", &format!("{triangle}{}", "g\nf 1 2 3\n".repeat(N)));
    obj("a material a face", &format!("{triangle}g a\n{}", "usemtl a\nf 1 2 3\nusemtl b\nf 1 2 3\n".repeat(N / 2)));
    obj("one surface, merged", &grid(150));
}

/// A binary or text model file parsed by `parse`, as `assert_charged` measures text.
fn model_file(what: &str, bytes: &[u8], parse: fn(&[u8], &str, &Ledger) -> rangesynth::Result<Mesh>) {
    let (peak, charged) = measure(bytes.len(), |ledger| {
        let _ = parse(bytes, what, ledger).expect(what);
    });
    println!("{what}: {} bytes, {peak} bytes at most, {charged} charged", bytes.len());
    assert!(peak as u64 <= charged, "{what}: parsing held {peak} bytes but charged only {charged}");
}

/// A PLY header of `vertices` f32 vertices and `faces` faces of int indices.
fn ply_header(format: &str, vertices: usize, faces: usize, extra: &str) -> String {
    format!(
        "ply\nformat {format} 1.0\n{extra}element vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

#[test]
fn ply_and_stl_parsing_hold_no_more_than_they_charge() {
    let triangle = "0 0 0\n1 0 0\n0 1 0\n";
    let ascii = |vertices: usize, faces: usize, extra: &str, body: String| {
        (ply_header("ascii", vertices, faces, extra) + &body).into_bytes()
    };
    model_file(
        "PLY text vertices",
        &ascii(N + 3, 1, "", "0 0 0\n".repeat(N) + triangle + &format!("3 {N} {} {}\n", N + 1, N + 2)),
        parse_ply,
    );
    model_file("PLY text faces", &ascii(3, N, "", triangle.to_string() + &"3 0 1 2\n".repeat(N)), parse_ply);
    let polygon = format!("100 0 {}\n", (1..100).map(|i| (1 + i % 2).to_string()).collect::<Vec<_>>().join(" "));
    model_file("PLY text polygons", &ascii(3, N / 50, "", triangle.to_string() + &polygon.repeat(N / 50)), parse_ply);
    model_file("PLY comments", &ascii(3, 1, &"comment\n".repeat(N), triangle.to_string() + "3 0 1 2\n"), parse_ply);
    let le = |v: &[f32]| v.iter().flat_map(|c| c.to_le_bytes()).collect::<Vec<u8>>();
    let face = [&[3u8][..], &[0i32, 1, 2].map(i32::to_le_bytes).concat()].concat();
    let binary = |vertices: usize, faces: usize, body: Vec<u8>| {
        [ply_header("binary_little_endian", vertices, faces, "").into_bytes(), body].concat()
    };
    let corners = le(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let last_face = [&[3u8][..], &[N as i32, N as i32 + 1, N as i32 + 2].map(i32::to_le_bytes).concat()].concat();
    model_file(
        "PLY binary vertices",
        &binary(N + 3, 1, [le(&[0.5; 3]).repeat(N), corners.clone(), last_face].concat()),
        parse_ply,
    );
    model_file("PLY binary faces", &binary(3, N, [corners.clone(), face.repeat(N)].concat()), parse_ply);
    let surfaces_header = ply_header("ascii", 3, N, "").replace("end_header", "property int surface\nend_header");
    let a_surface_a_face: String = (0..N).map(|s| format!("3 0 1 2 {s}\n")).collect();
    model_file("PLY a surface a face", (surfaces_header + triangle + &a_surface_a_face).as_bytes(), parse_ply);
    // A grid of triangles, one surface to split into its planar faces.
    let mut stl = vec![0u8; 80];
    stl.extend((N as u32).to_le_bytes());
    for t in 0..N {
        let (x, y) = ((t % 300) as f32, (t / 300) as f32);
        stl.extend([0u8; 12]);
        stl.extend(le(&[x, y, 0.0, x + 1.0, y, 0.0, x, y + 1.0, (t % 7) as f32]));
        stl.extend([0u8; 2]);
    }
    model_file("STL binary", &stl, parse_stl);
    let facet = "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
    model_file("STL text", format!("solid s\n{}endsolid s\n", facet.repeat(N)).as_bytes(), parse_stl);
}

#[test]
fn scene_and_hypothesis_parsing_hold_no_more_than_they_charge() {
    const SENSOR: &str =
        "[sensor]\nkind = \"orthographic\"\nwidth = 8\nheight = 8\npitch = [0.1, 0.1]\norigin = [0, 0]\ntheta_deg = 0\n";
    let scene = |what: &str, text: String| {
        assert_charged(what, &text, |ledger| {
            let _ = Scene::from_toml(&text, Path::new("."), ledger);
        })
    };
    scene("an array under an unknown key", format!("{SENSOR}x = [{}1]\n", "1,".repeat(N)));
    scene("a nested array under an unknown key", format!("{SENSOR}x = [{}[]]\n", "[],".repeat(N)));
    scene(
        "a table of one-letter keys",
        format!("{SENSOR}[x]\n{}", (0..N).map(|i| format!("k{i}=1\n")).collect::<String>()),
    );
    scene("objects", format!("{SENSOR}{}", "[[object]]\nmodel=\"builtin:box\"\n".repeat(N / 10)));

    let json = |what: &str, text: String| {
        assert_charged(what, &text, |ledger| {
            let _ = HypothesisFile::from_json(&text, ledger);
        })
    };
    let pose = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    let hypothesis = |i: usize| format!("{{\"id\":\"{i}\",\"model\":\"m\",\"pose\":{pose}}}");
    json("hypotheses", format!("{{\"hypotheses\":[{}]}}", (0..N / 10).map(hypothesis).collect::<Vec<_>>().join(",")));
    let bindings = "[1,1],".repeat(N);
    json(
        "bindings",
        format!("{{\"hypotheses\":[{{\"id\":\"a\",\"model\":\"m\",\"pose\":{pose},\"bindings\":[{bindings}[1,1]]}}]}}"),
    );
    json("an array under an unknown key", format!("{{\"x\":[{}1],\"hypotheses\":[]}}", "1,".repeat(N)));
}

/// Scaling a model (`[[object]] scale`) is charged before the scaled copy is made: building
/// the largest sphere and scaling it hold no more than the two charges.
#[test]
fn scaling_a_model_holds_no_more_than_it_charges() {
    let (peak, charged) = measure(0, |ledger| {
        let mesh = load_model("builtin:sphere:1024", Path::new("."), ledger).expect("built");
        let _ = mesh.scaled(0.001, ledger).expect("scaled");
    });
    println!("scaling: {peak} bytes at most, {charged} charged");
    assert!(peak as u64 <= charged, "scaling held {peak} bytes but charged only {charged}");
}

/// A built-in model is charged before it is built, per triangle (the largest sphere, a million
/// triangles, and a cylinder), as a model file's parse is.
#[test]
fn building_a_builtin_model_holds_no_more_than_it_charges() {
    for name in ["builtin:sphere:1024", "builtin:cylinder:4096"] {
        let (peak, charged) = measure(0, |ledger| {
            let _ = load_model(name, Path::new("."), ledger).expect(name);
        });
        println!("{name}: {peak} bytes at most, {charged} charged");
        assert!(peak as u64 <= charged, "{name}: building held {peak} bytes but charged only {charged}");
    }
}
