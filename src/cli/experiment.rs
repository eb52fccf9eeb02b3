//! `rangesynth experiment`: the paper's experiment on a synthetic benchmark (src/experiment/),
//! with a progress bar; prints the table and where its files went.

use super::console::{report, report_text};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rangesynth::experiment::{run_experiment, ExperimentConfig};
use rangesynth::gpu::ContextOptions;
use rangesynth::limits::Ledger;
use rangesynth::render::Raster;
use rangesynth::verify::Verifier;
use rangesynth::Renderer;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(clap::Args)]
pub struct ExperimentArgs {
    /// Write models/, views/<view>/ (range.exr, hypotheses.json, scores.jsonl), table.md,
    /// summary.json and scores.png into this directory, which is replaced whole (an earlier
    /// run's files do not stay beside the new ones; other files in it are kept).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Seven models in one view each at 160² (a few seconds on lavapipe) instead of fourteen
    /// models in five views each at 256².
    #[arg(long)]
    quick: bool,
    /// Seed of the poses, the hypotheses and the sensor noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn run(options: &ContextOptions, ledger: Arc<Ledger>, raster: Raster, args: &ExperimentArgs) -> Result<()> {
    let config = if args.quick { ExperimentConfig::quick(args.seed) } else { ExperimentConfig::full(args.seed) };
    let renderer = Renderer::new(options).context("starting Vulkan")?.with_ledger(ledger).with_raster(raster);
    let verifier = Verifier::new(renderer).context("starting Vulkan")?;
    let bar = match std::io::stderr().is_terminal() {
        true => ProgressBar::new((config.models * config.views_per_model) as u64),
        false => ProgressBar::hidden(),
    };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} views, eta {eta}").expect("valid template"));
    let output = run_experiment(&verifier, &config, &args.out, &mut |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    report!("device: {}", verifier.renderer().context().device_name())?;
    report_text(std::fs::read_to_string(args.out.join("table.md")).context("reading table.md back")?)?;
    let (correct, incorrect) = (output.summary.correct.n, output.summary.incorrect.n);
    report!(
        "\n{} views, {correct} correct and {incorrect} incorrect hypotheses; wrote {} (table.md, summary.json, \
         scores.png, models/, views/)",
        output.views,
        args.out.display()
    )?;
    super::check_device(verifier.renderer())
}
