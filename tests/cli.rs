//! The binary end to end: the demo, `render` of a scene file, and bad input, which must give a
//! clear message and a non-zero exit code, never a panic. Validation is on throughout (the
//! CLI exits non-zero when validation reports anything).

mod common;

use common::cli::{fresh_dir, rangesynth_command, text};
use std::path::{Path, PathBuf};
use std::process::Output;

fn rangesynth(args: &[&str]) -> Output {
    rangesynth_command().args(args).output().expect("the binary runs")
}

fn dir(name: &str) -> PathBuf {
    fresh_dir("cli", name)
}

#[test]
fn demo_writes_the_images_and_a_summary() {
    let out_dir = dir("demo");
    let out = rangesynth(&["demo", "--out", out_dir.to_str().unwrap()]);
    let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
    assert!(out.status.success(), "demo failed:\n{stdout}\n{stderr}");
    assert!(stdout.contains("device: "), "{stdout}");
    assert!(stdout.contains("low_top") && stdout.contains("shadowed"), "{stdout}");
    // The demo scene has a shadow pass and no effects: exactly these passes, in this order.
    let passes = stdout.lines().find(|l| l.starts_with("GPU time per pass: ")).expect("a pass-time line");
    let names: Vec<&str> =
        passes["GPU time per pass: ".len()..].split(", ").map(|p| p.rsplitn(3, ' ').nth(2).unwrap_or(p)).collect();
    assert_eq!(names, ["range", "shadow", "shadow mask"], "{passes}");
    for f in ["range.exr", "label_unshadowed.exr", "labels.json", "range.png", "label.png", "label_unshadowed.png"] {
        assert!(out_dir.join(f).is_file(), "{f} missing");
    }
    // The low top is partly shadowed by the tall part, the high top not at all.
    let row = |name: &str| {
        stdout
            .lines()
            .find(|l| l.contains(name))
            .unwrap()
            .split_whitespace()
            .rev()
            .take(2)
            .map(|v| v.parse::<u64>().unwrap())
            .collect::<Vec<_>>()
    };
    let (low_shadowed, low_valid) = (row("low_top")[0], row("low_top")[1]);
    assert!(low_shadowed > 1000 && low_valid > 1000, "{stdout}");
    assert_eq!(row("high_top")[0], 0);
}

fn write_scene(d: &Path, body: &str) -> PathBuf {
    let path = d.join("scene.toml");
    std::fs::write(&path, body).unwrap();
    path
}

const SENSOR: &str = "[sensor]\nkind = \"orthographic\"\nwidth = 32\nheight = 24\npitch = [0.1, 0.1]\norigin = [-1.5, 1.1]\ntheta_deg = 30.0\n";

#[test]
fn render_reads_a_scene_file_with_an_obj_model() {
    let d = dir("render");
    std::fs::write(d.join("tri.obj"), "v -1 -1 0\nv 1 -1 0\nv 0 1 0.5\ng only\nf 1 2 3\n").unwrap();
    let scene = write_scene(&d, &format!("{SENSOR}[shadow]\nmode = \"label\"\n[[object]]\nmodel = \"tri.obj\"\n[[object]]\nmodel = \"builtin:box\"\npose = [[1,0,0,0.9],[0,1,0,0],[0,0,1,-2],[0,0,0,1]]\n"));
    let out = rangesynth(&["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()]);
    assert!(out.status.success(), "{}{}", text(&out.stdout), text(&out.stderr));
    let labels = std::fs::read_to_string(d.join("out/labels.json")).unwrap();
    assert!(labels.contains("\"tri.obj\"") && labels.contains("\"builtin:box\""), "{labels}");
}

/// Runs `render` on a scene body and returns stderr, asserting a clean failure.
fn refused(name: &str, body: &str) -> String {
    refused_in(&dir(name), name, body)
}

fn refused_in(d: &Path, name: &str, body: &str) -> String {
    let scene = write_scene(d, body);
    let out = rangesynth(&["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{name}: expected exit code 1, stderr:\n{stderr}");
    assert!(stderr.starts_with("error: "), "{name}: {stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    stderr
}

/// `render` under a rig names the rule `auto` followed (`Renderer::rig_crossover`): on a CPU
/// device the scanner's for one object in the depth test, the rigs' own for a rig without
/// witnesses (no test on the GPU), as the renderer applies them.
#[test]
fn render_under_a_rig_names_the_crossover_it_followed() {
    let d = dir("rig_crossover");
    let rig = |witnesses: &str| {
        format!(
            "[sensor]\nkind = \"pinhole\"\nwidth = 48\nheight = 40\nfx = 50\nfy = 50\ncx = 23.5\ncy = 19.5\n{witnesses}\
             [shadow]\nmode = \"depth\"\n[[object]]\nmodel = \"builtin:box\"\npose = [[1.0, 0.0, 0.0, 0.0], \
             [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 4.0], [0.0, 0.0, 0.0, 1.0]]\n"
        )
    };
    let projector = "[[sensor.witness]]\nname = \"projector\"\nkind = \"directional\"\ndirection = [0.6, 0.0, -0.8]\n";
    for (name, witnesses) in [("with a witness", projector), ("without witnesses", "")] {
        let scene = write_scene(&d, &rig(witnesses));
        let out_dir = d.join(name.replace(' ', "_"));
        let out =
            rangesynth(&["--raster", "auto", "render", scene.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
        let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
        assert!(out.status.success(), "{name}: {stdout}\n{stderr}");
        let line = stdout.lines().find(|l| l.starts_with("raster: ")).expect("a raster line");
        let cpu = stdout.lines().any(|l| l.starts_with("device: ") && l.contains("llvmpipe"));
        let rule = match (cpu, witnesses.is_empty()) {
            (false, _) => "at least 1500 triangles",
            (true, false) => "at least 0.0001 triangles per footprint pixel",
            (true, true) => "at least 0.03 triangles per footprint pixel",
        };
        assert!(line.contains(rule), "{name}: {line}");
    }
}

#[test]
fn bad_scenes_are_refused_with_a_clear_message() {
    let object = "[[object]]\nmodel = \"builtin:box\"\n";
    let cases: &[(&str, String, &str)] = &[
        ("malformed", "[sensor\nwidth = 3".into(), "scene.toml"),
        ("no_sensor", object.into(), "missing field `sensor`"),
        (
            "incomplete_sensor",
            "[sensor]\nkind = \"orthographic\"\nwidth = 4\n".into(),
            "[sensor] kind = \"orthographic\" needs height",
        ),
        ("zero_width", SENSOR.replace("width = 32", "width = 0") + object, "at least 1"),
        ("too_large", SENSOR.replace("height = 24", "height = 100000") + object, "limited to"),
        ("theta_90", SENSOR.replace("theta_deg = 30.0", "theta_deg = 90.0") + object, "must lie between -89 and 89"),
        (
            "theta_minus_120",
            SENSOR.replace("theta_deg = 30.0", "theta_deg = -120.0") + object,
            "must lie between -89 and 89",
        ),
        ("theta_nan", SENSOR.replace("theta_deg = 30.0", "theta_deg = nan") + object, "must lie between -89 and 89"),
        ("pitch_zero", SENSOR.replace("pitch = [0.1, 0.1]", "pitch = [0.0, 0.1]") + object, "positive finite"),
        ("unknown_key", SENSOR.to_string() + "colour = 3\n" + object, "unknown field `colour`"),
        ("unknown_mode", SENSOR.to_string() + "[shadow]\nmode = \"soft\"\n" + object, "unknown variant `soft`"),
        ("unknown_kind", SENSOR.replace("\"orthographic\"", "\"fisheye\"") + object, "unknown variant `fisheye`"),
        (
            "pinhole_with_pitch",
            SENSOR.replace("\"orthographic\"", "\"pinhole\"") + object,
            "[sensor] kind = \"pinhole\" has no key pitch",
        ),
        ("missing_model", SENSOR.to_string() + "[[object]]\nmodel = \"nowhere.obj\"\n", "nowhere.obj: No such file"),
        ("unknown_builtin", SENSOR.to_string() + "[[object]]\nmodel = \"builtin:teapot\"\n", "unknown built-in"),
        (
            "non_rigid",
            SENSOR.to_string() + object + "pose = [[2,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n",
            "not a rigid transform",
        ),
        ("projective", SENSOR.to_string() + object + "pose = [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]]\n", "last row"),
        ("negative_sigma", SENSOR.to_string() + object + "[effects.noise]\nsigma = -1\n", "effects.noise.sigma = -1"),
        (
            "dropout_above_1",
            SENSOR.to_string() + object + "[effects.dropout]\nprobability = 1.5\n",
            "effects.dropout.probability = 1.5",
        ),
        ("zero_step", SENSOR.to_string() + object + "[effects.quantize]\nz_step = 0\n", "effects.quantize.z_step = 0"),
        (
            "flat_grazing",
            SENSOR.to_string() + object + "[effects.grazing]\nmax_incidence_deg = 0\n",
            "effects.grazing.max_incidence_deg = 0",
        ),
        ("unknown_effect", SENSOR.to_string() + object + "[effects.bloom]\n", "unknown field `bloom`"),
        ("bright_object", SENSOR.to_string() + object + "reflectivity = 2\n", "reflectivity = 2 is out of range"),
        (
            "nan_pose",
            SENSOR.to_string() + object + "pose = [[1,0,0,nan],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n",
            "non-finite",
        ),
    ];
    for (name, body, expected) in cases {
        let stderr = refused(name, body);
        assert!(stderr.contains(expected), "{name}: expected {expected:?} in:\n{stderr}");
    }
}

#[test]
fn bad_models_in_a_scene_are_refused_with_a_clear_message() {
    let cases = [
        ("nan_vertex", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite coordinate"),
        ("bad_index", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "tri.obj"),
        ("no_triangles", "v 0 0 0\nv 1 0 0\n", "no (non-degenerate) triangles"),
        ("garbage", "this is not an obj file\n\u{0}\u{1}", "tri.obj"),
    ];
    for (name, obj, expected) in cases {
        let d = dir(name);
        std::fs::write(d.join("tri.obj"), obj).unwrap();
        let stderr = refused_in(&d, name, &(SENSOR.to_string() + "[[object]]\nmodel = \"tri.obj\"\n"));
        assert!(stderr.contains(expected), "{name}: expected {expected:?} in:\n{stderr}");
    }
}

#[test]
fn degenerate_triangles_give_a_warning() {
    let d = dir("degenerate");
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 2\n").unwrap();
    let scene = write_scene(&d, &(SENSOR.to_string() + "[[object]]\nmodel = \"tri.obj\"\n"));
    let out = rangesynth(&["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()]);
    assert!(out.status.success());
    assert!(text(&out.stderr).contains("dropped 1 degenerate triangle"), "{}", text(&out.stderr));
}

#[test]
fn an_unknown_device_name_is_refused() {
    let d = dir("device");
    let out = rangesynth(&["demo", "--device", "no-such-gpu", "--out", d.to_str().unwrap()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no usable Vulkan device") && stderr.contains("not named \"no-such-gpu\""), "{stderr}");
}

/// `rangesynth verify HYPS --scene SENSED --out SCORES [extra…]`.
fn verify(hypotheses: &Path, sensed: &Path, scores: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "verify",
        hypotheses.to_str().unwrap(),
        "--scene",
        sensed.to_str().unwrap(),
        "--out",
        scores.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    rangesynth(&args)
}

/// Renders the example's sensed scene and returns (directory, path of range.exr).
fn sensed_example(name: &str) -> (PathBuf, PathBuf) {
    let d = dir(name);
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/example");
    let out = rangesynth(&[
        "render",
        example.join("sensed.toml").to_str().unwrap(),
        "--out",
        d.join("sensed").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let exr = d.join("sensed/range.exr");
    (d, exr)
}

#[test]
fn verify_scores_the_example_and_ranks_the_correct_hypothesis_first() {
    let (d, exr) = sensed_example("verify_example");
    let hyps = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/example/hypotheses.json");
    let scores = d.join("scores.jsonl");
    let out = verify(&hyps, &exr, &scores, &["--compare-shadow"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    let first_ranked = stdout.lines().find(|l| l.trim_start().starts_with("1 ")).expect("a ranked summary");
    assert!(first_ranked.contains("step-correct"), "{stdout}");
    let lines: Vec<serde_json::Value> =
        std::fs::read_to_string(&scores).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(lines.len(), 3);
    assert_eq!(lines[0]["id"], "step-correct");
    for key in ["s1", "s2", "s3", "s4", "s5", "s6", "s"] {
        assert!(lines[0][key].as_f64().is_some(), "{key} in {}", lines[0]);
    }
    assert!(lines[0]["rejected"].is_null());
    assert!(lines[0]["counts"]["n_i"].as_u64().unwrap() > 0);
    // Shadowing raises the correct hypothesis' score (the paper's §4 finding).
    assert!(lines[0]["s"].as_f64().unwrap() > lines[0]["unshadowed"]["s"].as_f64().unwrap());
    assert!(lines[2]["rejected"].as_str().unwrap().contains("s5"), "{}", lines[2]);
}

/// A hypothesis file in `d` of `n` hypotheses of the example's step, turned from its sensed
/// pose (25°) by `step` radians more each.
fn turning_steps(d: &Path, n: u32, step: f64) -> PathBuf {
    let hypotheses: Vec<serde_json::Value> = (0..n)
        .map(|i| {
            let a = 0.4363323129985824 + f64::from(i) * step;
            serde_json::json!({
                "id": format!("h{i}"),
                "model": "builtin:step",
                "pose": [[a.cos(), -a.sin(), 0.0, 0.3], [a.sin(), a.cos(), 0.0, -0.2], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]],
                "bindings": [[1, 1], [2, 2]]
            })
        })
        .collect();
    let hyps = d.join("hyps.json");
    std::fs::write(&hyps, serde_json::json!({ "hypotheses": hypotheses }).to_string()).unwrap();
    hyps
}

#[test]
fn verify_runs_a_batch_of_1024_from_the_cli() {
    let (d, exr) = sensed_example("verify_1024");
    let hyps = turning_steps(&d, 1024, 0.0005);
    let scores = d.join("scores.jsonl");
    let out = verify(&hyps, &exr, &scores, &["--chunk-size", "300"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let lines = std::fs::read_to_string(&scores).unwrap();
    assert_eq!(lines.lines().count(), 1024);
    assert!(text(&out.stdout).contains("1024 hypotheses"));
}

/// The summary says how many hypotheses each rasterizer rendered. The step: 20 triangles over
/// its footprint of about 190² pixels (bounding radius 1.84 at pitch 0.02, with margins), 0.0006
/// a pixel; a plate filling the image: 2 triangles over 256², 0.00003 a pixel; and the step far
/// outside the image, which renders nothing. `auto` on a CPU device takes compute from 0.0001
/// a pixel (the step); on a GPU under 0.004 too (both).
#[test]
fn verify_says_how_many_hypotheses_each_rasterizer_rendered() {
    let (d, exr) = sensed_example("verify_rasters");
    let pose = |x: f64| [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
    let hypotheses = serde_json::json!({ "hypotheses": [
        { "id": "step", "model": "builtin:step", "pose": pose(0.0), "bindings": [[1, 1]] },
        { "id": "plate", "model": "builtin:plane:8", "pose": pose(0.0), "bindings": [[1, 1]] },
        { "id": "away", "model": "builtin:step", "pose": pose(100.0), "bindings": [[1, 1]] },
    ]});
    let hyps = d.join("hyps.json");
    std::fs::write(&hyps, hypotheses.to_string()).unwrap();
    let raster_line = |flags: &[&str]| {
        let out = verify(&hyps, &exr, &d.join("scores.jsonl"), flags);
        let stdout = text(&out.stdout);
        assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
        stdout.lines().find(|l| l.starts_with("raster: ")).expect("a raster line").to_string()
    };
    let not_rendered = "1 not rendered (outside the image, or cast by exact mode)";
    let auto = match common::renderer().context().is_cpu() {
        true => "1 by compute, 1 by graphics",
        false => "2 by compute, 0 by graphics",
    };
    let line = raster_line(&[]);
    assert!(line.starts_with("raster: auto (") && line.ends_with(&format!("): {auto}, {not_rendered}")), "{line}");
    let line = raster_line(&["--raster", "graphics"]);
    assert_eq!(line, format!("raster: graphics: 0 by compute, 2 by graphics, {not_rendered}"));
    // Shadow mode exact casts every hypothesis' rays on the host: none is rasterized.
    let mut exact = hypotheses.clone();
    exact["shadow"] = serde_json::json!({ "mode": "exact" });
    std::fs::write(&hyps, exact.to_string()).unwrap();
    let line = raster_line(&["--raster", "graphics"]);
    assert_eq!(
        line,
        "raster: graphics: 0 by compute, 0 by graphics, 3 not rendered (outside the image, or cast by exact mode)"
    );
}

#[test]
fn verify_covers_hypotheses_in_groups_with_the_same_scores() {
    let (d, exr) = sensed_example("verify_grouped");
    let hyps = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/example/hypotheses.json");
    let scores = |n: &str| {
        let path = d.join(format!("scores-{n}.jsonl"));
        let out = verify(&hyps, &exr, &path, &["--raster", "compute", "--hypotheses-per-dispatch", n]);
        let stdout = text(&out.stdout);
        assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
        let expected = format!("compute rasterizer: up to {n} hypothes");
        assert!(stdout.lines().any(|l| l.starts_with(&expected)), "{expected:?} in {stdout}");
        std::fs::read_to_string(path).unwrap()
    };
    // The example's three hypotheses in one coverage dispatch, and each in its own.
    assert_eq!(scores("3"), scores("1"));
    for bad in ["0", "5", "many"] {
        let out = verify(&hyps, &exr, &d.join("s.jsonl"), &["--hypotheses-per-dispatch", bad]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {stderr}");
        assert!(stderr.contains("--hypotheses-per-dispatch"), "{bad}: {stderr}");
    }
}

/// `--slots` and `--chunks-in-flight`: the example's three hypotheses side by side in three
/// slots in one chunk, and one a run in one slot, in chunks of one, two or four at once, score
/// the same; the summary says how many; out-of-range counts are refused by name.
#[test]
fn verify_keeps_the_slots_and_chunks_asked_for_with_the_same_scores() {
    let (d, exr) = sensed_example("verify_slots");
    let hyps = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/example/hypotheses.json");
    let scores = |slots: &str, chunks: &str| {
        let path = d.join(format!("scores-{slots}-{chunks}.jsonl"));
        let flags = ["--slots", slots, "--chunks-in-flight", chunks, "--chunk-size", slots];
        let out = verify(&hyps, &exr, &path, &flags);
        let stdout = text(&out.stdout);
        assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
        let expected = format!("batches: up to {slots} hypothes");
        let chunks = format!("up to {chunks} chunk");
        assert!(stdout.lines().any(|l| l.starts_with(&expected) && l.contains(&chunks)), "{expected:?} in {stdout}");
        std::fs::read_to_string(path).unwrap()
    };
    let three_slots = scores("3", "1");
    assert_eq!(three_slots, scores("1", "2"));
    assert_eq!(three_slots, scores("1", "4"));
    let bad_values = [
        ("--slots", "0"),
        ("--slots", "65"),
        ("--slots", "many"),
        ("--chunks-in-flight", "5"),
        ("--memory-budget", "0"),
        ("--memory-budget", "abc"),
        ("--memory-budget", "1e30G"),
        ("--memory-budget", "16E"),
    ];
    for (flag, bad) in bad_values {
        let out = verify(&hyps, &exr, &d.join("s.jsonl"), &[flag, bad]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {bad}: {stderr}");
        assert!(stderr.contains(flag), "{flag} {bad}: {stderr}");
    }
}

#[test]
fn bad_hypothesis_files_are_refused_with_a_clear_message() {
    let (d, exr) = sensed_example("verify_bad");
    let pose = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    let cases = [
        ("not_json", "{".to_string(), "EOF"),
        ("no_hypotheses", "{}".to_string(), "missing field `hypotheses`"),
        ("negative_tolerance", r#"{"tolerance": -1, "hypotheses": []}"#.to_string(), "tolerance -1"),
        ("bad_pose", r#"{"hypotheses": [{"id": "a", "model": "builtin:box", "pose": [[3,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]}"#.to_string(), "not a rigid transform"),
        ("bad_surface", format!(r#"{{"hypotheses": [{{"id": "a", "model": "builtin:box", "pose": {pose}, "bindings": [[1, 9]]}}]}}"#), "binding (1, 9) names no surface"),
        ("label_zero", format!(r#"{{"hypotheses": [{{"id": "a", "model": "builtin:box", "pose": {pose}, "bindings": [[0, 1]]}}]}}"#), "label 0"),
        ("bad_model", format!(r#"{{"hypotheses": [{{"id": "a", "model": "missing.obj", "pose": {pose}}}]}}"#), "missing.obj"),
    ];
    for (name, body, expected) in cases {
        let hyps = d.join(format!("{name}.json"));
        std::fs::write(&hyps, body).unwrap();
        let out = verify(&hyps, &exr, &d.join("s.jsonl"), &[]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(stderr.contains(expected) && !stderr.contains("panicked"), "{name}: expected {expected:?} in {stderr}");
    }
    // A sensed image with no sensor header, and no "sensor" in the hypothesis file.
    let bare = d.join("bare.exr");
    let mut image = rangesynth::io::read_range_image(&exr, &Default::default()).unwrap();
    image.sensor = None;
    rangesynth::io::write_range_image(&bare, &image).unwrap();
    let hyps = d.join("ok.json");
    std::fs::write(&hyps, format!(r#"{{"hypotheses": [{{"id": "a", "model": "builtin:box", "pose": {pose}}}]}}"#))
        .unwrap();
    let out = verify(&hyps, &bare, &d.join("s.jsonl"), &[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("no sensor settings"), "{}", text(&out.stderr));
    let garbage = d.join("garbage.exr");
    std::fs::write(&garbage, "not an exr").unwrap();
    let out = verify(&hyps, &garbage, &d.join("s.jsonl"), &[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("not a usable OpenEXR file"), "{}", text(&out.stderr));
}

#[test]
fn verify_takes_the_effects_from_the_sensed_header_and_refuses_a_mismatch() {
    let d = dir("verify_effects");
    let effects = "[effects.noise]\nsigma = 0.003\nseed = 8\n[effects.dropout]\nprobability = 0.1\nseed = 2\n";
    let body = format!(
        "{}[shadow]\nmode = \"depth\"\n[[object]]\nmodel = \"builtin:step\"\n{effects}",
        SENSOR
            .replace("width = 32", "width = 64")
            .replace("height = 24", "height = 48")
            .replace("0.1, 0.1", "0.06, 0.06")
    );
    let scene = write_scene(&d, &body);
    let out = rangesynth(&["render", scene.to_str().unwrap(), "--out", d.join("sensed").to_str().unwrap()]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("effects: dropout, noise") && stdout.contains("pixels lost: shadow"), "{stdout}");
    assert!(stdout.contains("dropout") && stdout.contains(", noise "), "{stdout}");
    let exr = d.join("sensed/range.exr");
    let image = rangesynth::io::read_range_image(&exr, &Default::default()).unwrap();
    let header = image.effects.expect("the header records the effects");
    assert_eq!(header.noise.map(|n| (n.sigma, n.seed)), Some((0.003, 8)));
    let dropped = image.reason.expect("a reason channel").iter().filter(|&&r| r == 7).count();
    assert!(dropped > 0);

    let identity = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    let bindings = "[[1,1],[2,2],[3,3],[4,4],[5,5],[6,6],[7,7],[8,8]]";
    let file = |effects: &str| {
        format!(
            r#"{{{effects}"hypotheses": [{{"id": "true", "model": "builtin:step", "pose": {identity}, "bindings": {bindings}}}]}}"#
        )
    };
    let s_of = |name: &str, effects: &str| {
        let hyps = d.join(format!("{name}.json"));
        std::fs::write(&hyps, file(effects)).unwrap();
        let scores = d.join(format!("{name}.jsonl"));
        let out = verify(&hyps, &exr, &scores, &[]);
        (out, scores)
    };
    // From the header, and named alike in the file: the true pose reproduces the image.
    let same = r#""effects": {"dropout": {"probability": 0.1, "seed": 2}, "noise": {"sigma": 0.003, "seed": 8}}, "#;
    for (name, effects) in [("from_header", ""), ("same", same)] {
        let (out, scores) = s_of(name, effects);
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
        let line: serde_json::Value = serde_json::from_str(std::fs::read_to_string(&scores).unwrap().trim()).unwrap();
        assert_eq!(line["s"].as_f64(), Some(1.0), "{name}: {line}");
    }
    for (name, effects) in [("none", r#""effects": {}, "#), ("other_seed", &same.replace("\"seed\": 8", "\"seed\": 9"))]
    {
        let (out, _) = s_of(name, effects);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(stderr.contains("names the effects") && stderr.contains("was made with"), "{name}: {stderr}");
    }
    // A simpler sensor model than the image's, on request: the true pose no longer scores 1.
    let hyps = d.join("simpler.json");
    std::fs::write(&hyps, file(r#""effects": {}, "#)).unwrap();
    let scores = d.join("simpler.jsonl");
    let out = verify(&hyps, &exr, &scores, &["--override-effects"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_str(std::fs::read_to_string(&scores).unwrap().trim()).unwrap();
    assert!(line["s"].as_f64().unwrap() < 0.99, "{line}");
    let (out, _) = s_of("bad", r#""effects": {"noise": {"sigma": -2}}, "#);
    assert!(text(&out.stderr).contains("effects.noise.sigma = -2"), "{}", text(&out.stderr));
}

/// A hypothesis' `"scale"` reads a millimetre model into the metre scene: the millimetre box
/// at scale 0.001 scores exactly as the metre box does, and without the scale it does not.
#[test]
fn verify_reads_a_hypothesis_models_scale() {
    let d = dir("verify_scale");
    let corners: Vec<[f64; 3]> =
        (0..8).map(|i| [(i & 1) as f64 - 0.5, ((i >> 1) & 1) as f64 - 0.5, ((i >> 2) & 1) as f64]).collect();
    let faces = "g bottom\nf 1 3 4 2\ng top\nf 5 6 8 7\ng front\nf 1 2 6 5\ng back\nf 3 7 8 4\ng left\nf 1 5 7 3\ng right\nf 2 4 8 6\n";
    for (name, unit) in [("box_m.obj", 1.0), ("box_mm.obj", 1000.0)] {
        let vertices: String =
            corners.iter().map(|c| format!("v {} {} {}\n", c[0] * unit, c[1] * unit, c[2] * unit)).collect();
        std::fs::write(d.join(name), vertices + faces).unwrap();
    }
    let pose = "[[0.8,-0.6,0,0.1],[0.6,0.8,0,0],[0,0,1,0],[0,0,0,1]]";
    let scene = write_scene(&d, &format!("{SENSOR}[[object]]\nmodel = \"box_m.obj\"\npose = {pose}\n"));
    let out = rangesynth(&["render", scene.to_str().unwrap(), "--out", d.join("sensed").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let bindings = "[[1,1],[2,2],[3,3],[4,4],[5,5],[6,6]]";
    let hypothesis = |id: &str, model: &str, scale: &str| {
        format!(r#"{{"id": "{id}", "model": "{model}", {scale}"pose": {pose}, "bindings": {bindings}}}"#)
    };
    let hyps = d.join("hypotheses.json");
    let list = [
        hypothesis("metre", "box_m.obj", ""),
        hypothesis("millimetre", "box_mm.obj", r#""scale": 0.001, "#),
        hypothesis("unscaled", "box_mm.obj", ""),
    ];
    std::fs::write(&hyps, format!(r#"{{"hypotheses": [{}]}}"#, list.join(","))).unwrap();
    let scores = d.join("scores.jsonl");
    let out = verify(&hyps, &d.join("sensed/range.exr"), &scores, &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let lines: Vec<serde_json::Value> =
        std::fs::read_to_string(&scores).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    let by_id = |id: &str| lines.iter().find(|l| l["id"] == id).unwrap_or_else(|| panic!("{id} scored"));
    for key in ["s1", "s2", "s3", "s4", "s5", "s6", "s", "counts"] {
        assert_eq!(by_id("millimetre")[key], by_id("metre")[key], "{key}");
    }
    assert!(by_id("metre")["s"].as_f64().unwrap() > 0.9, "{}", by_id("metre"));
    assert_ne!(by_id("unscaled")["counts"], by_id("metre")["counts"]);
}

/// `verify` under a pinhole camera and projector, from the command line: the sensed EXR's
/// header carries the rig, the true pose of the one box scores exactly 1, and a hypothesis
/// file whose rig differs from the header is refused naming the key (`fx`); with
/// `--override-sensor` its rig is taken, and the true pose no longer scores 1; a sensor of
/// another kind of view is refused even then.
#[test]
fn verify_scores_under_a_pinhole_rig_and_refuses_a_rig_that_differs() {
    let d = dir("verify_rig");
    let rig = "[sensor]\nkind = \"pinhole\"\nwidth = 96\nheight = 72\nfx = 90.0\nfy = 90.0\ncx = 47.5\ncy = 35.5\n\
               [[sensor.witness]]\nname = \"projector\"\nkind = \"pinhole\"\n\
               pose = [[1,0,0,0.3],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n\
               width = 96\nheight = 72\nfx = 60.0\nfy = 60.0\ncx = 47.5\ncy = 35.5\n";
    let pose = "[[0.9,0,0.4358898943540674,0.1],[0,-1,0,0],[0.4358898943540674,0,-0.9,3],[0,0,0,1]]";
    let scene = write_scene(
        &d,
        &format!("{rig}[shadow]\nmode = \"depth\"\n[[object]]\nmodel = \"builtin:box\"\npose = {pose}\n"),
    );
    let out = rangesynth(&["render", scene.to_str().unwrap(), "--out", d.join("sensed").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let exr = d.join("sensed/range.exr");
    let bindings = "[[1,1],[2,2],[3,3],[4,4],[5,5],[6,6]]";
    let file = |sensor: &str| {
        format!(
            r#"{{{sensor}"hypotheses": [{{"id": "true", "model": "builtin:box", "pose": {pose}, "bindings": {bindings}}}]}}"#
        )
    };
    let hyps = d.join("true.json");
    std::fs::write(&hyps, file("")).unwrap();
    let scores = d.join("true.jsonl");
    let out = verify(&hyps, &exr, &scores, &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_str(std::fs::read_to_string(&scores).unwrap().trim()).unwrap();
    assert_eq!(line["s"].as_f64(), Some(1.0), "{line}");
    assert!(line["counts"]["n_i"].as_u64().unwrap() > 100, "{line}");

    let other = r#""sensor": {"kind": "pinhole", "width": 96, "height": 72, "fx": 95.0, "fy": 90.0, "cx": 47.5, "cy": 35.5, "witness": [{"name": "projector", "kind": "pinhole", "pose": [[1,0,0,0.3],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "width": 96, "height": 72, "fx": 60.0, "fy": 60.0, "cx": 47.5, "cy": 35.5}]}, "#;
    let hyps = d.join("other.json");
    std::fs::write(&hyps, file(other)).unwrap();
    let out = verify(&hyps, &exr, &d.join("other.jsonl"), &[]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("fx = 95") && stderr.contains("90"), "{stderr}");
    // The file's rig on request: the sensed pixels read through other intrinsics no longer
    // match the true pose's.
    let scores = d.join("other.jsonl");
    let out = verify(&hyps, &exr, &scores, &["--override-sensor"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let line: serde_json::Value = serde_json::from_str(std::fs::read_to_string(&scores).unwrap().trim()).unwrap();
    assert!(line["s"].as_f64().unwrap() < 0.99, "{line}");
    // Never another kind of view, even on request: its depths mean something else.
    let scanner = r#""sensor": {"kind": "orthographic", "width": 96, "height": 72, "pitch": [0.01, 0.01], "origin": [0, 0], "theta_deg": 30}, "#;
    let hyps = d.join("scanner.json");
    std::fs::write(&hyps, file(scanner)).unwrap();
    let out = verify(&hyps, &exr, &d.join("scanner.jsonl"), &["--override-sensor"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("is a view of kind pinhole but the sensor's reference view is orthographic"), "{stderr}");
}

/// `--shard i/N` verifies the i-th of N contiguous ranges: the three shards' outputs of a file
/// of 10 hypotheses, concatenated in order, are the unsharded output byte for byte, and a
/// shard that is not i/N with i < N is refused.
#[test]
fn verify_shards_concatenate_to_the_unsharded_output() {
    let (d, exr) = sensed_example("verify_shards");
    let hyps = turning_steps(&d, 10, 0.05);
    let whole = d.join("whole.jsonl");
    let out = verify(&hyps, &exr, &whole, &[]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut joined = Vec::new();
    for i in 0..3 {
        let part = d.join(format!("part{i}.jsonl"));
        let out = verify(&hyps, &exr, &part, &["--shard", &format!("{i}/3")]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        joined.extend(std::fs::read(&part).unwrap());
    }
    assert_eq!(String::from_utf8(joined).unwrap(), std::fs::read_to_string(&whole).unwrap());
    let out = verify(&hyps, &exr, &d.join("bad.jsonl"), &["--shard", "3/3"]);
    assert!(!out.status.success() && text(&out.stderr).contains("not i/N"), "{}", text(&out.stderr));
}
