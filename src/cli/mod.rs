//! The `rangesynth` command line: `render` a scene file, run the `demo` on the embedded
//! default scene, or `verify` hypotheses against a sensed image. Errors come back as values;
//! `main` prints them and exits non-zero.

mod verify;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use rangesynth::gpu::ContextOptions;
use rangesynth::io::{label_map, write_render_directory};
use rangesynth::mesh::Mesh;
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
}

pub fn run(cli: Cli) -> Result<()> {
    let mut options = ContextOptions::from_env();
    options.validation |= cli.validation;
    if cli.device.is_some() {
        options.device = cli.device;
    }
    let (scene, out_dir) = match cli.command {
        Command::Render { scene, out } => (Scene::from_file(&scene)?, out),
        Command::Demo { out } => (Scene::from_toml(DEMO_SCENE, Path::new("."))?, out),
        Command::Verify(args) => return verify::run(&options, &args),
    };
    for object in &scene.objects {
        warn_degenerate(&object.mesh);
    }
    let renderer = Renderer::new(&options).context("starting Vulkan")?;
    let output = renderer.render(&scene)?;
    let written = write_render_directory(&out_dir, &scene, &output)?;
    print_summary(&renderer, &scene, &output)?;
    println!("wrote {}", written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "));
    check_validation(&renderer)
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
    println!("{:>6}  {:<28} {:<12} {:>8} {:>9}", "label", "model", "surface", "valid", "shadowed");
    for entry in label_map(scene)? {
        let valid = out.label.iter().filter(|&&l| l == entry.label).count();
        let before = out.label_unshadowed.iter().filter(|&&l| l == entry.label).count();
        if before > 0 {
            let model = format!("{} {}", entry.object, entry.model);
            println!("{:>6}  {:<28} {:<12} {:>8} {:>9}", entry.label, model, entry.surface_name, valid, before - valid);
        }
    }
    let ms = |t: Option<f64>| t.map_or("-".to_string(), |t| format!("{t:.2} ms"));
    println!(
        "GPU time per pass: range {}, shadow {}, shadow mask {}",
        ms(out.timings.range_ms),
        ms(out.timings.shadow_ms),
        ms(out.timings.mask_ms)
    );
    Ok(())
}
