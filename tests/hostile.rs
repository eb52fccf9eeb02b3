//! Hostile and careless input, as a long-running daemon meets it (issue "Hostile input and
//! data safety"): every case runs the real binary or library and asserts a clean refusal (exit
//! code 1, a message naming the problem, no panic, no abort, no hang) and that earlier output
//! files survive whole. Each case failed before the fix it names.

mod common;

use common::cli::{fresh_dir, rangesynth_command, refused, text};
use glam::DMat4;
use rangesynth::io::{parse_range_image, read_range_image};
use rangesynth::limits::Ledger;
use rangesynth::mesh::load_obj;
use rangesynth::shadow::ShadowMode;
use rangesynth::Scene;
use std::io::Read;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

fn rangesynth() -> Command {
    let mut c = rangesynth_command();
    c.env_remove("RANGESYNTH_MEMORY_BUDGET");
    c
}

fn run(args: &[&str]) -> Output {
    rangesynth().args(args).output().expect("the binary runs")
}

/// Waits for a child at most `limit`; kills it and fails the test when it takes longer (a
/// hang).
fn finish_within(mut child: Child, limit: Duration, what: &str) -> (ExitStatus, String) {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut stderr = String::new();
            child.stderr.take().map(|mut e| e.read_to_string(&mut stderr));
            return (status, stderr);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("{what}: still running after {limit:?} (a hang)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn dir(name: &str) -> PathBuf {
    fresh_dir("hostile", name)
}

const SENSOR: &str = "[sensor]\nkind = \"orthographic\"\nwidth = 32\nheight = 24\npitch = [0.1, 0.1]\norigin = [-1.5, 1.1]\ntheta_deg = 30.0\n[shadow]\nmode = \"depth\"\n";
const IDENTITY: &str = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";

fn write_scene(d: &Path, name: &str, body: &str) -> PathBuf {
    let path = d.join(name);
    std::fs::write(&path, body).unwrap();
    path
}

/// Renders a box on a plane as the sensed image; returns its range.exr.
fn sensed(d: &Path) -> PathBuf {
    let scene = write_scene(
        d,
        "sensed.toml",
        &format!("{SENSOR}[[object]]\nmodel = \"builtin:box\"\n[[object]]\nmodel = \"builtin:plane:6\"\n"),
    );
    let out = run(&["render", scene.to_str().unwrap(), "--out", d.join("sensed").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    d.join("sensed/range.exr")
}

/// A hypothesis file of boxes at the identity pose, one per (id, bindings).
fn hypotheses(entries: impl IntoIterator<Item = (String, Vec<[u32; 2]>)>) -> serde_json::Value {
    let list: Vec<serde_json::Value> = entries
        .into_iter()
        .map(|(id, bindings)| {
            let pose: serde_json::Value = serde_json::from_str(IDENTITY).unwrap();
            serde_json::json!({"id": id, "model": "builtin:box", "pose": pose, "bindings": bindings})
        })
        .collect();
    serde_json::json!({ "hypotheses": list })
}

fn ids(names: &[&str]) -> Vec<(String, Vec<[u32; 2]>)> {
    names.iter().map(|n| (n.to_string(), vec![])).collect()
}

fn verify(hyps: &Path, exr: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["verify", hyps.to_str().unwrap(), "--scene", exr.to_str().unwrap(), "--out"];
    args.push(out.to_str().unwrap());
    args.extend(extra);
    run(&args)
}

/// Overwrites the dataWindow's xMax in an EXR header (attribute name, type "box2i", size 16,
/// then xMin, yMin, xMax, yMax as little-endian i32).
fn claim_width(bytes: &mut [u8], width: i32) {
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).expect("a dataWindow attribute") + key.len() + 4;
    bytes[at + 8..at + 12].copy_from_slice(&(width - 1).to_le_bytes());
}

// 1. Allocation bomb.
#[test]
fn an_exr_header_claiming_a_huge_image_is_refused_before_allocating() {
    let d = dir("exr_bomb");
    let exr = sensed(&d);
    let mut bytes = std::fs::read(&exr).unwrap();
    claim_width(&mut bytes, 1 << 29);
    let bomb = d.join("bomb.exr");
    std::fs::write(&bomb, &bytes).unwrap();
    let hyps = write_scene(&d, "h.json", &hypotheses(ids(&["a"])).to_string());
    let out = verify(&hyps, &bomb, &d.join("s.jsonl"), &[]);
    assert_ne!(out.status.signal(), Some(libc::SIGABRT), "aborted: {}", text(&out.stderr));
    refused(&out, "2^29 columns", "sides are limited to 16384");

    // Within the side limit, but more than so small a file can hold.
    claim_width(&mut bytes, 16384);
    let e = parse_range_image(&bytes, &bomb, &Ledger::default()).unwrap_err().to_string();
    assert!(e.contains("more than its") && e.contains("can hold"), "{e}");
}

/// A data window that disagrees with the file's blocks is refused, never read with the blocks
/// put on other rows: the window moved down 10 rows and right 10 columns (its blocks still
/// start at row 0), and a window whose corners are the wrong way round. The exr crate read the
/// first as the image moved, the second as a window of the same size.
#[test]
fn an_exr_whose_data_window_disagrees_with_its_blocks_is_refused() {
    let d = dir("exr_window");
    let exr = sensed(&d);
    let bytes = std::fs::read(&exr).unwrap();
    let image = parse_range_image(&bytes, &exr, &Ledger::default()).unwrap();
    let (w, h) = (image.width as i32, image.height as i32);
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).expect("a dataWindow attribute") + key.len() + 4;
    let with_window = |corners: [i32; 4]| {
        let mut patched = bytes.clone();
        for (k, v) in corners.iter().enumerate() {
            patched[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
        parse_range_image(&patched, &exr, &Ledger::default()).map(|_| ()).unwrap_err().to_string()
    };
    let e = with_window([10, 10, w + 9, h + 9]);
    assert!(e.contains("starts at row 0, which is not a block's first row of the data window's rows 10 to"), "{e}");
    let e = with_window([w - 1, h - 1, 0, 0]);
    assert!(e.contains("ends before it begins"), "{e}");
}

// 2. Device files and FIFOs, as models and as material libraries.
#[test]
fn devices_and_fifos_are_never_read() {
    let d = dir("devices");
    let fifo = d.join("fifo.obj");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0.5\nf 1 2 3\n";
    std::fs::write(d.join("zero_mtl.obj"), format!("mtllib /dev/zero\n{triangle}")).unwrap();
    std::fs::write(d.join("fifo_mtl.obj"), format!("mtllib fifo.obj\n{triangle}")).unwrap();
    for (model, ok) in [("/dev/zero", false), ("fifo.obj", false), ("zero_mtl.obj", true), ("fifo_mtl.obj", true)] {
        let scene = write_scene(&d, "scene.toml", &format!("{SENSOR}[[object]]\nmodel = \"{model}\"\n"));
        let child = rangesynth()
            .args(["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let (status, stderr) = finish_within(child, Duration::from_secs(60), model);
        match ok {
            true => assert!(status.success(), "{model}: {stderr}"),
            false => {
                assert_eq!(status.code(), Some(1), "{model}: {stderr}");
                assert!(stderr.contains("is not a regular file"), "{model}: {stderr}");
            }
        }
    }
}

// 3. Built-in names.
#[test]
fn builtin_names_are_capped_and_spellings_of_one_model_load_it_once() {
    let e = rangesynth::mesh::builtin_mesh("builtin:sphere:4096").unwrap_err().to_string();
    assert!(e.contains("from 4 to 1024"), "{e}");
    let objects: String = ["builtin:sphere:64", "builtin:sphere:064", "builtin:sphere:0064", "builtin:sphere:+64"]
        .iter()
        .map(|m| format!("[[object]]\nmodel = \"{m}\"\n"))
        .collect();
    let scene = Scene::from_toml(&format!("{SENSOR}{objects}"), Path::new("."), &Ledger::default()).unwrap();
    let first = &scene.objects[0].mesh;
    assert!(scene.objects.iter().all(|o| std::sync::Arc::ptr_eq(&o.mesh, first)), "one model, built once");
    assert_eq!(first.name, "builtin:sphere:64");
}

// 4. Memory up front.
#[test]
fn work_beyond_the_memory_budget_is_refused_with_its_figure() {
    let d = dir("budget");
    // Without shadows: with them, the device's storage buffers would refuse the image first
    // (see below).
    let big = SENSOR.replace("width = 32", "width = 16384").replace("height = 24", "height = 16384");
    let big = big.replace("mode = \"depth\"", "mode = \"none\"");
    let scene = write_scene(&d, "big.toml", &format!("{big}[[object]]\nmodel = \"builtin:box\"\n"));
    let out = run(&["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()]);
    // 48 bytes a pixel for the range view alone: at least 12 GiB.
    let e = refused(&out, "16384² render", "rendering a 16384×16384 image needs about 1");
    assert!(e.contains(" GiB on top of the ") && e.contains(", more than the memory budget of 4.0 GiB"), "{e}");
    // The budget is the user's to set, by flag or environment.
    let small = write_scene(&d, "small.toml", &format!("{SENSOR}[[object]]\nmodel = \"builtin:box\"\n"));
    let out_dir = d.join("out");
    let args = ["render", small.to_str().unwrap(), "--out", out_dir.to_str().unwrap()];
    let out = rangesynth().args(args).args(["--memory-budget", "16K"]).output().unwrap();
    refused(&out, "--memory-budget", "more than the memory budget of 16.0 KiB");
    let out = rangesynth().args(args).env("RANGESYNTH_MEMORY_BUDGET", "16K").output().unwrap();
    refused(&out, "RANGESYNTH_MEMORY_BUDGET", "more than the memory budget of 16.0 KiB");

    let exr = sensed(&d);
    let hyps = write_scene(&d, "h.json", &hypotheses(ids(&["a"])).to_string());
    let out = verify(&hyps, &exr, &d.join("s.jsonl"), &["--memory-budget", "64K"]);
    refused(&out, "verify", "verifying against a 32×24 image needs about");
    // One budget for the run: reading the 32×24 image (its 1.9 KiB file, 15 KiB decoded) fits
    // 24 KiB; preparing it too (32 bytes a pixel, 24 KiB more) does not.
    let out = verify(&hyps, &exr, &d.join("s.jsonl"), &["--memory-budget", "24K"]);
    refused(&out, "verify", "preparing the 32×24 sensed image");
}

#[test]
fn images_beyond_the_devices_storage_buffers_are_refused_by_name() {
    let renderer = common::renderer();
    let range = renderer.context().max_storage_buffer_range();
    // The smallest square image whose buffers of a word a pixel (the shadowed labels) exceed
    // what the device binds: 5,793² on lavapipe (128 MiB), within the default memory budget.
    let side = ((range / 4) as f64).sqrt().floor() as u32 + 1;
    let sensor = common::centred_sensor(side, side, 1.0 / f64::from(side), [0.0, 0.0], 45.0);
    for mode in [ShadowMode::Label, ShadowMode::Depth] {
        let scene = common::scene(sensor, mode, &[("builtin:box", DMat4::IDENTITY)]);
        let e = renderer.render(&scene).expect_err("refused").to_string();
        assert!(e.contains(&format!("a {side}×{side} image needs")), "{e}");
        assert!(e.contains(&format!("({range} bytes, its maxStorageBufferRange)")), "{e}");
    }
    common::assert_no_validation_messages();
}

// 5. verify's output.
#[test]
fn verify_validates_everything_before_it_writes_and_never_touches_an_input() {
    let d = dir("verify_out");
    let exr = sensed(&d);
    let scores = d.join("scores.jsonl");
    let old = "{\"id\": \"earlier results\"}\n";

    // A bad hypothesis far into the file (past the first 4,096-hypothesis slice).
    let mut entries: Vec<_> = (0..4500).map(|i| (format!("h{i}"), vec![[1, 1]])).collect();
    entries.push(("bad".into(), vec![[1, 99]]));
    let hyps = write_scene(&d, "bad.json", &hypotheses(entries).to_string());
    std::fs::write(&scores, old).unwrap();
    let out = verify(&hyps, &exr, &scores, &[]);
    refused(&out, "bad hypothesis #4501", "binding (1, 99) names no surface");
    assert_eq!(std::fs::read_to_string(&scores).unwrap(), old, "the earlier output was touched");

    // Duplicate ids would make the output ambiguous.
    let dup = write_scene(&d, "dup.json", &hypotheses(ids(&["a", "b", "a"])).to_string());
    refused(&verify(&dup, &exr, &scores, &[]), "duplicate ids", "hypothesis id \"a\" is used more than once");

    // --out naming an input.
    let hyps = write_scene(&d, "good.json", &hypotheses(ids(&["a"])).to_string());
    for input in [&hyps, &exr] {
        let before = std::fs::read(input).unwrap();
        refused(&verify(&hyps, &exr, input, &[]), "--out is an input", "refusing to overwrite");
        assert_eq!(std::fs::read(input).unwrap(), before);
    }
    assert!(std::fs::read_dir(&d).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().ends_with(".tmp")));
}

#[test]
fn a_killed_verify_leaves_the_earlier_output_whole() {
    let d = dir("verify_kill");
    let exr = sensed(&d);
    let scores = d.join("scores.jsonl");
    let old = "{\"id\": \"earlier results\"}\n";
    std::fs::write(&scores, old).unwrap();
    let many = hypotheses((0..200_000).map(|i| (format!("h{i}"), vec![[1, 1]])));
    let hyps = write_scene(&d, "many.json", &many.to_string());
    for signal in [libc::SIGKILL, libc::SIGINT] {
        let mut command = rangesynth();
        command
            .args(["verify", hyps.to_str().unwrap(), "--scene", exr.to_str().unwrap(), "--out"])
            .arg(&scores)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        // SIGINT's default disposition, as at a terminal: a test run started in the background
        // of a shell without job control inherits SIGINT ignored, and verify then runs on.
        // SAFETY: between fork and exec only async-signal-safe calls: signal(2) is one.
        unsafe {
            command.pre_exec(|| {
                libc::signal(libc::SIGINT, libc::SIG_DFL);
                Ok(())
            });
        }
        // A killed run leaves its temporary file behind; the next run's must be its own.
        let temporary = |d: &Path| -> Vec<PathBuf> {
            std::fs::read_dir(d)
                .unwrap()
                .flatten()
                .map(|e| e.path())
                .filter(|p| {
                    let name = p.file_name().unwrap().to_string_lossy().into_owned();
                    name.starts_with(".scores.jsonl.") && name.ends_with(".tmp")
                })
                .collect()
        };
        temporary(&d).iter().for_each(|p| std::fs::remove_file(p).unwrap());
        let mut child = command.spawn().unwrap();
        // Killed once it has written part of its output (its temporary file beside the target
        // holds bytes): the kill then lands mid-write. The wait's limit is a hang guard only.
        let start = Instant::now();
        while !temporary(&d).iter().any(|p| std::fs::metadata(p).is_ok_and(|m| m.len() > 0)) {
            if let Some(status) = child.try_wait().unwrap() {
                let mut stderr = String::new();
                child.stderr.take().map(|mut e| e.read_to_string(&mut stderr));
                panic!("verify ended ({status:?}) before it wrote any output: {stderr}");
            }
            assert!(start.elapsed() < Duration::from_secs(300), "verify wrote no output in 300 s (a hang)");
            std::thread::sleep(Duration::from_millis(10));
        }
        // SAFETY: signalling our own child.
        assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
        let (status, stderr) = finish_within(child, Duration::from_secs(30), "killed verify");
        assert_eq!(status.signal(), Some(signal), "verify ended before the signal: {stderr}");
        let now = std::fs::read_to_string(&scores).unwrap();
        assert!(now == old, "signal {signal} replaced the output with {} bytes", now.len());
    }
}

// 6. render's output.
#[test]
fn concurrent_renders_into_one_directory_each_leave_a_whole_set() {
    let d = dir("render_concurrent");
    let out = d.join("out");
    let scenes = [(32, 24), (24, 32)].map(|(w, h)| {
        let sensor =
            SENSOR.replace("width = 32", &format!("width = {w}")).replace("height = 24", &format!("height = {h}"));
        write_scene(&d, &format!("{w}x{h}.toml"), &format!("{sensor}[[object]]\nmodel = \"builtin:box\"\n"))
    });
    for round in 0..6 {
        let children: Vec<Child> = scenes
            .iter()
            .map(|s| {
                rangesynth()
                    .args(["render", s.to_str().unwrap(), "--out", out.to_str().unwrap()])
                    .stdout(Stdio::null())
                    .stderr(Stdio::piped())
                    .spawn()
                    .unwrap()
            })
            .collect();
        for child in children {
            let (status, stderr) = finish_within(child, Duration::from_secs(120), "render");
            assert!(status.success(), "{stderr}");
        }
        // Every file of the directory comes from the same render.
        let range = read_range_image(&out.join("range.exr"), &Ledger::default()).unwrap();
        let (w, h, _) = rangesynth::io::read_label_image(&out.join("label_unshadowed.exr"), &Ledger::default())
            .unwrap_or_else(|e| panic!("round {round}: {e}"));
        assert_eq!((range.width, range.height), (w, h), "round {round}: mixed EXRs");
        for png in ["range.png", "label.png", "label_unshadowed.png"] {
            let decoder = png::Decoder::new(std::fs::File::open(out.join(png)).unwrap());
            let info = decoder.read_info().unwrap();
            assert_eq!((info.info().width, info.info().height), (w, h), "round {round}: {png} from the other render");
        }
    }
}

#[test]
fn a_render_that_fails_partway_leaves_the_previous_set() {
    let d = dir("render_fail");
    let out = d.join("out");
    let first = write_scene(&d, "first.toml", &format!("{SENSOR}[[object]]\nmodel = \"builtin:box\"\n"));
    assert!(run(&["render", first.to_str().unwrap(), "--out", out.to_str().unwrap()]).status.success());
    let before: Vec<Vec<u8>> =
        ["range.exr", "labels.json", "range.png"].iter().map(|f| std::fs::read(out.join(f)).unwrap()).collect();
    // A directory where a preview must go makes the write fail after the EXRs.
    std::fs::remove_file(out.join("label.png")).unwrap();
    std::fs::create_dir(out.join("label.png")).unwrap();
    let second = write_scene(&d, "second.toml", &format!("{SENSOR}[[object]]\nmodel = \"builtin:step\"\n"));
    let result = run(&["render", second.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    refused(&result, "render onto a directory", "label.png");
    let after: Vec<Vec<u8>> =
        ["range.exr", "labels.json", "range.png"].iter().map(|f| std::fs::read(out.join(f)).unwrap()).collect();
    assert!(before == after, "the failed render replaced some of the previous files");
    // And the scene file is never an output.
    let clash = write_scene(&out, "labels.json", &format!("{SENSOR}[[object]]\nmodel = \"builtin:box\"\n"));
    refused(
        &run(&["render", clash.to_str().unwrap(), "--out", out.to_str().unwrap()]),
        "scene in DIR",
        "refusing to overwrite",
    );
}

// 7. Silently wrong.
#[test]
fn a_sensor_that_disagrees_with_the_sensed_header_is_refused_unless_overridden() {
    let d = dir("sensor_mismatch");
    let exr = sensed(&d);
    let mut body = hypotheses([("a".to_string(), vec![[1, 1]])]);
    body["sensor"] = serde_json::json!({"kind": "orthographic", "width": 32, "height": 24, "pitch": [0.2, 0.1],
                                        "origin": [-1.5, 1.1], "theta_deg": 30.0});
    let hyps = write_scene(&d, "h.json", &body.to_string());
    let e = refused(
        &verify(&hyps, &exr, &d.join("s.jsonl"), &[]),
        "pitch mismatch",
        "pitch = [0.2, 0.1] (header: [0.1, 0.1])",
    );
    assert!(!e.contains("origin"), "{e}");
    // Overridden, the file's sensor is the one rendered with: columns twice as wide show the
    // box in half as many pixels as the header's sensor does.
    let box_pixels = |hyps: &Path, flags: &[&str]| -> u64 {
        let out = verify(hyps, &exr, &d.join("s.jsonl"), flags);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let line = std::fs::read_to_string(d.join("s.jsonl")).unwrap();
        let record: serde_json::Value = serde_json::from_str(line.lines().next().unwrap()).unwrap();
        record["counts"]["surface_population"].as_array().unwrap().iter().map(|n| n.as_u64().unwrap()).sum()
    };
    let overridden = box_pixels(&hyps, &["--override-sensor"]);
    let header =
        box_pixels(&write_scene(&d, "plain.json", &hypotheses([("a".to_string(), vec![[1, 1]])]).to_string()), &[]);
    assert!(header > 50, "the box shows at the header's pitch: {header} pixels");
    let ratio = overridden as f64 / header as f64;
    assert!((0.4..=0.6).contains(&ratio), "{overridden} pixels at pitch 0.2, {header} at 0.1");
}

#[test]
fn toml_arrays_of_the_wrong_length_are_refused_as_json_refuses_them() {
    let object = format!("[[object]]\nmodel = \"builtin:box\"\npose = {IDENTITY}\n");
    let cases = [
        (
            "3-value pitch",
            SENSOR.replace("pitch = [0.1, 0.1]", "pitch = [0.1, 0.1, 0.1]") + &object,
            "exactly 2 values",
        ),
        ("1-value origin", SENSOR.replace("origin = [-1.5, 1.1]", "origin = [-1.5]") + &object, "exactly 2 values"),
        ("5-number row", SENSOR.to_string() + &object.replace("[1,0,0,0],", "[1,0,0,0,7],"), "exactly 4 values, not 5"),
        (
            "5 rows",
            SENSOR.to_string() + &object.replace("[0,0,0,1]]", "[0,0,0,1],[0,0,0,1]]"),
            "exactly 4 values, not 5",
        ),
    ];
    for (what, body, expected) in cases {
        let e = Scene::from_toml(&body, Path::new("."), &Ledger::default()).unwrap_err().to_string();
        assert!(e.contains(expected), "{what}: {e}");
    }
}

#[test]
fn obj_groups_are_numbered_in_file_order_and_trailing_comments_are_comments() {
    let d = dir("obj");
    let path = d.join("groups.obj");
    std::fs::write(&path, "v 0 1 0 # apex\nv 0 0 0\nv 1 0 0\nv 1 1 0\ng empty\ng second\nf 1 2 3\ng third\nf 2 3 4\n")
        .unwrap();
    let mesh = load_obj(&path, &Ledger::default()).unwrap();
    assert_eq!(mesh.surface_names, ["empty", "second", "third"]);
    assert_eq!(mesh.triangle_surfaces, [2, 3]);
    assert_eq!(mesh.positions[0], [0.0, 1.0, 0.0]);
}

#[test]
fn a_closed_stdout_ends_render_quietly_with_its_files_whole() {
    let d = dir("pipe");
    let scene = write_scene(&d, "s.toml", &format!("{SENSOR}[[object]]\nmodel = \"builtin:box\"\n"));
    let mut child = rangesynth()
        .args(["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader is gone before the first line, as `| head -0` would be
    let (status, stderr) = finish_within(child, Duration::from_secs(60), "render | head");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(status.signal(), Some(libc::SIGPIPE), "{stderr}");
    assert!(read_range_image(&d.join("out/range.exr"), &Ledger::default()).is_ok());
}

// 8. The summary's cost is linear in pixels + labels: checked for correctness here (the
// populations of many labels), its cost is measured in the note.
#[test]
fn the_summary_counts_each_surface_of_a_many_group_model() {
    let d = dir("many_groups");
    let n = 4096;
    let mut obj = String::new();
    for k in 0..n {
        // Strips 1/n wide across x ∈ [−1.5, 1.5], each its own group.
        let (x0, x1) = (-1.5 + 3.0 * k as f64 / n as f64, -1.5 + 3.0 * (k + 1) as f64 / n as f64);
        obj += &format!("v {x0} -1 0\nv {x1} -1 0\nv {x1} 1 0\nv {x0} 1 0\ng s{k}\nf -4 -3 -2\nf -4 -2 -1\n");
    }
    std::fs::write(d.join("strips.obj"), obj).unwrap();
    let scene = write_scene(&d, "s.toml", &format!("{SENSOR}[[object]]\nmodel = \"strips.obj\"\n"));
    let out = run(&["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let range = read_range_image(&d.join("out/range.exr"), &Ledger::default()).unwrap();
    let mut expected = std::collections::BTreeMap::new();
    for &l in range.label.iter().filter(|&&l| l != 0) {
        *expected.entry(l).or_insert(0u64) += 1;
    }
    let listed: std::collections::BTreeMap<u32, u64> = stdout
        .lines()
        .filter(|l| l.contains("strips.obj"))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f[0].parse().unwrap(), f[f.len() - 2].parse().unwrap())
        })
        .collect();
    assert_eq!(listed, expected);
}

// 5. Poses so far away that the depth range overflows.
#[test]
fn an_object_posed_beyond_any_depth_range_is_refused_with_a_message() {
    let d = dir("overflow");
    let far = "[[1,0,0,0],[0,1,0,0],[0,0,1,1e308],[0,0,0,1]]";
    let body = format!(
        "{SENSOR}[[object]]\nmodel = \"builtin:box\"\npose = {far}\n[[object]]\nmodel = \"builtin:box\"\npose = [[1,0,0,0],[0,1,0,0],[0,0,1,-1e308],[0,0,0,1]]\n"
    );
    let scene = write_scene(&d, "far.toml", &body);
    let out = run(&["render", scene.to_str().unwrap(), "--out", d.join("out").to_str().unwrap()]);
    refused(&out, "a depth range that overflows", "not finite");
}
