//! `rangesynth verify HYPS.json --scene SENSED.exr --out SCORES.jsonl`: scores every
//! hypothesis, writes one JSON line each, and prints a ranked summary. Sensor and shadow
//! settings come from the hypothesis file, else from the sensed EXR's header.

use super::check_validation;
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rangesynth::gpu::ContextOptions;
use rangesynth::io::read_range_image;
use rangesynth::verify::{
    Hypothesis, HypothesisFile, Record, SensedImage, Verification, Verifier, VerifySettings, MAX_CHUNK,
};
use rangesynth::Renderer;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct VerifyArgs {
    /// The hypothesis file (JSON).
    hypotheses: PathBuf,
    /// The sensed image, as `render` writes it (range.exr).
    #[arg(long)]
    scene: PathBuf,
    /// Where to write one JSON object per hypothesis.
    #[arg(long)]
    out: PathBuf,
    /// Also score each hypothesis without shadowing (an "unshadowed" object on each line).
    #[arg(long)]
    compare_shadow: bool,
    /// Most hypotheses per GPU submission.
    #[arg(long, default_value_t = MAX_CHUNK)]
    chunk_size: usize,
    /// How many of the best hypotheses the summary lists.
    #[arg(long, default_value_t = 10)]
    top: usize,
}

pub fn run(options: &ContextOptions, args: &VerifyArgs) -> Result<()> {
    let file = HypothesisFile::from_file(&args.hypotheses)?;
    let image = read_range_image(&args.scene)?;
    let sensor = file.sensor.or(image.sensor).with_context(|| {
        format!(
            "no sensor settings: neither {} has a \"sensor\" object nor {} a sensor header",
            args.hypotheses.display(),
            args.scene.display()
        )
    })?;
    let shadow = file.shadow.or(image.shadow).unwrap_or_default();
    let sensed = SensedImage::new(&image, &sensor).with_context(|| format!("sensed image {}", args.scene.display()))?;
    let verifier = Verifier::new(Renderer::new(options).context("starting Vulkan")?);
    let base_dir = args.hypotheses.parent().unwrap_or(Path::new("."));
    let hypotheses = file
        .hypotheses
        .iter()
        .map(|h| {
            let model = verifier.model(&h.model, base_dir).with_context(|| format!("hypothesis {:?}", h.id))?;
            Ok(Hypothesis { id: h.id.clone(), model, pose: h.pose, bindings: h.bindings.clone() })
        })
        .collect::<Result<Vec<_>>>()?;
    let settings = VerifySettings {
        sensor,
        shadow: shadow.mode,
        tolerance: file.tolerance,
        compare_shadow: args.compare_shadow,
        chunk_size: args.chunk_size,
    };
    let bar = if std::io::stderr().is_terminal() && hypotheses.len() > 1 {
        let bar = ProgressBar::new(hypotheses.len() as u64);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} hypotheses, {per_sec}, eta {eta}")
                .expect("valid template"),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let start = std::time::Instant::now();
    let results = verifier.verify(&sensed, &settings, &hypotheses, &mut |done| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    write_records(&args.out, &results, &sensed)?;
    print_summary(verifier.renderer(), &settings, &results, args.top, seconds);
    println!("wrote {}", args.out.display());
    check_validation(verifier.renderer())
}

fn write_records(path: &Path, results: &[Verification], sensed: &SensedImage) -> Result<()> {
    let file = std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut out = BufWriter::new(file);
    for v in results {
        serde_json::to_writer(&mut out, &Record::new(v, sensed))?;
        out.write_all(b"\n")?;
    }
    out.flush().with_context(|| format!("writing {}", path.display()))
}

fn print_summary(renderer: &Renderer, settings: &VerifySettings, results: &[Verification], top: usize, seconds: f64) {
    let s = &settings.sensor;
    println!("device: {}", renderer.context().device_name());
    println!(
        "{} hypotheses against a {}×{} image, θ = {}°, shadow mode {}, τ = {}: {:.2} s ({:.1} per second)",
        results.len(),
        s.width,
        s.height,
        s.theta_deg,
        settings.shadow.as_str(),
        settings.tolerance,
        seconds,
        results.len() as f64 / seconds.max(1e-9)
    );
    let mut ranked: Vec<&Verification> = results.iter().collect();
    ranked.sort_by(|a, b| b.scores.s.total_cmp(&a.scores.s));
    println!(
        "{:>4}  {:<20} {:>10} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}  unshadowed s / rejected",
        "rank", "id", "s", "s1", "s2", "s3", "s4", "s5", "s6"
    );
    for (rank, v) in ranked.iter().take(top).enumerate() {
        let c = &v.scores;
        let extra = match (&c.rejected, &v.unshadowed) {
            (Some(reason), _) => reason.clone(),
            (None, Some((_, u))) => format!("{:.4e}", u.s),
            (None, None) => String::new(),
        };
        println!(
            "{:>4}  {:<20} {:>10.4e} {:>6.3} {:>6.3} {:>6.3} {:>6.3} {:>6.3} {:>6.3}  {extra}",
            rank + 1,
            v.id,
            c.s,
            c.s1,
            c.s2,
            c.s3,
            c.s4,
            c.s5,
            c.s6
        );
    }
    let rejected = results.iter().filter(|v| v.scores.rejected.is_some()).count();
    if rejected > 0 {
        println!("{rejected} of {} hypotheses rejected", results.len());
    }
}
