//! rangesynth's side of the comparison with a CPU ray tracer (tools/bench_embree.py, which runs
//! this and Embree in the same run). It measures `verify`'s cost per hypothesis (render, shadow,
//! score) in shadow modes label, depth and exact, for three workloads: a 12-triangle box at 256²,
//! the ~100k-triangle sphere:320 at 256², and the sphere at 1024². Each model fills much of the
//! paper's scanner's image (θ = 45°). Each batch holds 16 hypotheses, each turned about z and
//! moved by a seeded random amount. It counts the fastest of three batches, a mode at a time in
//! turn. It prints one JSON object a line: workload, mode, ms a hypothesis.
//!
//! `-- --export DIR` also writes each workload's mesh (vertices and triangles), its sensor (the
//! scanner's keys) and the 16 poses to DIR/WORKLOAD.json, so that the ray tracer casts the same
//! rays at the same triangles.
//!
//! Run: `cargo run --release --example bench_exact [-- --export DIR]`; RANGESYNTH_DEVICE picks
//! the device.

use glam::{DMat4, DVec3};
use rand::{Rng, SeedableRng};
use rangesynth::effects::Effects;
use rangesynth::gpu::ContextOptions;
use rangesynth::io::RangeImage;
use rangesynth::scene::{Scene, SceneObject};
use rangesynth::sensor::{Scanner, Sensor};
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, Verifier, VerifySettings};
use rangesynth::Renderer;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// (name, model, image side, extent in model units).
const WORKLOADS: [(&str, &str, u32, f64); 3] = [
    ("box-256", "builtin:box", 256, 1.6),
    ("sphere-256", "builtin:sphere:320", 256, 1.05),
    ("sphere-1024", "builtin:sphere:320", 1024, 1.05),
];
const MODES: [ShadowMode; 3] = [ShadowMode::Label, ShadowMode::Depth, ShadowMode::Exact];
const BATCH: usize = 16;
const ROUNDS: usize = 3;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let export = args.iter().position(|a| a == "--export").map(|i| PathBuf::from(&args[i + 1]));
    let verifier = Verifier::new(Renderer::new(&ContextOptions::from_env())?)?;
    eprintln!("device: {}", verifier.renderer().context().device_name());
    for (name, model_name, side, extent) in WORKLOADS {
        let scanner = Scanner::square(side, extent, 45.0);
        let sensor = Sensor::from(scanner);
        let model = verifier.model(model_name, Path::new("."))?;
        let (centre, _) = model.mesh.bounding_sphere();
        let at = DMat4::from_translation(DVec3::new(-centre.x, -centre.y, 0.0));
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(40);
        let poses: Vec<DMat4> = (0..BATCH)
            .map(|_| {
                let shift = DVec3::new(rng.gen_range(-0.05..0.05), rng.gen_range(-0.05..0.05), 0.0) * extent;
                DMat4::from_translation(shift) * DMat4::from_rotation_z(rng.gen_range(0.0..std::f64::consts::TAU)) * at
            })
            .collect();
        if let Some(dir) = &export {
            write_workload(&dir.join(format!("{name}.json")), &model.mesh, &scanner, &poses)?;
        }
        let hypotheses: Vec<Hypothesis> = (0..)
            .zip(&poses)
            .map(|(i, &pose)| Hypothesis { id: format!("h{i}"), model: model.clone(), pose, bindings: vec![(1, 1)] })
            .collect();
        let mut fastest = [f64::INFINITY; MODES.len()];
        let mut inputs = Vec::new();
        for mode in MODES {
            let settings = VerifySettings {
                sensor: sensor.clone(),
                shadow: ShadowSettings::of(mode),
                effects: Effects::default(),
                tolerance: 0.1,
                compare_shadow: false,
                chunk_size: BATCH,
            };
            let object =
                SceneObject { model_ref: model_name.into(), mesh: model.mesh.clone(), pose: at, reflectivity: None };
            let scene = Scene {
                sensor: sensor.clone(),
                shadow: settings.shadow,
                effects: Effects::default(),
                objects: vec![object],
            };
            let sensed = SensedImage::new(&RangeImage::from(&verifier.renderer().render(&scene)?), &sensor)?;
            // Warm up (pipelines; shader compilation in software drivers).
            verifier.verify(&sensed, &settings, &hypotheses[..1], &mut |_| {})?;
            inputs.push((settings, sensed));
        }
        for _ in 0..ROUNDS {
            for ((settings, sensed), fastest) in inputs.iter().zip(&mut fastest) {
                let start = Instant::now();
                verifier.verify(sensed, settings, &hypotheses, &mut |_| {})?;
                *fastest = fastest.min(start.elapsed().as_secs_f64());
            }
        }
        for (mode, seconds) in MODES.iter().zip(fastest) {
            let ms = seconds * 1e3 / BATCH as f64;
            println!("{}", json!({ "workload": name, "mode": mode.as_str(), "ms": ms }));
        }
    }
    Ok(())
}

/// The workload for the ray tracer: the mesh, the scanner, the poses (row-major 4×4s).
fn write_workload(
    path: &Path,
    mesh: &rangesynth::mesh::Mesh,
    scanner: &Scanner,
    poses: &[DMat4],
) -> anyhow::Result<()> {
    let vertices: Vec<[f64; 3]> = (0..mesh.positions.len() as u32).map(|v| mesh.vertex(v).to_array()).collect();
    let rows = |m: &DMat4| m.transpose().to_cols_array();
    let workload = json!({
        "vertices": vertices,
        "triangles": mesh.triangles,
        "sensor": {
            "width": scanner.width, "height": scanner.height, "pitch": scanner.pitch,
            "origin": scanner.origin, "theta_deg": scanner.theta_deg,
        },
        "poses": poses.iter().map(rows).collect::<Vec<_>>(),
    });
    std::fs::write(path, serde_json::to_vec(&workload)?)?;
    Ok(())
}
