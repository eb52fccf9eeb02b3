//! The `rangesynth` command line: `render` a scene file, run the `demo` on the embedded
//! default scene, `verify` hypotheses against a sensed image, score a BOP results file (`bop`),
//! measure what `accuracy` costs in time, or run the paper's `experiment`. Errors come back as values;
//! `main` prints them and exits non-zero.

mod accuracy;
mod bop;
pub(crate) mod console;
mod experiment;
mod shard;
mod verify;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use console::{note, report};
use rangesynth::effects::Reason;
use rangesynth::gpu::{CacheLoad, ContextOptions};
use rangesynth::io::refuse_overwriting_inputs;
use rangesynth::limits::{Ledger, MemoryBudget};
use rangesynth::mesh::Mesh;
use rangesynth::render::{Raster, COVERAGE_MEMBERS};
use rangesynth::render_set::{check_depth_png, render_files, render_set, write_render_set};
use rangesynth::sensor::{Sensor, View};
use rangesynth::shadow::ShadowMode;
use rangesynth::untrusted::escaped;
use rangesynth::{RenderOutput, Renderer, Scene};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The embedded default scene of `rangesynth demo`.
pub const DEMO_SCENE: &str = include_str!("demo_scene.toml");

#[derive(Parser)]
#[command(name = "rangesynth", version, about = "Realistic (triangulation-shadowed) range images on any Vulkan device")]
pub struct Cli {
    /// Use the Vulkan device whose name contains this, or whose UUID (nvidia-smi's GPU-… form
    /// too) or index (in the Vulkan loader's order, as Python's rangesynth.devices() lists
    /// them) it is (also RANGESYNTH_DEVICE).
    #[arg(long, global = true)]
    device: Option<String>,
    /// Turn on Vulkan validation with synchronization validation (also RANGESYNTH_VALIDATION=1).
    #[arg(long, global = true)]
    validation: bool,
    /// Refuse work that would need more memory than this, e.g. 8G (also
    /// RANGESYNTH_MEMORY_BUDGET; default 4G).
    #[arg(long, global = true, value_name = "SIZE", value_parser = memory_budget)]
    memory_budget: Option<MemoryBudget>,
    /// Render with the graphics pipeline or the compute rasterizer, which renders views of up
    /// to four objects (every verify hypothesis) and leaves the others to the graphics
    /// pipeline; auto (the default) takes the compute rasterizer where the device has it and
    /// the crossover measured for its kind says so (render::Crossover: on a CPU device, models
    /// of at least 0.0001 triangles per pixel of their footprint; on a GPU, of at least 1,500
    /// triangles, or under 0.004 a footprint pixel).
    #[arg(long, global = true, value_name = "auto|graphics|compute", default_value = "auto")]
    raster: Raster,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render SCENE.toml into DIR: range.exr, label_unshadowed.exr, labels.json, PNG previews.
    Render {
        scene: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Also write depth.png, BOP's depth image: each valid pixel's depth along the optical
        /// axis / SCALE as a uint16, 0 elsewhere (pinhole sensors).
        #[arg(long, value_name = "SCALE", value_parser = depth_scale)]
        depth_png: Option<f64>,
    },
    /// Render the embedded demo scene (a stepped block and a cylinder on a table) into DIR.
    Demo {
        #[arg(long)]
        out: PathBuf,
    },
    /// Score the hypotheses of HYPS.json against a sensed range image; one JSON line each.
    Verify(verify::VerifyArgs),
    /// Score a BOP results file's pose estimates against a BOP dataset's depth images under the
    /// sensor's rig: depth-only scores and VSD, as CSV.
    Bop(bop::BopArgs),
    /// Measure what accuracy costs in time: every shadow setting on standard scenes against
    /// exact ray casting, into DIR/accuracy.csv and DIR/accuracy.png.
    Accuracy(accuracy::AccuracyArgs),
    /// The paper's experiment on a synthetic benchmark: does shadowing separate correct from
    /// incorrect hypotheses? Writes views, scores, table.md, summary.json and scores.png into DIR.
    Experiment(experiment::ExperimentArgs),
}

/// `--memory-budget`'s value, read as clap reads an option's, so that a bad one is a usage
/// error (exit code 2) like any other option's.
fn memory_budget(text: &str) -> std::result::Result<MemoryBudget, String> {
    text.parse().map_err(|e: rangesynth::Error| match e {
        rangesynth::Error::Setting { reason, .. } => reason,
        other => other.to_string(),
    })
}

/// `--depth-png`'s scale: a positive, finite number, or a usage error.
fn depth_scale(text: &str) -> std::result::Result<f64, String> {
    let scale: f64 = text.parse().map_err(|e| format!("{e}"))?;
    rangesynth::io::check_depth_scale(scale).map(|()| scale).map_err(|_| "it must be positive and finite".into())
}

pub fn run(cli: Cli) -> Result<()> {
    let mut options = ContextOptions::from_env();
    options.validation |= cli.validation;
    if cli.device.is_some() {
        options.device = cli.device;
    }
    let budget = match cli.memory_budget {
        Some(budget) => budget,
        None => MemoryBudget::from_env()?,
    };
    // One account for the whole run: its inputs, what is parsed from them, and each step's
    // plan on top.
    let ledger = Arc::new(Ledger::new(budget));
    let (scene, out_dir, depth_png) = match cli.command {
        Command::Render { scene: path, out, depth_png } => (Scene::from_file(&path, &ledger)?, out, depth_png),
        Command::Demo { out } => (Scene::from_toml(DEMO_SCENE, Path::new("."), &ledger)?, out, None),
        Command::Verify(args) => return verify::run(&options, ledger, cli.raster, &args),
        Command::Bop(args) => return bop::run(&options, ledger, cli.raster, &args),
        Command::Accuracy(args) => return accuracy::run(&options, ledger, &args),
        Command::Experiment(args) => return experiment::run(&options, ledger, cli.raster, &args),
    };
    if let Some(scale) = depth_png {
        check_depth_png(&scene, scale)?;
    }
    let outputs: Vec<PathBuf> = render_files(depth_png.is_some()).iter().map(|name| out_dir.join(name)).collect();
    refuse_overwriting_inputs(outputs.iter().map(PathBuf::as_path), &ledger)?;
    let set = render_set(&out_dir, depth_png.is_some())?;
    for object in &scene.objects {
        warn_degenerate(&object.mesh);
    }
    let renderer =
        Renderer::new(&options).context("starting Vulkan")?.with_ledger(ledger.clone()).with_raster(cli.raster);
    let output = renderer.render(&scene)?;
    let written = write_render_set(set, &scene, &output, depth_png)?;
    print_summary(&renderer, &scene, &output)?;
    report!("wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))?;
    check_device(&renderer)
}

/// Tells the user about triangles the model lost (they are dropped, not rendered).
fn warn_degenerate(mesh: &Mesh) {
    if mesh.dropped_degenerate > 0 {
        note!("warning: {}: dropped {} degenerate triangle(s)", escaped(&mesh.name, 200), mesh.dropped_degenerate);
    }
}

/// Says when the device's pipeline cache could not be used or written (the run goes on
/// without it: src/gpu/pipeline_cache.rs), and fails when validation (if on) reported anything.
fn check_device(renderer: &Renderer) -> Result<()> {
    let cache = renderer.context().pipeline_cache_report();
    let path = cache.path.as_deref().map_or(String::new(), |p| escaped(&p.display().to_string(), 200));
    if let CacheLoad::Ignored(why) = &cache.load {
        note!("note: the pipeline cache {path} was not used ({why}); its pipelines were built anew");
    }
    if let Some(Err(why)) = &cache.last_save {
        note!(
            "warning: the pipeline cache {path} could not be written: {why}; the next run builds its pipelines again"
        );
    }
    let messages = renderer.context().take_validation_messages();
    if !messages.is_empty() {
        anyhow::bail!("Vulkan validation reported {} message(s):\n{}", messages.len(), messages.join("\n"));
    }
    Ok(())
}

/// What a summary says of a sensor's witnesses: the scanner's θ, or the witnesses' names.
fn witnesses_text(s: &Sensor) -> String {
    match s.scanner() {
        Some(scanner) => format!("θ = {}°", scanner.theta_deg),
        None => {
            let names: Vec<String> = s.witnesses.iter().map(|w| escaped(&w.name, 20)).collect();
            format!("witnesses: {}", if names.is_empty() { "none".to_string() } else { names.join(", ") })
        }
    }
}

fn print_summary(renderer: &Renderer, scene: &Scene, out: &RenderOutput) -> Result<()> {
    let s = &scene.sensor;
    report!("device: {}", renderer.context().device_name())?;
    match (scene.shadow.mode, renderer.raster()) {
        (ShadowMode::Exact, _) => report!("raster: none (shadow mode exact casts rays on the CPU)")?,
        _ if s.scanner().is_none() && out.raster.is_none() => {
            report!("raster: none (this rig's rays are cast on the CPU)")?
        }
        (_, Raster::Auto) if s.scanner().is_none() => report!(
            "raster: {} (a rig's pinhole views; auto: compute for up to {COVERAGE_MEMBERS} objects of {})",
            out.raster.map_or("none", Raster::as_str),
            renderer.rig_crossover(s, scene.shadow.mode, scene.objects.len())
        )?,
        _ if s.scanner().is_none() => {
            report!("raster: {} (a rig's pinhole views)", out.raster.map_or("none", Raster::as_str))?
        }
        (_, Raster::Auto) => report!(
            "raster: {} (auto: compute for up to {COVERAGE_MEMBERS} objects of {})",
            out.raster.map_or("none", Raster::as_str),
            renderer.crossover()
        )?,
        _ => report!("raster: {}", out.raster.map_or("none", Raster::as_str))?,
    }
    let view = match s.reference {
        View::Orthographic(o) => format!("{}×{} at pitch {}×{}", o.width, o.height, o.pitch[0], o.pitch[1]),
        View::Pinhole(p) => {
            let k = p.intrinsics;
            format!("{}×{} pinhole, fx {} fy {} cx {} cy {}", k.width, k.height, k.fx, k.fy, k.cx, k.cy)
        }
        _ => format!("{}×{}", s.width(), s.height()),
    };
    let witnesses = witnesses_text(s);
    report!(
        "image: {view}, {witnesses}, shadow mode {}{}",
        scene.shadow.mode.as_str(),
        if out.shadow_pass { "" } else { " (no shadow pass)" }
    )?;
    let with_effects = !scene.effects.is_empty();
    if with_effects {
        report!("effects: {}", scene.effects.passes().map(|e| e.pass_name()).collect::<Vec<_>>().join(", "))?;
    }
    let effects_column = if with_effects { format!(" {:>9}", "effects") } else { String::new() };
    // A column per witness of a rig other than the scanner (whose one is `shadowed`): the
    // pixels of each label that witness did not see.
    let witness_columns = if s.scanner().is_some() { 0 } else { s.witnesses.len() };
    let witness_names: Vec<String> = s.witnesses[..witness_columns].iter().map(|w| escaped(&w.name, 24)).collect();
    let widths: Vec<usize> = witness_names.iter().map(|name| name.chars().count().max(9)).collect();
    let witness_header: String = witness_names.iter().zip(&widths).map(|(name, &w)| format!(" {name:>w$}")).collect();
    report!(
        "{:>6}  {:<28} {:<12} {:>8} {:>9}{effects_column}{witness_header}",
        "label",
        "model",
        "surface",
        "valid",
        "shadowed"
    )?;
    // One pass over the pixels and one over the labels: [valid, shadowed, lost to an effect,
    // lost by each witness] per label.
    let bases = scene.label_bases()?;
    let labels: usize = scene.objects.iter().map(|o| o.mesh.surface_names.len()).sum();
    let stride = 3 + witness_columns;
    let mut populations = vec![0u64; (labels + 1) * stride];
    for ((&surface, &reason), &bits) in out.label_unshadowed.iter().zip(&out.reason).zip(&out.witness) {
        let which = match reason {
            Reason::Valid => 0,
            Reason::Shadow => 1,
            _ => 2,
        };
        if let Some(p) = populations.get_mut(surface as usize * stride..(surface as usize + 1) * stride) {
            p[which] += 1;
            for (k, count) in p[3..].iter_mut().enumerate() {
                *count += u64::from(bits >> k & 1);
            }
        }
    }
    // Only the labels with pixels, read in place (a scene can have millions of labels).
    for (object, (o, base)) in scene.objects.iter().zip(bases).enumerate() {
        for (s, name) in o.mesh.surface_names.iter().enumerate() {
            let label = base as usize + s + 1;
            let p = &populations[label * stride..(label + 1) * stride];
            let (valid, shadowed, lost) = (p[0], p[1], p[2]);
            if valid + shadowed + lost > 0 {
                let model = format!("{object} {}", escaped(&o.model_ref, 26));
                let lost = if with_effects { format!(" {lost:>9}") } else { String::new() };
                let by_witness: String = p[3..].iter().zip(&widths).map(|(n, &w)| format!(" {n:>w$}")).collect();
                let surface = escaped(name, 40);
                report!("{label:>6}  {model:<28} {surface:<12} {valid:>8} {shadowed:>9}{lost}{by_witness}")?;
            }
        }
    }
    if with_effects {
        let lost: Vec<String> = Reason::ALL[2..]
            .iter()
            .map(|&r| (r, out.pixels_lost_to(r)))
            .filter(|&(_, n)| n > 0)
            .map(|(r, n)| format!("{} {n}", r.name()))
            .collect();
        report!("pixels lost: {}", if lost.is_empty() { "none".to_string() } else { lost.join(", ") })?;
    }
    let passes: Vec<String> = out
        .timings
        .iter()
        .filter(|t| !t.on_cpu)
        .map(|t| format!("{} {}", t.name, t.ms.map_or("-".to_string(), |ms| format!("{ms:.2} ms"))))
        .collect();
    for t in out.timings.iter().filter(|t| t.on_cpu) {
        report!("CPU time: {} {:.2} ms", t.name, t.ms.unwrap_or(0.0))?;
    }
    if !passes.is_empty() {
        report!("GPU time per pass: {}", passes.join(", "))?;
    }
    Ok(())
}
