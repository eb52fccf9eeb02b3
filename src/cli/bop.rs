//! `rangesynth bop DATASET --results FILE.csv --rig RIG.toml --out SCORES.csv`: a BOP results
//! file's rows scored against the dataset's depth images under the rig (src/bop/,
//! docs/bop.md), written as the input's columns followed by the scores', in input order,
//! atomically.

use super::console::report;
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rangesynth::bop::{parse_results, same_image, BopScorer, BopSettings, Dataset, RESULTS_HEADER, SCORE_COLUMNS};
use rangesynth::gpu::ContextOptions;
use rangesynth::io::{parse_json, parse_toml, read_input_text, refuse_overwriting_inputs, PendingFile};
use rangesynth::limits::Ledger;
use rangesynth::render::Raster;
use rangesynth::sensor::Sensor;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::Renderer;
use serde::Deserialize;
use std::collections::HashSet;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Args)]
pub struct BopArgs {
    /// The dataset's directory (models/, and a directory per split).
    dataset: PathBuf,
    /// The results file: scene_id,im_id,obj_id,score,R,t,time.
    #[arg(long)]
    results: PathBuf,
    /// The rig of the sensor that took the images: a scene file whose [sensor] has a pinhole
    /// reference view (its size and intrinsics are each image's) and the witnesses.
    #[arg(long)]
    rig: PathBuf,
    /// Where the scores go: the results' columns, then
    /// inlier,violation,explained_holes,depth_score,vsd,vsd_recall,vsd_shadowed,vsd_shadowed_recall.
    #[arg(long)]
    out: PathBuf,
    /// The split whose scenes the rows name.
    #[arg(long, default_value = "test")]
    split: String,
    /// Score only the (scene, image, object) triples a BOP targets file lists
    /// (test_targets_bop19.json); other rows are left out of the scores.
    #[arg(long)]
    targets: Option<PathBuf>,
    /// δ, mm: the depth-only scores' tolerance and VSD's visibility tolerance.
    #[arg(long, default_value_t = 15.0)]
    delta: f64,
    /// Multiplies the rig's lengths into the dataset's millimetres: 1000 for a rig in metres,
    /// as those in rigs/ are; 1 for a rig written in millimetres.
    #[arg(long, default_value_t = 1000.0)]
    rig_scale: f64,
    /// How the rig's images are made: exact (f64 rays on the CPU), depth (the depth test's
    /// walk toward each witness) or label (the paper's label test), the rows of an image drawn
    /// together on the GPU, or none (no shadows, on the GPU).
    #[arg(long, default_value = "exact", value_parser = ["exact", "depth", "label", "none"])]
    shadow_mode: String,
}

/// What `rangesynth bop` reads of the rig's file: its `[sensor]` (the rest of a scene file,
/// shadow settings, effects and objects, is not read).
#[derive(Deserialize)]
struct RigFile {
    sensor: Sensor,
}

/// One entry of a BOP targets file.
#[derive(Deserialize)]
struct Target {
    scene_id: u32,
    im_id: u32,
    obj_id: u32,
}

pub fn run(options: &ContextOptions, ledger: Arc<Ledger>, raster: Raster, args: &BopArgs) -> Result<()> {
    if !(args.rig_scale.is_finite() && args.rig_scale > 0.0) {
        anyhow::bail!("--rig-scale {} must be positive and finite", args.rig_scale);
    }
    let dataset = Dataset::open(&args.dataset, &args.split, &ledger)?;
    let rig_text = read_input_text(&args.rig, "rig", &ledger)?;
    let rig: RigFile = parse_toml(&rig_text).with_context(|| format!("rig {}", args.rig.display()))?;
    let mode = match args.shadow_mode.as_str() {
        "depth" => ShadowMode::Depth,
        "label" => ShadowMode::Label,
        "none" => ShadowMode::None,
        _ => ShadowMode::Exact,
    };
    let settings =
        BopSettings { rig: rig.sensor.scaled(args.rig_scale), delta: args.delta, shadow: ShadowSettings::of(mode) };
    let text = read_input_text(&args.results, "results file", &ledger)?;
    let mut rows = parse_results(&args.results, &text, &ledger)?;
    if let Some(path) = &args.targets {
        let targets: Vec<Target> = parse_json(&read_input_text(path, "targets file", &ledger)?)
            .with_context(|| format!("targets {}", path.display()))?;
        let listed: HashSet<(u32, u32, u32)> = targets.iter().map(|t| (t.scene_id, t.im_id, t.obj_id)).collect();
        rows.retain(|r| listed.contains(&(r.scene_id, r.im_id, r.obj_id)));
    }
    // The GPU, where it draws the rig's images.
    let renderer = match mode {
        ShadowMode::Exact => None,
        _ => Some(Renderer::new(options).context("starting Vulkan")?.with_ledger(ledger.clone()).with_raster(raster)),
    };
    let mut scorer = BopScorer::new(&dataset, &settings, renderer.as_ref(), &ledger)?;
    refuse_overwriting_inputs([args.out.as_path()], &ledger)?;

    let bar = match std::io::stderr().is_terminal() && rows.len() > 1 {
        true => {
            let bar = ProgressBar::new(rows.len() as u64);
            let style = ProgressStyle::with_template("{bar:40} {pos}/{len} rows, {per_sec}, eta {eta}");
            bar.set_style(style.expect("valid template"));
            bar
        }
        false => ProgressBar::hidden(),
    };
    let start = std::time::Instant::now();
    let mut pending = PendingFile::new(&args.out)?.guarding_inputs(&ledger);
    let mut out = csv::Writer::from_writer(pending.file());
    let written = |e: csv::Error| anyhow::anyhow!("writing {}: {e}", args.out.display());
    out.write_record(RESULTS_HEADER.iter().chain(&SCORE_COLUMNS)).map_err(written)?;
    // An image's rows together, as the scorer makes their images (streamed a run at a time).
    for run in rows.chunk_by(same_image) {
        for (row, scores) in run.iter().zip(scorer.score_rows(run)?) {
            out.write_record(row.fields.iter().cloned().chain(scores.cells())).map_err(written)?;
            bar.inc(1);
        }
    }
    out.flush().with_context(|| format!("writing {}", args.out.display()))?;
    drop(out);
    pending.commit()?;
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    report!("scored {} rows in {seconds:.2} s ({:.1} rows/s)", rows.len(), rows.len() as f64 / seconds.max(1e-9))?;
    report!("wrote {}", args.out.display())?;
    match &renderer {
        Some(renderer) => super::check_device(renderer),
        None => Ok(()),
    }
}
