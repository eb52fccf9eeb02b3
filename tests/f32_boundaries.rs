//! f32 at every boundary (issue "Hostile input, round two", item 6): parameters each valid
//! alone whose combination the GPU computes in f32 (src/render/plan/gpu_arithmetic.rs, the
//! sensor's grid in src/sensor/orthographic.rs, a model's coordinates in src/mesh/mod.rs). Each refusal
//! below is of a scene that `render` used to accept, writing ±inf into valid pixels (which
//! `verify` then refused to read) or an image with the wrong pixels; each scene just inside
//! the bounds renders an image whose every valid z is finite, and `verify` accepts it and
//! scores the object that made it.

mod common;

use common::cli::{fresh_dir, rangesynth_command, refused, text};
use rangesynth::io::read_range_image;
use rangesynth::limits::Ledger;
use std::path::{Path, PathBuf};
use std::process::Output;

const IDENTITY: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

/// A pose translating by (x, y, z).
fn at(x: f64, y: f64, z: f64) -> String {
    format!("[[1,0,0,{x:e}],[0,1,0,{y:e}],[0,0,1,{z:e}],[0,0,0,1]]")
}

/// A pose turning by 30° about z.
fn turned() -> String {
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    format!("[[{c},{},0,0],[{s},{c},0,0],[0,0,1,0],[0,0,0,1]]", -s)
}

/// A 16×16 sensor with these pitch and origin, at θ.
fn sensor(pitch: f64, origin: [f64; 2], theta_deg: f64) -> String {
    format!(
        "[sensor]\nkind = \"orthographic\"\nwidth = 16\nheight = 16\npitch = [{pitch:e}, {pitch:e}]\n\
         origin = [{:e}, {:e}]\ntheta_deg = {theta_deg}\n[shadow]\nmode = \"depth\"\n",
        origin[0], origin[1]
    )
}

/// The sensor centred on (x, y).
fn sensor_over(pitch: f64, (x, y): (f64, f64), theta_deg: f64) -> String {
    sensor(pitch, [x - 7.5 * pitch, y + 7.5 * pitch], theta_deg)
}

fn scene_text(sensor: &str, objects: &[(&str, String)], effects: &str) -> String {
    let objects: String =
        objects.iter().map(|(model, pose)| format!("[[object]]\nmodel = \"{model}\"\npose = {pose}\n")).collect();
    format!("{sensor}{objects}{effects}")
}

fn run(args: &[&str]) -> Output {
    rangesynth_command().env_remove("RANGESYNTH_MEMORY_BUDGET").args(args).output().expect("the binary runs")
}

fn render(dir: &Path, scene: &str) -> (Output, PathBuf) {
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.join("out");
    (run(&["render", path.to_str().unwrap(), "--out", out.to_str().unwrap()]), out)
}

/// Verifies one hypothesis (`model` at `pose`) against `exr`, with `extra` keys in its file.
fn verify(dir: &Path, exr: &Path, (model, pose): (&str, &str), extra: &str, flags: &[&str]) -> Output {
    let hyps = dir.join("hyps.json");
    let file = format!("{{{extra}\"hypotheses\": [{{\"id\": \"h\", \"model\": \"{model}\", \"pose\": {pose}}}]}}");
    std::fs::write(&hyps, file).unwrap();
    let scores = dir.join("scores.jsonl");
    let mut args = vec!["verify", hyps.to_str().unwrap(), "--scene", exr.to_str().unwrap()];
    args.extend(["--out", scores.to_str().unwrap()]);
    args.extend(flags);
    run(&args)
}

#[test]
fn combinations_the_gpus_f32_cannot_hold_are_refused_by_name() {
    let box_at = |pose: String| vec![("builtin:box", pose)];
    let cases: Vec<(&str, String, &str)> = vec![
        // Quantization divides z by the step: 100 / 2e-38 overflows (was: Z = inf).
        (
            "quantize",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 30.0),
                &box_at(at(0.0, 0.0, 100.0)),
                "[effects.quantize]\nz_step = 2e-38\n",
            ),
            "effects.quantize.z_step = 2e-38",
        ),
        // σ grows with (z − reference)²: 1e18 · (1e10)² is 1e38, and z ± 6σ overflows (was: Z = -inf).
        (
            "noise",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 30.0),
                &box_at(IDENTITY.into()),
                "[effects.noise]\nsigma = 0\ndepth_coefficient = 1e18\ndepth_reference = 1e10\n",
            ),
            "effects.noise",
        ),
        // A pixel's squared area is 1e-120 (was: 128 of the box's 256 pixels).
        (
            "tiny pitch",
            scene_text(&sensor_over(1e-30, (0.0, 0.0), 0.0), &box_at(IDENTITY.into()), ""),
            "pitch [1e-30, 1e-30]",
        ),
        // Its squared area overflows (was: an image without the box).
        ("huge pitch", scene_text(&sensor(1e38, [0.0, 0.0], 0.0), &box_at(IDENTITY.into()), ""), "pitch [1e38, 1e38]"),
        // f32 coordinates there are 7.6e22 apart (was: an image without the box).
        (
            "far origin",
            scene_text(&sensor(1.0, [1e30, 1e30], 0.0), &box_at(at(1e30, 1e30, 0.0)), ""),
            "origin [1e30, 1e30]",
        ),
        // The box reaches 4.2e7 pixels from the first: f32 window coordinates are 4 pixels apart (was:
        // 146 pixels where the geometry has 123).
        (
            "seen reach",
            scene_text(&sensor_over(3e-8, (0.4, 0.3), 0.0), &box_at(turned()), ""),
            "object 1 (builtin:box) reaches 4.220e7 pixels",
        ),
        // Beside the image, but 5e30 pixels away.
        (
            "unseen reach",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 0.0),
                &[("builtin:box", IDENTITY.into()), ("builtin:box", at(5e29, 0.0, 0.0))],
                "",
            ),
            "object 2 (builtin:box) reaches 5.000e30 pixels",
        ),
        (
            "far in depth",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 0.0),
                &[("builtin:box", IDENTITY.into()), ("builtin:box", at(5.0, 0.0, 1e31))],
                "",
            ),
            "object 2 (builtin:box) reaches 1.000e31 model units",
        ),
        // Beside a small plate (a depth range of 0.014), 1e29 deep: 7e30 depth ranges away.
        (
            "many depth ranges away",
            scene_text(
                &sensor_over(0.0001, (0.0, 0.0), 0.0),
                &[("builtin:plane:0.01", IDENTITY.into()), ("builtin:box", at(5.0, 0.0, 1e29))],
                "",
            ),
            "times the range view's depth range from it",
        ),
    ];
    for (name, scene, expected) in cases {
        let d = fresh_dir("f32_boundaries", &name.replace(' ', "_"));
        let (out, dir) = render(&d, &scene);
        refused(&out, name, expected);
        assert!(!dir.exists(), "{name}: no output set is left");
    }
}

/// What shows nowhere is never refused for what the GPU would compute where it showed: a view
/// with nothing in it far from the frame's origin, and effects that would overflow only at
/// depths where nothing is.
#[test]
fn what_shows_nowhere_is_not_checked_as_if_it_showed() {
    let d = fresh_dir("f32_boundaries", "shows_nowhere");
    // The sensor 1e8 from the origin at θ = 30°: the shadow view's local origin lies 5e7 deep,
    // where an empty view's depth range about 0 would have no f32 span.
    let far = scene_text(&sensor_over(10.0, (1e8, 0.0), 30.0), &[("builtin:box", IDENTITY.into())], "");
    let (out, dir) = render(&d, &far);
    assert!(out.status.success(), "an empty view far from the origin: {}", text(&out.stderr));
    assert!(read_range_image(&dir.join("range.exr"), &Ledger::default()).unwrap().label.iter().all(|&l| l == 0));
    // Noise whose σ overflows at z ≈ 0 but not near 1e10, where the scene is; a hypothesis
    // posed beside the image, at z = 0, is no reason to refuse the verification.
    let noisy = "[effects.noise]\nsigma = 0\ndepth_coefficient = 1e18\ndepth_reference = 1e10\n";
    let scene = scene_text(&sensor_over(1024.0, (0.0, 0.0), 0.0), &[("builtin:box", at(0.0, 0.0, 1e10))], noisy);
    let (out, dir) = render(&d, &scene);
    assert!(out.status.success(), "noise about the scene's depth: {}", text(&out.stderr));
    let out = verify(&d, &dir.join("range.exr"), ("builtin:box", &at(1e6, 0.0, 0.0)), "", &[]);
    assert!(out.status.success(), "a hypothesis out of view: {}", text(&out.stderr));
}

#[test]
fn a_model_beyond_the_coordinates_f32_rotates_is_refused() {
    let d = fresh_dir("f32_boundaries", "model_coordinates");
    std::fs::write(d.join("far.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 2e30\nf 1 2 3\n").unwrap();
    let scene = scene_text(&sensor_over(0.1, (0.0, 0.0), 0.0), &[("far.obj", IDENTITY.into())], "");
    let (out, _) = render(&d, &scene);
    refused(&out, "a vertex at 2e30", "within ±1e30");
}

#[test]
fn effects_a_hypothesis_file_names_are_checked_for_each_hypothesis() {
    let d = fresh_dir("f32_boundaries", "hypothesis_effects");
    let scene = scene_text(&sensor_over(0.1, (0.0, 0.0), 30.0), &[("builtin:box", IDENTITY.into())], "");
    let (out, dir) = render(&d, &scene);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let exr = dir.join("range.exr");
    let effects = "\"effects\": {\"quantize\": {\"z_step\": 2e-38}},";
    let out = verify(&d, &exr, ("builtin:box", &at(0.0, 0.0, 100.0)), effects, &["--override-effects"]);
    let message = refused(&out, "a hypothesis at z = 100 quantized at 2e-38", "effects.quantize.z_step");
    assert!(message.contains("hypothesis \"h\""), "{message}");
}

/// Scenes just inside each bound: every valid pixel's z is finite, and `verify` reads the
/// image and finds the object that made it, every pixel of it within the tolerance.
#[test]
fn scenes_at_the_edges_of_the_bounds_render_finite_images_that_verify_accepts() {
    let plane = |size: f64| format!("builtin:plane:{size:e}");
    let cases: Vec<(&str, String, (String, String))> = vec![
        // z / z_step reaches about 1.4e36.
        (
            "fine quantization",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 30.0),
                &[("builtin:box", IDENTITY.into())],
                "[effects.quantize]\nz_step = 1e-36\n",
            ),
            ("builtin:box".into(), IDENTITY.into()),
        ),
        // σ reaches about 1e34 at the largest coefficients, then quantized.
        (
            "loud noise",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 30.0),
                &[("builtin:box", IDENTITY.into())],
                "[effects.noise]\nsigma = 1e18\ndepth_coefficient = 1e18\ndepth_reference = 1e8\n\
                 incidence_coefficient = 1e18\n[effects.quantize]\nz_step = 1e-3\n",
            ),
            ("builtin:box".into(), IDENTITY.into()),
        ),
        // A pixel's area is 1.2e-19: its square is just a normal f32.
        (
            "small pitch",
            scene_text(&sensor_over(3.4e-10, (0.0, 0.0), 30.0), &[(&plane(2e-8), IDENTITY.into())], ""),
            (plane(2e-8), IDENTITY.into()),
        ),
        // A pixel's area is 1.6e19, its square 2.6e38.
        (
            "large pitch",
            scene_text(&sensor_over(4e9, (0.0, 0.0), 30.0), &[(&plane(1e11), IDENTITY.into())], ""),
            (plane(1e11), IDENTITY.into()),
        ),
        // f32 coordinates at 1e6 are 0.0625 apart, a quarter of the pitch.
        (
            "far origin",
            scene_text(&sensor_over(0.25, (1e6, -1e6), 30.0), &[("builtin:box", at(1e6, -1e6, 0.0))], ""),
            ("builtin:box".into(), at(1e6, -1e6, 0.0)),
        ),
        // Shadow mode `exact` rasterizes nothing: a plate reaching 1e7 pixels is cast on the host.
        (
            "exact mode, far reach",
            scene_text(&sensor_over(0.0001, (0.0, 0.0), 30.0), &[(&plane(2000.0), IDENTITY.into())], "")
                .replace("mode = \"depth\"", "mode = \"exact\""),
            (plane(2000.0), IDENTITY.into()),
        ),
        // A box far beside the image, 1e22 pixels away, changes nothing.
        (
            "far neighbour",
            scene_text(
                &sensor_over(0.1, (0.0, 0.0), 30.0),
                &[("builtin:box", IDENTITY.into()), ("builtin:box", at(1e21, 0.0, 0.0))],
                "",
            ),
            ("builtin:box".into(), IDENTITY.into()),
        ),
    ];
    for (name, scene, (model, pose)) in cases {
        let d = fresh_dir("f32_boundaries", &name.replace(' ', "_"));
        let (out, dir) = render(&d, &scene);
        assert!(out.status.success(), "{name}: {}", text(&out.stderr));
        let exr = dir.join("range.exr");
        let image = read_range_image(&exr, &Ledger::default()).unwrap();
        let valid: Vec<f32> = image.label.iter().zip(&image.z).filter(|(&l, _)| l != 0).map(|(_, &z)| z).collect();
        assert!(!valid.is_empty(), "{name}: the object shows");
        assert!(valid.iter().all(|z| z.is_finite()), "{name}: a valid pixel's z is not finite");
        let out = verify(&d, &exr, (&model, &pose), "\"tolerance\": 1e30,", &[]);
        assert!(out.status.success(), "{name}: verify refused the image render wrote: {}", text(&out.stderr));
        let line = std::fs::read_to_string(d.join("scores.jsonl")).unwrap();
        let record: serde_json::Value = serde_json::from_str(line.lines().next().unwrap()).unwrap();
        let counts = &record["counts"];
        assert_eq!(counts["n1_plus"], counts["n_i"], "{name}: every valid pixel of the object agrees: {line}");
        assert_eq!(counts["n_i"].as_u64(), Some(valid.len() as u64), "{name}: {line}");
    }
}
