//! `rangesynth bop`'s throughput: rows per second of a 100-row results file against one
//! 640×480 image of a BOP-format dataset written to a temporary directory, for a 12-triangle
//! box and a 3,990-triangle sphere (each 100 mm across, 1 m from the camera), scored under a
//! camera with a projector 75 mm beside it, its images cast on the CPU (`--shadow-mode exact`)
//! and drawn on the device (`--shadow-mode label`, the image's rows together). The baseline,
//! measured in the same run, scores the same rows under the camera alone (no witness to test),
//! so the ratio is what the rig's shadows cost. Every row has the image's ground truth, so each
//! scores VSD twice as well.
//!
//! Run: `cargo run --release --example bench_bop`.

use glam::{DMat4, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangesynth::bop::{BopScorer, BopSettings, Dataset, ResultRow};
use rangesynth::exact::{render_rig, ExactObject};
use rangesynth::gpu::ContextOptions;
use rangesynth::io::write_depth_png;
use rangesynth::limits::Ledger;
use rangesynth::sensor::{Intrinsics, Pinhole, PixelRect, Sensor, View, Witness, WitnessGeometry};
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::Renderer;
use std::path::Path;
use std::time::Instant;

const ROWS: usize = 100;

fn camera() -> Intrinsics {
    Intrinsics { width: 640, height: 480, fx: 572.4, fy: 573.6, cx: 325.3, cy: 242.0 }
}

fn rig(projector: bool) -> Sensor {
    let witnesses = match projector {
        true => vec![Witness {
            name: "projector".into(),
            geometry: WitnessGeometry::Pinhole {
                pose: DMat4::from_translation(DVec3::new(75.0, 0.0, 0.0)),
                intrinsics: camera(),
            },
        }],
        false => vec![],
    };
    Sensor { reference: View::Pinhole(Pinhole { intrinsics: camera(), near: 0.0, far: f64::INFINITY }), witnesses }
}

/// A box 100 mm a side, or a UV sphere of radius 50 mm of 3,990 triangles (57 segments, 36
/// rings), as ASCII PLY.
fn model_ply(sphere: bool) -> String {
    let (mut vertices, mut faces): (Vec<[f64; 3]>, Vec<[usize; 3]>) = (Vec::new(), Vec::new());
    if sphere {
        let (rings, segments) = (36, 57);
        vertices.push([0.0, 0.0, 50.0]);
        for i in 1..rings {
            let polar = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..segments {
                let azimuth = std::f64::consts::TAU * j as f64 / segments as f64;
                vertices.push([
                    50.0 * polar.sin() * azimuth.cos(),
                    50.0 * polar.sin() * azimuth.sin(),
                    50.0 * polar.cos(),
                ]);
            }
        }
        vertices.push([0.0, 0.0, -50.0]);
        let at = |i: usize, j: usize| 1 + (i - 1) * segments + j % segments;
        for j in 0..segments {
            faces.push([0, at(1, j), at(1, j + 1)]);
            for i in 1..rings - 1 {
                faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
            faces.push([vertices.len() - 1, at(rings - 1, j + 1), at(rings - 1, j)]);
        }
    } else {
        vertices = (0..8)
            .map(|i| {
                [
                    (i & 1) as f64 * 100.0 - 50.0,
                    ((i >> 1) & 1) as f64 * 100.0 - 50.0,
                    ((i >> 2) & 1) as f64 * 100.0 - 50.0,
                ]
            })
            .collect();
        faces = vec![
            [0, 1, 3],
            [0, 3, 2],
            [4, 6, 7],
            [4, 7, 5],
            [0, 2, 6],
            [0, 6, 4],
            [1, 5, 7],
            [1, 7, 3],
            [0, 4, 5],
            [0, 5, 1],
            [2, 3, 7],
            [2, 7, 6],
        ];
    }
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        vertices.len(),
        faces.len()
    );
    vertices.iter().for_each(|[x, y, z]| ply += &format!("{x} {y} {z}\n"));
    faces.iter().for_each(|[a, b, c]| ply += &format!("3 {a} {b} {c}\n"));
    ply
}

fn bop_rotation_and_translation(pose: &DMat4) -> (String, String) {
    let r = glam::DMat3::from_mat4(*pose).transpose().to_cols_array();
    let t = pose.w_axis.truncate();
    (r.map(|v| v.to_string()).join(" "), format!("{} {} {}", t.x, t.y, t.z))
}

/// Writes the dataset: the model, the camera, the ground truth and its depth image.
fn write_dataset(root: &Path, sphere: bool, truth: DMat4) -> anyhow::Result<()> {
    let models = root.join("models");
    std::fs::create_dir_all(&models)?;
    std::fs::write(models.join("models_info.json"), r#"{"1": {"diameter": 100.0}}"#)?;
    std::fs::write(models.join("obj_000001.ply"), model_ply(sphere))?;
    let scene = root.join("test/000001");
    std::fs::create_dir_all(scene.join("depth"))?;
    let k = camera();
    std::fs::write(
        scene.join("scene_camera.json"),
        format!(r#"{{"1": {{"cam_K": [{}, 0, {}, 0, {}, {}, 0, 0, 1], "depth_scale": 0.1}}}}"#, k.fx, k.cx, k.fy, k.cy),
    )?;
    let (r, t) = bop_rotation_and_translation(&truth);
    let list = |text: String| text.split(' ').collect::<Vec<_>>().join(", ");
    std::fs::write(
        scene.join("scene_gt.json"),
        format!(r#"{{"1": [{{"cam_R_m2c": [{}], "cam_t_m2c": [{}], "obj_id": 1}}]}}"#, list(r), list(t)),
    )?;
    let mesh = rangesynth::scene::load_model_as(
        models.join("obj_000001.ply").to_str().unwrap_or_default(),
        Path::new("."),
        &Ledger::default(),
        Default::default(),
        1.0,
    )?;
    let full = PixelRect { col: 0, row: 0, width: k.width, height: k.height };
    let image = render_rig(
        &rig(true),
        &[ExactObject { mesh: &mesh, pose: truth, label_base: 0, solidity: mesh.solidity() }],
        ShadowMode::Exact,
        full,
    )?;
    let values: Vec<u16> =
        image.shadowed.iter().zip(&image.z).map(|(&l, &z)| if l != 0 { (z / 0.1).round() as u16 } else { 0 }).collect();
    write_depth_png(&scene.join("depth/000001.png"), k.width, k.height, &values)?;
    Ok(())
}

/// Seconds to score the rows under the rig, its images made in shadow mode `mode` (`label`
/// on `renderer`'s device).
fn time_rows(
    root: &Path,
    projector: bool,
    rows: &[ResultRow],
    mode: ShadowMode,
    renderer: &Renderer,
) -> anyhow::Result<f64> {
    let ledger = Ledger::default();
    let dataset = Dataset::open(root, "test", &ledger)?;
    let settings = BopSettings { rig: rig(projector), delta: 15.0, shadow: ShadowSettings::of(mode) };
    let mut scorer = BopScorer::new(&dataset, &settings, Some(renderer), &ledger)?;
    let start = Instant::now();
    scorer.score_rows(rows)?;
    Ok(start.elapsed().as_secs_f64())
}

fn main() -> anyhow::Result<()> {
    let renderer = Renderer::new(&ContextOptions::from_env())?;
    let device = renderer.context().device_name().to_string();
    println!(
        "rows/s scoring {ROWS} rows against one 640×480 image ({} CPU threads; {device})",
        rayon::current_num_threads()
    );
    println!("| model | triangles | mode | camera alone (rows/s) | camera + projector (rows/s) | ratio |");
    println!("|---|---|---|---|---|---|");
    let truth = DMat4::from_translation(DVec3::new(10.0, -5.0, 1000.0)) * DMat4::from_rotation_x(0.4);
    for (name, sphere, triangles) in [("box", false, 12), ("sphere", true, 3990)] {
        let dir = tempfile::tempdir()?;
        write_dataset(dir.path(), sphere, truth)?;
        let mut rng = ChaCha8Rng::seed_from_u64(40);
        let rows: Vec<ResultRow> = (0..ROWS)
            .map(|_| {
                let shift =
                    DVec3::new(rng.gen_range(-10.0..10.0), rng.gen_range(-10.0..10.0), rng.gen_range(-30.0..30.0));
                let pose = DMat4::from_translation(shift) * truth * DMat4::from_rotation_z(rng.gen_range(-0.3..0.3));
                let (r, t) = bop_rotation_and_translation(&pose);
                let fields = vec!["1".into(), "1".into(), "1".into(), "1".into(), r, t, "0".into()];
                ResultRow { scene_id: 1, im_id: 1, obj_id: 1, pose, fields }
            })
            .collect();
        for (mode, side) in [(ShadowMode::Exact, "exact (CPU)"), (ShadowMode::Label, "label (GPU)")] {
            let alone = time_rows(dir.path(), false, &rows, mode, &renderer)?;
            let with_projector = time_rows(dir.path(), true, &rows, mode, &renderer)?;
            let rate = |seconds: f64| ROWS as f64 / seconds;
            println!(
                "| {name} | {triangles} | {side} | {:.1} | {:.1} | {:.2} |",
                rate(alone),
                rate(with_projector),
                rate(with_projector) / rate(alone)
            );
        }
    }
    Ok(())
}
