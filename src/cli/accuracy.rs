//! `rangesynth accuracy`: the sweep of src/accuracy/ with a progress bar; writes
//! `DIR/accuracy.csv` and `DIR/accuracy.png` as one set that replaces DIR whole (io/atomic.rs)
//! and prints the table. The rasterizer is
//! one of the sweep's settings, so the global `--raster` does not apply.

use super::console::{report, report_text};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rangesynth::accuracy::{
    self, standard_scenes, sweep_settings, Summary, SweepOptions, SweepScene, SweepVerifiers, Table,
};
use rangesynth::gpu::ContextOptions;
use rangesynth::io::{refuse_overwriting_inputs, StagedSet};
use rangesynth::limits::Ledger;
use rangesynth::render::Raster;
use rangesynth::verify::Verifier;
use rangesynth::Renderer;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(clap::Args)]
pub struct AccuracyArgs {
    /// Write accuracy.csv and accuracy.png into this directory.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// A smaller sweep (128² images, fewer settings and poses) that finishes in a few minutes
    /// on lavapipe.
    #[arg(long)]
    quick: bool,
    /// Also measure this scene file (its effects are left out); may be repeated.
    #[arg(long = "scene", value_name = "FILE")]
    scenes: Vec<PathBuf>,
}

const FILES: [&str; 2] = ["accuracy.csv", "accuracy.png"];

pub fn run(options: &ContextOptions, ledger: Arc<Ledger>, args: &AccuracyArgs) -> Result<()> {
    let outputs = FILES.map(|name| args.out.join(name));
    // Before the sweep, so an output that would be refused is refused at once.
    let staged = StagedSet::new(&args.out, &FILES, &[])?;
    let (size, dense, sweep_options) = match args.quick {
        true => (128, 160, SweepOptions { poses: 8, runs: 2, reference_tessellation: 512 }),
        false => {
            (256, 320, SweepOptions { poses: 32, runs: 3, reference_tessellation: accuracy::REFERENCE_TESSELLATION })
        }
    };
    let mut scenes = standard_scenes(size, dense)?;
    for path in &args.scenes {
        scenes.push(SweepScene::from_file(path, &ledger)?);
    }
    refuse_overwriting_inputs(outputs.iter().map(PathBuf::as_path), &ledger)?;
    let renderer =
        Renderer::new(options).context("starting Vulkan")?.with_ledger(ledger.clone()).with_raster(Raster::Graphics);
    let ctx = renderer.context().clone();
    let supports_compute = renderer.supports_compute_raster();
    let graphics = Verifier::new(renderer)?;
    let compute = match supports_compute {
        true => Some(Verifier::new(
            Renderer::with_context(ctx.clone())?.with_ledger(ledger.clone()).with_raster(Raster::Compute),
        )?),
        false => None,
    };
    let settings = sweep_settings(args.quick, compute.is_some());
    let cells = accuracy::cells(&settings, &scenes)?.len();
    let bar = match std::io::stderr().is_terminal() {
        true => ProgressBar::new(cells as u64),
        false => ProgressBar::hidden(),
    };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}, eta {eta}").expect("valid template"));
    let verifiers = SweepVerifiers { graphics: &graphics, compute: compute.as_ref() };
    let mut started = 0;
    let rows = accuracy::sweep(&verifiers, &settings, &scenes, sweep_options, &mut |cell| {
        bar.set_position(started);
        bar.set_message(cell.to_string());
        started += 1;
    })?;
    bar.finish_and_clear();

    accuracy::write_csv(&staged.staged(FILES[0]), &rows)?;
    accuracy::write_plot(&staged.staged(FILES[1]), &rows)?;
    let written = staged.commit()?;
    report!("device: {}", ctx.device_name())?;
    report_text(Table(&rows))?;
    report_text(Summary(&rows))?;
    report!("wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))?;
    for verifier in std::iter::once(&graphics).chain(compute.as_ref()) {
        super::check_device(verifier.renderer())?;
    }
    Ok(())
}
