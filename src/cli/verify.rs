//! `rangesynth verify HYPS.json --scene SENSED.exr --out SCORES.jsonl`: scores every
//! hypothesis, writes one JSON line each, and prints a ranked summary. Sensor, shadow and
//! effects settings come from the hypothesis file, else from the sensed EXR's header; effects
//! given by both must agree unless `--override-effects` says to use the file's.
//!
//! Every hypothesis is checked (models loaded, bindings, views, memory) before anything is
//! written. Hypotheses are then verified a slice at a time and their lines written as each
//! slice finishes, so beyond the parsed input only a small summary row per hypothesis is kept;
//! the lines go to a temporary file that replaces `--out` only once it is complete.

use super::console::report;
use super::shard::Shard;
use super::{check_device, warn_degenerate};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rangesynth::effects::Effects;
use rangesynth::gpu::ContextOptions;
use rangesynth::io::{read_range_image, refuse_overwriting_inputs, PendingFile};
use rangesynth::limits::Ledger;
use rangesynth::render::{Raster, COVERAGE_MEMBERS, MAX_SLOTS};
use rangesynth::sensor::Sensor;
use rangesynth::untrusted::{escaped, quoted};
use rangesynth::verify::{
    Hypothesis, HypothesisFile, Record, SensedImage, Verification, Verifier, VerifySettings, MAX_CHUNK,
    MAX_CHUNKS_IN_FLIGHT,
};
use rangesynth::Renderer;
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// Use the hypothesis file's "sensor" even where it differs from the sensed image's header
    /// (without it, a difference is refused).
    #[arg(long)]
    override_sensor: bool,
    /// Use the hypothesis file's "effects" even where they differ from those the sensed image's
    /// header records (without it, a difference is refused): to verify with a simpler sensor
    /// model than the one that made the image.
    #[arg(long)]
    override_effects: bool,
    /// Verify only shard i of N (from 0): the i-th of N contiguous, near-equal ranges of the
    /// file's hypotheses; the N outputs, concatenated in order, are the unsharded output byte
    /// for byte. For job arrays: Kubernetes' JOB_COMPLETION_INDEX or Slurm's
    /// SLURM_ARRAY_TASK_ID is i.
    #[arg(long, value_name = "i/N")]
    shard: Option<Shard>,
    /// Most hypotheses per GPU submission.
    #[arg(long, default_value_t = MAX_CHUNK)]
    chunk_size: usize,
    /// Hypotheses the compute rasterizer covers in one dispatch, 1 to 4 (default: 4 on a GPU,
    /// where it saves a dispatch and a barrier each; 1 on a CPU device such as lavapipe, where
    /// those cost next to nothing). The scores are the same either way.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=COVERAGE_MEMBERS as u64))]
    hypotheses_per_dispatch: Option<u64>,
    /// Hypotheses a batch renders side by side, each in render targets of its own (its slot),
    /// 1 to 64: each stage of their passes waits behind one barrier (default: 16 on a GPU, where
    /// a barrier drains the device; 4 on a CPU device such as lavapipe, where it costs next to
    /// nothing). Fewer where the memory budget holds fewer. The scores are the same either way.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=MAX_SLOTS as u64))]
    slots: Option<u64>,
    /// Chunks (submissions) in flight at once, 1 to 4: with more than one, chunks are recorded
    /// while the device runs another (default: 3 on a GPU; 1 on a CPU device, whose device work
    /// runs on the same cores). Fewer where the memory budget holds fewer. The scores are the
    /// same either way.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=MAX_CHUNKS_IN_FLIGHT as u64))]
    chunks_in_flight: Option<u64>,
    /// How many of the best hypotheses the summary lists.
    #[arg(long, default_value_t = 10)]
    top: usize,
}

pub fn run(options: &ContextOptions, ledger: Arc<Ledger>, raster: Raster, args: &VerifyArgs) -> Result<()> {
    let file = HypothesisFile::from_file(&args.hypotheses, &ledger)?;
    let image = read_range_image(&args.scene, &ledger)?;
    let sensor = match (file.sensor, image.sensor.clone()) {
        (Some(given), Some(header)) if given != header && !args.override_sensor => anyhow::bail!(
            "{} gives a sensor that differs from the one in {}'s header: {}; fix one of them, or pass \
             --override-sensor to use the hypothesis file's",
            args.hypotheses.display(),
            args.scene.display(),
            sensor_differences(&given, &header)
        ),
        (given, header) => given.or(header).with_context(|| {
            format!(
                "no sensor settings: neither {} has a \"sensor\" object nor {} a sensor header",
                args.hypotheses.display(),
                args.scene.display()
            )
        })?,
    };
    let shadow = file.shadow.or(image.shadow).unwrap_or_default();
    let effects = match (file.effects, image.effects) {
        (Some(given), Some(header)) if given != header && !args.override_effects => anyhow::bail!(
            "{} names the effects {} but {} was made with {}; make them agree, leave \"effects\" out of \
             the hypothesis file, or pass --override-effects to use the hypothesis file's",
            args.hypotheses.display(),
            effects_text(&given),
            args.scene.display(),
            effects_text(&header)
        ),
        (given, header) => given.or(header).unwrap_or_default(),
    };
    // The range image as read (X, Y, Z, label) is held while the sensed image is built from it.
    let pixels = u64::from(image.width) * u64::from(image.height);
    ledger.charge(
        format_args!("preparing the {}×{} sensed image {}", image.width, image.height, args.scene.display()),
        (16 + SensedImage::HOST_BYTES_PER_PIXEL) * pixels,
    )?;
    let sensed = SensedImage::new(&image, &sensor).with_context(|| format!("sensed image {}", args.scene.display()))?;
    drop(image);
    let mut renderer =
        Renderer::new(options).context("starting Vulkan")?.with_ledger(ledger.clone()).with_raster(raster);
    if let Some(n) = args.hypotheses_per_dispatch {
        renderer = renderer.with_hypotheses_per_dispatch(n as usize);
    }
    let mut verifier = Verifier::new(renderer).context("starting Vulkan")?;
    if let Some(n) = args.slots {
        verifier = verifier.with_slots(n as usize);
    }
    if let Some(n) = args.chunks_in_flight {
        verifier = verifier.with_chunks_in_flight(n as usize);
    }
    let base_dir = args.hypotheses.parent().unwrap_or(Path::new("."));
    let mut warned = std::collections::HashSet::new();
    let tolerance = file.tolerance;
    let total = file.hypotheses.len();
    let shard = args.shard.map_or(0..total, |shard| shard.range(total));
    let hypotheses = file
        .hypotheses
        .into_iter()
        .skip(shard.start)
        .take(shard.len())
        .map(|h| {
            let model = verifier
                .model_as(&h.model, base_dir, h.surfaces, h.scale)
                .with_context(|| format!("hypothesis {}", quoted(&h.id)))?;
            if warned.insert(h.model.clone()) {
                warn_degenerate(&model.mesh);
            }
            Ok(Hypothesis { id: h.id, model, pose: h.pose, bindings: h.bindings })
        })
        .collect::<Result<Vec<_>>>()?;
    let settings = VerifySettings {
        sensor,
        shadow,
        effects,
        tolerance,
        compare_shadow: args.compare_shadow,
        chunk_size: args.chunk_size,
    };
    verifier.check(&sensed, &settings, &hypotheses)?;
    refuse_overwriting_inputs([args.out.as_path()], &ledger)?;

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
    let mut pending = PendingFile::new(&args.out)?.guarding_inputs(&ledger);
    let mut out = BufWriter::new(pending.file());
    let mut rows = Vec::with_capacity(hypotheses.len());
    // Each chunk's records written as it comes (Verifier::verify_each): a few chunks' results
    // held at a time at most, however many hypotheses.
    let written = |e: std::io::Error| rangesynth::Error::Io { path: args.out.clone(), source: e };
    verifier.verify_each(&sensed, &settings, &hypotheses, &mut |chunk| {
        for v in &chunk {
            serde_json::to_writer(&mut out, &Record::new(v, &sensed)).map_err(|e| written(e.into()))?;
            out.write_all(b"\n").map_err(written)?;
            rows.push(SummaryRow::from(v));
        }
        bar.set_position(rows.len() as u64);
        Ok(())
    })?;
    out.flush().with_context(|| format!("writing {}", args.out.display()))?;
    drop(out);
    pending.commit()?;
    bar.finish_and_clear();
    print_summary(&verifier, &settings, &rows, args.top, start.elapsed().as_secs_f64())?;
    report!("wrote {}", args.out.display())?;
    check_device(verifier.renderer())
}

/// Each key in which two sensors differ as files write them, with both values (the
/// witnesses as one key, `witness`).
fn sensor_differences(given: &Sensor, header: &Sensor) -> String {
    let keys = |sensor: &Sensor| match serde_json::to_value(sensor) {
        Ok(serde_json::Value::Object(keys)) => keys,
        _ => serde_json::Map::new(),
    };
    let (given, header) = (keys(given), keys(header));
    let mut names: Vec<&String> = given.keys().chain(header.keys()).collect();
    names.sort();
    names.dedup();
    let value = |keys: &serde_json::Map<String, serde_json::Value>, name: &str| {
        keys.get(name).map_or_else(|| "(none)".to_string(), shown)
    };
    names
        .into_iter()
        .filter(|name| given.get(*name) != header.get(*name))
        .map(|name| format!("{name} = {} (header: {})", value(&given, name), value(&header, name)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A value as a message shows it: arrays with a space after each comma, as files write them.
fn shown(value: &serde_json::Value) -> String {
    match value {
        serde_json::Value::Array(items) => format!("[{}]", items.iter().map(shown).collect::<Vec<_>>().join(", ")),
        other => other.to_string(),
    }
}

/// The effects as one line of JSON, for messages.
fn effects_text(effects: &Effects) -> String {
    serde_json::to_string(effects).unwrap_or_else(|e| format!("(unprintable: {e})"))
}

/// What the ranked summary needs of one hypothesis.
struct SummaryRow {
    id: String,
    scores: [f64; 7],
    rejected: Option<String>,
    unshadowed: Option<f64>,
    raster: Option<Raster>,
}

impl From<&Verification> for SummaryRow {
    fn from(v: &Verification) -> Self {
        let s = &v.scores;
        Self {
            id: v.id.clone(),
            scores: [s.s, s.s1, s.s2, s.s3, s.s4, s.s5, s.s6],
            rejected: s.rejected.clone(),
            unshadowed: v.unshadowed.as_ref().map(|(_, u)| u.s),
            raster: v.raster,
        }
    }
}

/// How many hypotheses each rasterizer rendered: "12 by compute, 4 by graphics", and those
/// that rendered nothing (their footprints missed the image, or exact mode cast rays).
fn rasterized(results: &[SummaryRow]) -> String {
    let count = |raster: Option<Raster>| results.iter().filter(|r| r.raster == raster).count();
    let mut parts: Vec<String> = [Raster::Compute, Raster::Graphics]
        .into_iter()
        .map(|raster| format!("{} by {}", count(Some(raster)), raster.as_str()))
        .collect();
    let none = count(None);
    if none > 0 {
        parts.push(format!("{none} not rendered (outside the image, or cast by exact mode)"));
    }
    parts.join(", ")
}

fn print_summary(
    verifier: &Verifier,
    settings: &VerifySettings,
    results: &[SummaryRow],
    top: usize,
    seconds: f64,
) -> Result<()> {
    let (s, renderer) = (&settings.sensor, verifier.renderer());
    report!("device: {}", renderer.context().device_name())?;
    match renderer.raster() {
        Raster::Auto => report!(
            "raster: auto (compute for models of {}, where the device has it; else graphics): {}",
            if s.scanner().is_some() {
                renderer.crossover()
            } else {
                renderer.rig_crossover(s, settings.shadow.mode, 1)
            },
            rasterized(results)
        )?,
        raster => report!("raster: {}: {}", raster.as_str(), rasterized(results))?,
    }
    if renderer.may_compute() {
        let n = renderer.hypotheses_per_dispatch();
        report!("compute rasterizer: up to {n} hypothes{} a coverage dispatch", if n == 1 { "is" } else { "es" })?;
    }
    let (slots, chunks) = (verifier.slots(), verifier.chunks_in_flight());
    report!(
        "batches: up to {slots} hypothes{} side by side (slots), up to {chunks} chunk{} in flight (fewer where the \
         memory budget holds fewer)",
        if slots == 1 { "is" } else { "es" },
        if chunks == 1 { "" } else { "s" }
    )?;
    if !settings.effects.is_empty() {
        report!("effects: {}", effects_text(&settings.effects))?;
    }
    let witnesses = super::witnesses_text(s);
    report!(
        "{} hypotheses against a {}×{} image, {witnesses}, shadow mode {}, τ = {}: {:.2} s ({:.1} per second)",
        results.len(),
        s.width(),
        s.height(),
        settings.shadow.mode.as_str(),
        settings.tolerance,
        seconds,
        results.len() as f64 / seconds.max(1e-9)
    )?;
    let mut ranked: Vec<&SummaryRow> = results.iter().collect();
    ranked.sort_by(|a, b| b.scores[0].total_cmp(&a.scores[0]));
    report!(
        "{:>4}  {:<20} {:>10} {:>6} {:>6} {:>6} {:>6} {:>6} {:>6}  unshadowed s / rejected",
        "rank",
        "id",
        "s",
        "s1",
        "s2",
        "s3",
        "s4",
        "s5",
        "s6"
    )?;
    for (rank, v) in ranked.iter().take(top).enumerate() {
        let extra = match (&v.rejected, v.unshadowed) {
            (Some(reason), _) => reason.clone(),
            (None, Some(u)) => format!("{u:.4e}"),
            (None, None) => String::new(),
        };
        let [s, s1, s2, s3, s4, s5, s6] = v.scores;
        report!(
            "{:>4}  {:<20} {s:>10.4e} {s1:>6.3} {s2:>6.3} {s3:>6.3} {s4:>6.3} {s5:>6.3} {s6:>6.3}  {extra}",
            rank + 1,
            escaped(&v.id, 40),
        )?;
    }
    let rejected = results.iter().filter(|v| v.rejected.is_some()).count();
    if rejected > 0 {
        report!("{rejected} of {} hypotheses rejected", results.len())?;
    }
    Ok(())
}
