//! `rangesynth accuracy` end to end (validation on): the quick sweep with a scene of the
//! user's, its CSV parsed and checked against itself and, on the user's scene, every
//! setting's row against the tests' independent CPU reference; its plot decoded, and an
//! output path that names an input refused.

mod common;

use common::cli::{fresh_dir, rangesynth_command};
use common::paired;
use common::reference::reference_render;
use rangesynth::limits::Ledger;
use rangesynth::shadow::{Neighbourhood, ShadowMode, ShadowSettings};
use rangesynth::Scene;
use std::collections::HashMap;
use std::path::PathBuf;

const HEADER: &str = "setting,scene,pixels,wrong_pixels,wrong_pct,max_abs_dz,score_abs_error,ms_per_pose";

/// A box on a table, off the pixel lattice, at θ = 45°: its shadow on the table is what the
/// `none` setting gets wrong.
const SCENE: &str = r#"
[sensor]
kind = "orthographic"
width = 64
height = 48
pitch = [0.05, 0.05]
origin = [-1.5731, 1.1913]
theta_deg = 45.0

[[object]]
model = "builtin:box"
pose = [[1,0,0,0.0123],[0,1,0,0.0071],[0,0,1,0],[0,0,0,1]]

[[object]]
model = "builtin:plane:4"
"#;

fn dir(name: &str) -> PathBuf {
    fresh_dir("accuracy", name)
}

fn accuracy(args: &[&str]) -> std::process::Output {
    rangesynth_command().arg("accuracy").args(args).output().expect("the binary runs")
}

struct CsvRow {
    pixels: u64,
    wrong_pixels: u64,
    wrong_pct: f64,
    max_abs_dz: f64,
    score_abs_error: f64,
    ms_per_pose: f64,
}

#[test]
fn the_quick_sweep_writes_a_csv_that_parses_and_a_plot() {
    let d = dir("quick");
    let scene_path = d.join("box on table.toml");
    std::fs::write(&scene_path, SCENE).unwrap();
    let out_dir = d.join("out");
    let out = accuracy(&["--quick", "--out", out_dir.to_str().unwrap(), "--scene", scene_path.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));

    let csv = std::fs::read_to_string(out_dir.join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some(HEADER));
    let mut rows: HashMap<(String, String), CsvRow> = HashMap::new();
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), 8, "{line}");
        let number = |i: usize| fields[i].parse::<f64>().unwrap_or_else(|e| panic!("{line}: field {i}: {e}"));
        let row = CsvRow {
            pixels: fields[2].parse().unwrap(),
            wrong_pixels: fields[3].parse().unwrap(),
            wrong_pct: number(4),
            max_abs_dz: number(5),
            score_abs_error: number(6),
            ms_per_pose: number(7),
        };
        assert!(row.wrong_pixels <= row.pixels, "{line}");
        let pct = 100.0 * row.wrong_pixels as f64 / row.pixels as f64;
        assert!((row.wrong_pct - pct).abs() <= 1e-4, "{line}");
        assert!(row.max_abs_dz >= 0.0 && row.score_abs_error >= 0.0 && row.ms_per_pose > 0.0, "{line}");
        assert!(rows.insert((fields[0].to_string(), fields[1].to_string()), row).is_none(), "{line} twice");
    }

    let scenes = ["box", "step", "cylinder", "sphere", "cluttered", "dense part", "box on table"];
    for setting in ["none", "label x1", "label x2", "depth x1", "depth x2", "label 2x2 x1", "exact"] {
        for scene in scenes {
            let row = rows.get(&(setting.to_string(), scene.to_string()));
            let row = row.unwrap_or_else(|| panic!("no row for {setting} on {scene}"));
            if setting == "exact" {
                assert_eq!((row.wrong_pixels, row.score_abs_error), (0, 0.0), "exact on {scene}");
            }
        }
    }
    // Tessellation settings apply to scenes with curved built-ins only.
    for scene in scenes {
        let curved = !matches!(scene, "box" | "step" | "box on table");
        assert_eq!(rows.contains_key(&("depth x1 N=16".to_string(), scene.to_string())), curved, "{scene}");
    }
    // Depth shadows are exact away from edges here; no shadows at all miss the box's shadow,
    // which the independent reference counts.
    let scene = Scene::from_toml(SCENE, &d, &Ledger::default()).unwrap();
    let reference = reference_render(&scene);
    let shadowed = reference.label.iter().zip(&reference.occluded).filter(|(&l, &o)| l != 0 && o).count() as u64;
    assert!(shadowed > 50, "the box casts a shadow: {shadowed} pixels");
    let row = |setting: &str| &rows[&(setting.to_string(), "box on table".to_string())];
    assert_eq!(row("none").wrong_pixels, shadowed);
    assert_eq!(row("depth x1").wrong_pixels, 0);
    // Every setting's wrong pixels are its pixels that differ from exact shadowing as the
    // reference casts it (exact mode's row included), not from exact mode's image.
    let expected = reference.label_shadowed();
    let of = ShadowSettings::of;
    let columns = |mode, columns| ShadowSettings { columns, ..of(mode) };
    let square = ShadowSettings { neighbourhood: Neighbourhood::Square2, ..of(ShadowMode::Label) };
    for (setting, shadow) in [
        ("none", of(ShadowMode::None)),
        ("label x1", of(ShadowMode::Label)),
        ("label x2", columns(ShadowMode::Label, 2)),
        ("depth x1", of(ShadowMode::Depth)),
        ("depth x2", columns(ShadowMode::Depth, 2)),
        ("label 2x2 x1", square),
        ("exact", of(ShadowMode::Exact)),
    ] {
        let out = common::render(&Scene { shadow, ..scene.clone() });
        let wrong = paired(&out.label, &expected).filter(|(a, b)| a != b).count() as u64;
        assert_eq!(row(setting).wrong_pixels, wrong, "{setting} on the box on a table");
    }
    let step = &rows[&("none".to_string(), "step".to_string())];
    assert!(step.score_abs_error > 0.0, "ignoring the step's shadow on itself changes its correct score");
    assert!(stdout.contains("box on table") && stdout.contains("ms/pose"), "the table is printed:\n{stdout}");

    let decoder = png::Decoder::new(std::fs::File::open(out_dir.join("accuracy.png")).unwrap());
    let reader = decoder.read_info().expect("the plot is a PNG");
    assert_eq!((reader.info().width, reader.info().height), (1100, 750));
}

#[test]
fn a_scene_without_objects_is_refused() {
    let d = dir("empty");
    let scene_path = d.join("empty.toml");
    std::fs::write(&scene_path, &SCENE[..SCENE.find("[[object]]").unwrap()]).unwrap();
    let out = accuracy(&["--quick", "--out", d.join("out").to_str().unwrap(), "--scene", scene_path.to_str().unwrap()]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("empty.toml") && stderr.contains("first object"), "{stderr}");
    assert!(!d.join("out").exists(), "nothing is written");
}

#[test]
fn an_output_that_names_an_input_is_refused() {
    let d = dir("refused");
    let scene_path = d.join("accuracy.csv");
    std::fs::write(&scene_path, SCENE).unwrap();
    let out = accuracy(&["--quick", "--out", d.to_str().unwrap(), "--scene", scene_path.to_str().unwrap()]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("accuracy.csv"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&scene_path).unwrap(), SCENE, "the input is left whole");
}
