//! The `rangesynth` command line: `render` a scene file, run the `demo` on the embedded
//! default scene, `verify` hypotheses against a sensed image, measure what `accuracy` costs in
//! time, or run the paper's `experiment`. Errors come back as values;
//! `main` prints them and exits non-zero.

mod accuracy;
mod experiment;
mod verify;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use rangesynth::effects::Reason;
use rangesynth::gpu::ContextOptions;
use rangesynth::io::{label_map, refuse_overwriting_inputs, render_set, write_render_set, RENDER_FILES};
use rangesynth::limits::MemoryBudget;
use rangesynth::mesh::Mesh;
use rangesynth::render::{Raster, COVERAGE_MEMBERS};
use rangesynth::shadow::ShadowMode;
use rangesynth::{RenderOutput, Renderer, Scene};
use std::path::{Path, PathBuf};

/// The embedded default scene of `rangesynth demo`.
pub const DEMO_SCENE: &str = include_str!("demo_scene.toml");

#[derive(Parser)]
#[command(name = "rangesynth", version, about = "Realistic (triangulation-shadowed) range images on any Vulkan device")]
pub struct Cli {
    /// Use the Vulkan device whose name contains this (also RANGESYNTH_DEVICE).
    #[arg(long, global = true)]
    device: Option<String>,
    /// Turn on Vulkan validation with synchronization validation (also RANGESYNTH_VALIDATION=1).
    #[arg(long, global = true)]
    validation: bool,
    /// Refuse work that would need more memory than this, e.g. 8G (also
    /// RANGESYNTH_MEMORY_BUDGET; default 4G).
    #[arg(long, global = true, value_name = "SIZE")]
    memory_budget: Option<String>,
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
    },
    /// Render the embedded demo scene (a stepped block and a cylinder on a table) into DIR.
    Demo {
        #[arg(long)]
        out: PathBuf,
    },
    /// Score the hypotheses of HYPS.json against a sensed range image; one JSON line each.
    Verify(verify::VerifyArgs),
    /// Measure what accuracy costs in time: every shadow setting on standard scenes against
    /// exact ray casting, into DIR/accuracy.csv and DIR/accuracy.png.
    Accuracy(accuracy::AccuracyArgs),
    /// The paper's experiment on a synthetic benchmark: does shadowing separate correct from
    /// incorrect hypotheses? Writes views, scores, table.md, summary.json and scores.png into DIR.
    Experiment(experiment::ExperimentArgs),
}

pub fn run(cli: Cli) -> Result<()> {
    let mut options = ContextOptions::from_env();
    options.validation |= cli.validation;
    if cli.device.is_some() {
        options.device = cli.device;
    }
    let budget = match &cli.memory_budget {
        Some(text) => text.parse().context("--memory-budget")?,
        None => MemoryBudget::from_env()?,
    };
    let (scene, out_dir, inputs) = match cli.command {
        Command::Render { scene: path, out } => {
            let scene = Scene::from_file(&path, budget)?;
            let base_dir = path.parent().unwrap_or(Path::new("."));
            let mut inputs = model_files(scene.objects.iter().map(|o| o.model_ref.as_str()), base_dir);
            inputs.push(path);
            (scene, out, inputs)
        }
        Command::Demo { out } => (Scene::from_toml(DEMO_SCENE, Path::new("."), budget)?, out, Vec::new()),
        Command::Verify(args) => return verify::run(&options, budget, cli.raster, &args),
        Command::Accuracy(args) => return accuracy::run(&options, budget, &args),
        Command::Experiment(args) => return experiment::run(&options, budget, cli.raster, &args),
    };
    let outputs = RENDER_FILES.map(|name| out_dir.join(name));
    refuse_overwriting_inputs(outputs.iter().map(PathBuf::as_path), inputs.iter().map(PathBuf::as_path))?;
    let set = render_set(&out_dir)?;
    for object in &scene.objects {
        warn_degenerate(&object.mesh);
    }
    let renderer =
        Renderer::new(&options).context("starting Vulkan")?.with_memory_budget(budget).with_raster(cli.raster);
    let output = renderer.render(&scene)?;
    let written = write_render_set(set, &scene, &output)?;
    print_summary(&renderer, &scene, &output)?;
    println!("wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
    check_validation(&renderer)
}

/// The files behind model references (built-ins have none), relative to `base_dir`.
fn model_files<'a>(references: impl Iterator<Item = &'a str>, base_dir: &Path) -> Vec<PathBuf> {
    references.filter(|r| !r.starts_with("builtin:")).map(|r| base_dir.join(r)).collect()
}

/// Tells the user about triangles the model lost (they are dropped, not rendered).
fn warn_degenerate(mesh: &Mesh) {
    if mesh.dropped_degenerate > 0 {
        eprintln!("warning: {}: dropped {} degenerate triangle(s)", mesh.name, mesh.dropped_degenerate);
    }
}

/// Fails when validation (if on) reported anything.
fn check_validation(renderer: &Renderer) -> Result<()> {
    let messages = renderer.context().take_validation_messages();
    if !messages.is_empty() {
        anyhow::bail!("Vulkan validation reported {} message(s):\n{}", messages.len(), messages.join("\n"));
    }
    Ok(())
}

fn print_summary(renderer: &Renderer, scene: &Scene, out: &RenderOutput) -> Result<()> {
    let s = &scene.sensor;
    println!("device: {}", renderer.context().device_name());
    match (scene.shadow.mode, renderer.raster()) {
        (ShadowMode::Exact, _) => println!("raster: none (shadow mode exact casts rays on the CPU)"),
        (_, Raster::Auto) => println!(
            "raster: {} (auto: compute for up to {COVERAGE_MEMBERS} objects of {})",
            out.raster.as_str(),
            renderer.crossover()
        ),
        _ => println!("raster: {}", out.raster.as_str()),
    }
    println!(
        "image: {}×{} at pitch {}×{}, θ = {}°, shadow mode {}{}",
        s.width,
        s.height,
        s.pitch[0],
        s.pitch[1],
        s.theta_deg,
        scene.shadow.mode.as_str(),
        if out.shadow_pass { "" } else { " (no shadow pass)" }
    );
    let with_effects = !scene.effects.is_empty();
    if with_effects {
        println!("effects: {}", scene.effects.passes().map(|e| e.pass_name()).collect::<Vec<_>>().join(", "));
    }
    let effects_column = if with_effects { format!(" {:>9}", "effects") } else { String::new() };
    println!("{:>6}  {:<28} {:<12} {:>8} {:>9}{effects_column}", "label", "model", "surface", "valid", "shadowed");
    // One pass over the pixels and one over the labels: [valid, shadowed, lost to an effect]
    // per label.
    let labels = label_map(scene)?;
    let mut populations = vec![[0u64; 3]; labels.len() + 1];
    for (&surface, &reason) in out.label_unshadowed.iter().zip(&out.reason) {
        let which = match reason {
            Reason::Valid => 0,
            Reason::Shadow => 1,
            _ => 2,
        };
        if let Some(p) = populations.get_mut(surface as usize) {
            p[which] += 1;
        }
    }
    for entry in labels {
        let [valid, shadowed, lost] = populations[entry.label as usize];
        if valid + shadowed + lost > 0 {
            let model = format!("{} {}", entry.object, entry.model);
            let lost = if with_effects { format!(" {lost:>9}") } else { String::new() };
            println!("{:>6}  {:<28} {:<12} {valid:>8} {shadowed:>9}{lost}", entry.label, model, entry.surface_name);
        }
    }
    if with_effects {
        let lost: Vec<String> = Reason::ALL[2..]
            .iter()
            .map(|&r| (r, out.pixels_lost_to(r)))
            .filter(|&(_, n)| n > 0)
            .map(|(r, n)| format!("{} {n}", r.name()))
            .collect();
        println!("pixels lost: {}", if lost.is_empty() { "none".to_string() } else { lost.join(", ") });
    }
    let passes: Vec<String> = out
        .timings
        .iter()
        .filter(|t| !t.on_cpu)
        .map(|t| format!("{} {}", t.name, t.ms.map_or("-".to_string(), |ms| format!("{ms:.2} ms"))))
        .collect();
    for t in out.timings.iter().filter(|t| t.on_cpu) {
        println!("CPU time: {} {:.2} ms", t.name, t.ms.unwrap_or(0.0));
    }
    println!("GPU time per pass: {}", passes.join(", "));
    Ok(())
}
