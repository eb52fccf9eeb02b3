//! The Rust side of `tools/bench_python.py`, which measures what a call through Python costs
//! over the same call through the library. It takes a JSON file of poses (each 16 numbers,
//! row-major). It renders the sensed image the Python side renders (docs/example/sensed.toml)
//! and prepares it once, and warms up. Then, for each line read from its input (a number n), it
//! verifies the batch's first n `builtin:box` poses in one `Verifier::verify` call and prints
//! the call's seconds on a line, so that the Python side's calls and its take turns one by one. The
//! settings match the Python side's call: depth-mode shadows, no effects, tolerance 0.1,
//! bindings (1, 1) and (2, 1), the default rasterizer and device.

use glam::DMat4;
use rangesynth::gpu::ContextOptions;
use rangesynth::io::RangeImage;
use rangesynth::limits::Ledger;
use rangesynth::scene::Scene;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, Verifier, VerifySettings, DEFAULT_TOLERANCE};
use rangesynth::Renderer;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

const SENSED: &str = include_str!("../docs/example/sensed.toml");

fn main() -> anyhow::Result<()> {
    let Some(poses) = std::env::args().nth(1).map(PathBuf::from) else {
        anyhow::bail!("usage: bench_python_baseline POSES.json (then one line per call)");
    };
    let rows: Vec<[f64; 16]> = serde_json::from_str(&std::fs::read_to_string(&poses)?)?;
    let verifier = Verifier::new(Renderer::new(&ContextOptions::from_env())?)?;
    let scene = Scene::from_toml(SENSED, Path::new("."), &Ledger::default())?;
    let image = RangeImage::from(&verifier.renderer().render(&scene)?);
    let sensed = SensedImage::new(&image, &scene.sensor)?;
    let model = verifier.model("builtin:box", Path::new("."))?;
    let hypotheses: Vec<Hypothesis> = rows
        .iter()
        .enumerate()
        .map(|(i, row)| Hypothesis {
            id: i.to_string(),
            model: model.clone(),
            pose: DMat4::from_cols_array(row).transpose(),
            bindings: vec![(1, 1), (2, 1)],
        })
        .collect();
    let settings = VerifySettings {
        sensor: scene.sensor.clone(),
        shadow: ShadowSettings::of(ShadowMode::Depth),
        effects: Default::default(),
        tolerance: DEFAULT_TOLERANCE,
        compare_shadow: false,
        chunk_size: 1024,
    };
    // Warm up (pipelines, shader compilation in software drivers), as the Python side does.
    verifier.verify(&sensed, &settings, &hypotheses[..1], &mut |_| {})?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "ready")?;
    out.flush()?;
    for line in std::io::stdin().lock().lines() {
        let count: usize = line?.trim().parse()?;
        let start = Instant::now();
        verifier.verify(&sensed, &settings, &hypotheses[..count.min(hypotheses.len())], &mut |_| {})?;
        writeln!(out, "{}", start.elapsed().as_secs_f64())?;
        out.flush()?;
    }
    Ok(())
}
