//! Hostile input, round two (issue "Hostile input, round two"): what sits between the parsers —
//! dependencies that panic, a budget per file rather than per run, expansion factors assumed
//! rather than measured, outputs that replace inputs, errors that do not say which hypothesis
//! or that echo raw input. Each case runs the real binary or library and failed before the
//! change it names; tests/memory.rs measures the expansion factors themselves.

mod common;

use common::cli::{fresh_dir, rangesynth_command, refused, text};
use rangesynth::limits::{Ledger, MemoryBudget};
use rangesynth::Scene;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Output;

const SENSOR: &str = "[sensor]\nkind = \"orthographic\"\nwidth = 32\nheight = 24\npitch = [0.1, 0.1]\norigin = [-1.5, 1.1]\ntheta_deg = 30.0\n[shadow]\nmode = \"label\"\n";
const IDENTITY: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
/// Two triangles facing the sensor, in two groups.
const TWO_FACES: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\ng a\nusemtl grey\nf 1 2 3\ng b\nf 1 3 4\n";

fn run(args: &[&str], budget: Option<&str>) -> Output {
    let mut command = rangesynth_command();
    command.env_remove("RANGESYNTH_MEMORY_BUDGET").args(args);
    if let Some(budget) = budget {
        command.args(["--memory-budget", budget]);
    }
    command.output().expect("the binary runs")
}

fn succeeded(out: &Output, what: &str) {
    assert!(out.status.success(), "{what}: {:?}\n{}", out.status, text(&out.stderr));
}

fn write(path: PathBuf, text: impl AsRef<[u8]>) -> PathBuf {
    std::fs::write(&path, text).unwrap();
    path
}

fn render(scene: &Path, out: &Path, budget: Option<&str>) -> Output {
    run(&["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap()], budget)
}

fn verify(hyps: &Path, exr: &Path, out: &Path) -> Output {
    let args = ["verify", hyps.to_str().unwrap(), "--scene", exr.to_str().unwrap(), "--out", out.to_str().unwrap()];
    run(&args, None)
}

fn scene_of(d: &Path, models: &[&str]) -> PathBuf {
    let objects: String = models.iter().map(|m| format!("[[object]]\nmodel = \"{m}\"\n")).collect();
    write(d.join("scene.toml"), format!("{SENSOR}{objects}"))
}

#[test]
fn a_material_library_in_any_form_the_format_allows_is_read_not_panicked_on() {
    let d = fresh_dir("hostile_two", "mtl_forms");
    write(d.join("m.mtl"), "newmtl grey\nKd 0.5\nKs 1 1\nKa spectral grey.rfl\nnewmtl xyz\nKd xyz 0.2 0.2 0.2\n");
    write(d.join("m.obj"), format!("mtllib m.mtl\n{TWO_FACES}"));
    let scene = write(
        d.join("scene.toml"),
        format!("{SENSOR}[effects.reflectivity]\nthreshold = 0.3\n[[object]]\nmodel = \"m.obj\"\n"),
    );
    succeeded(&render(&scene, &d.join("out"), None), "Kd 0.5");
    // The grey material's reflectivity (0.5, above the minimum) keeps its pixels.
    let mesh = rangesynth::mesh::load_obj(&d.join("m.obj"), &Ledger::default()).unwrap();
    assert_eq!(mesh.surface_reflectivity, [Some(0.5), Some(0.5)]);
}

#[test]
fn one_model_under_many_spellings_is_loaded_and_charged_once() {
    let d = fresh_dir("hostile_two", "spellings");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    // 500,000 vertices (cheap to render, as none is used but the triangle's): loading the
    // model charges about 28 MB, forty times far over 300M.
    let mut text = String::from("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nf 1 2 3\n");
    text += &"v 0 0 0\n".repeat(500_000);
    write(d.join("m.obj"), text);
    std::os::unix::fs::symlink(d.join("m.obj"), d.join("link.obj")).unwrap();
    let spellings: Vec<String> = (0..40)
        .map(|i| match i % 4 {
            0 => "m.obj".to_string(),
            1 => format!("{}m.obj", "./".repeat(i)),
            2 => "sub/../m.obj".to_string(),
            _ => "link.obj".to_string(),
        })
        .collect();
    let spellings: Vec<&str> = spellings.iter().map(String::as_str).collect();
    let scene = scene_of(&d, &spellings);
    let parsed = Scene::from_file(&scene, &Ledger::new(MemoryBudget::new(300 << 20))).unwrap();
    assert_eq!(parsed.objects.len(), 40);
    assert!(parsed.objects.iter().all(|o| std::sync::Arc::ptr_eq(&o.mesh, &parsed.objects[0].mesh)), "one model");
    succeeded(&render(&scene, &d.join("out"), Some("300M")), "40 spellings under 300M");
}

/// A long-lived verifier keeps the models it loaded, by file identity; a model rewritten in
/// place (same inode, as `cp new.obj m.obj` leaves it) is read anew, not served as it was.
#[test]
fn a_model_rewritten_in_place_is_read_anew_by_a_long_lived_verifier() {
    let d = fresh_dir("hostile_two", "rewritten_model");
    let path = write(d.join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let first = common::VERIFIER.model("m.obj", &d).unwrap();
    assert_eq!(first.mesh.triangles.len(), 1);
    std::fs::OpenOptions::new().append(true).open(&path).unwrap().write_all(b"v 1 1 0\nf 2 4 3\n").unwrap();
    let again = common::VERIFIER.model("m.obj", &d).unwrap();
    assert_eq!(again.mesh.triangles.len(), 2, "the model as the file holds it now");
    assert!(std::sync::Arc::ptr_eq(&again, &common::VERIFIER.model("./m.obj", &d).unwrap()), "and kept");
}

#[test]
fn a_library_named_by_many_lines_is_read_once() {
    let d = fresh_dir("hostile_two", "mtllib_lines");
    write(d.join("big.mtl"), format!("newmtl grey\nKd 0.5\n{}", "# padding line\n".repeat(140_000)));
    let lines = "mtllib big.mtl\nmtllib ./big.mtl\n".repeat(5);
    write(d.join("m.obj"), format!("{lines}{TWO_FACES}"));
    let scene = scene_of(&d, &["m.obj"]);
    // The 2 MiB library once fits 6 MiB; ten times would not.
    succeeded(&render(&scene, &d.join("out"), Some("6M")), "ten mtllib lines");
}

#[test]
fn the_budget_covers_the_whole_run_and_a_refusal_names_the_input_that_crossed_it() {
    let d = fresh_dir("hostile_two", "whole_run");
    // Each model fits alone; the two together do not.
    let model = format!("v -1 -1 0\nv 1 -1 0\nv 1 1 0\n{}", "f 1 2 3\n".repeat(40_000));
    write(d.join("a.obj"), &model);
    write(d.join("b.obj"), &model);
    let one = scene_of(&d, &["a.obj"]);
    succeeded(&render(&one, &d.join("out"), Some("24M")), "one model");
    let two = scene_of(&d, &["a.obj", "b.obj"]);
    let e = refused(&render(&two, &d.join("out"), Some("24M")), "two models", "b.obj");
    assert!(e.contains("on top of the") && e.contains("the run already holds"), "{e}");
}

#[test]
fn many_groups_and_objects_are_charged_before_they_are_built_and_leave_no_output() {
    let d = fresh_dir("hostile_two", "groups");
    // Empty groups: 2 bytes of text each, but a surface and a label each.
    write(d.join("groups.obj"), format!("{TWO_FACES}{}", "g\n".repeat(500_000)));
    let scene = scene_of(&d, &["groups.obj"]);
    let out = d.join("out");
    refused(&render(&scene, &out, Some("64M")), "empty groups", "groups.obj");
    // 2,000 groups under 200 objects: 400,000 labels, charged as the objects are read.
    write(d.join("many.obj"), format!("{TWO_FACES}{}", "g\n".repeat(2_000)));
    let scene = scene_of(&d, &["many.obj"; 200]);
    refused(&render(&scene, &out, Some("24M")), "labels", "labels so far");
    // 100,000 objects: the scene's text is charged as it is parsed.
    let scene =
        write(d.join("objects.toml"), format!("{SENSOR}{}", "[[object]]\nmodel = \"builtin:box\"\n".repeat(100_000)));
    refused(&render(&scene, &out, Some("256M")), "100,000 objects", "parsing the scene's TOML");
    assert!(!out.exists(), "a refused render writes nothing");
}

#[test]
fn a_huge_value_under_an_unknown_key_is_refused_without_echoing_it() {
    let d = fresh_dir("hostile_two", "unknown_key");
    // 4 MB of TOML whose tree would take about 700 MB.
    let scene = write(d.join("scene.toml"), format!("{SENSOR}x = [{}1]\n", "1,".repeat(2_000_000)));
    let e = refused(&render(&scene, &d.join("out"), Some("512M")), "unknown key", "parsing the scene's TOML");
    assert!(e.len() < 1000, "{} bytes of message", e.len());
    // Within the budget, the key is named on its line, and the line is not echoed.
    let scene = write(d.join("scene.toml"), format!("{SENSOR}x = [{}1\u{1b}]\n", "1,".repeat(100_000)));
    let e = refused(&render(&scene, &d.join("out"), None), "unknown key", "line 10");
    assert!(e.len() < 1000 && !e.contains('\u{1b}'), "{} bytes of message", e.len());
}

#[test]
fn verify_never_writes_over_any_file_it_read_material_libraries_included() {
    let d = fresh_dir("hostile_two", "protected");
    write(d.join("m.mtl"), "newmtl grey\nKd 0.5\n");
    write(d.join("m.obj"), format!("mtllib m.mtl\n{TWO_FACES}"));
    let sensed_scene = scene_of(&d, &["m.obj"]);
    succeeded(&render(&sensed_scene, &d.join("sensed"), None), "sensed");
    let hyps = serde_json::json!({"hypotheses": [{"id": "h", "model": "m.obj", "pose": serde_json::from_str::<serde_json::Value>(IDENTITY).unwrap()}]});
    let hyps = write(d.join("h.json"), hyps.to_string());
    let exr = d.join("sensed/range.exr");
    for target in ["m.mtl", "m.obj", "h.json", "sensed/range.exr"] {
        let before = std::fs::read(d.join(target)).unwrap();
        let out = verify(&hyps, &exr, &d.join(target));
        refused(&out, target, "this output is one of the run's inputs");
        assert_eq!(std::fs::read(d.join(target)).unwrap(), before, "{target} changed");
    }
    // A render whose output set would replace its own model's material library.
    std::fs::create_dir_all(d.join("set")).unwrap();
    write(d.join("set/labels.json"), "newmtl grey\nKd 0.5\n");
    write(d.join("set/m.obj"), format!("mtllib labels.json\n{TWO_FACES}"));
    let scene = write(d.join("set/scene.toml"), format!("{SENSOR}[[object]]\nmodel = \"m.obj\"\n"));
    let out = render(&scene, &d.join("set"), None);
    refused(&out, "render over its library", "this output is one of the run's inputs");
    assert_eq!(std::fs::read_to_string(d.join("set/labels.json")).unwrap(), "newmtl grey\nKd 0.5\n");
}

#[test]
fn geometry_is_read_as_written() {
    let d = fresh_dir("hostile_two", "as_written");
    let plain = "v -1 -1 0\nv 1 -1 0\nv -1 1 0\nv 1 1 5\nf 1 2 3\n";
    let render_of = |name: &str, text: &str| {
        write(d.join(name), text);
        let scene = write(d.join(format!("{name}.toml")), format!("{SENSOR}[[object]]\nmodel = \"{name}\"\n"));
        let out = d.join(format!("{name}.out"));
        succeeded(&render(&scene, &out, None), name);
        rangesynth::io::read_range_image(&out.join("range.exr"), &Ledger::default()).unwrap()
    };
    let expected = render_of("plain.obj", plain);
    assert!(expected.label.iter().any(|&l| l != 0), "the triangle is seen");
    for (name, text) in [
        ("bom.obj", format!("\u{feff}{plain}")),
        ("crlf.obj", plain.replace('\n', "\r\n")),
        ("cr.obj", plain.replace('\n', "\r")),
        ("lines.obj", format!("{plain}l 1 2 4\nl 2 3 4 1\np 4\n")),
    ] {
        let image = render_of(name, &text);
        assert_eq!(image.label, expected.label, "{name}: a different image");
        assert_eq!(
            image.z.iter().map(|z| z.to_bits()).collect::<Vec<_>>(),
            expected.z.iter().map(|z| z.to_bits()).collect::<Vec<_>>(),
            "{name}"
        );
    }
}

#[test]
fn errors_name_the_hypothesis_and_escape_what_they_quote() {
    let d = fresh_dir("hostile_two", "named");
    let sensed_scene = scene_of(&d, &["builtin:box"]);
    succeeded(&render(&sensed_scene, &d.join("sensed"), None), "sensed");
    let exr = d.join("sensed/range.exr");
    let pose = |z: f64| serde_json::json!([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, z], [0, 0, 0, 1]]);
    let mut list: Vec<serde_json::Value> = (0..5000)
        .map(|i| serde_json::json!({"id": format!("h{i}"), "model": "builtin:box", "pose": pose(0.0)}))
        .collect();
    list[3120] = serde_json::json!({"id": "far\u{1b}[2J\naway", "model": "builtin:box", "pose": pose(1e30)});
    let hyps = write(d.join("h.json"), serde_json::json!({"hypotheses": list}).to_string());
    let out = verify(&hyps, &exr, &d.join("s.jsonl"));
    let e = refused(&out, "far hypothesis", "hypothesis \"far\\u{1b}[2J\\naway\": ");
    assert!(!e.contains('\u{1b}') && e.trim_end().lines().count() == 1, "raw input reached the terminal: {e:?}");
    // A run that succeeds prints its ranking with the ids escaped and cut too.
    let ids = ["clear\u{1b}[2J", "\u{202e}reversed", &"long".repeat(25_000)];
    let list: Vec<serde_json::Value> =
        ids.iter().map(|id| serde_json::json!({"id": id, "model": "builtin:box", "pose": pose(0.0)})).collect();
    let hyps = write(d.join("ids.json"), serde_json::json!({"hypotheses": list}).to_string());
    let out = verify(&hyps, &exr, &d.join("ids.jsonl"));
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("clear\\u{1b}[2J") && stdout.contains("\\u{202e}reversed"), "{stdout}");
    assert!(!stdout.contains(['\u{1b}', '\u{202e}']), "raw input reached the terminal: {stdout:?}");
    assert!(stdout.lines().all(|line| line.len() < 1000), "an id printed whole: {stdout:?}");
    // A bad budget setting is named once, as the setting it is.
    let out = rangesynth_command()
        .env("RANGESYNTH_MEMORY_BUDGET", "4X")
        .args(["render", sensed_scene.to_str().unwrap(), "--out", d.join("x").to_str().unwrap()])
        .output()
        .unwrap();
    let e = refused(&out, "budget variable", "RANGESYNTH_MEMORY_BUDGET: \"4X\" has an unknown unit");
    assert!(!e.contains("invalid scene"), "{e}");
}
