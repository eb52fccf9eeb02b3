//! Verification throughput: hypotheses per second at 256² for a 12-triangle box and a
//! ~10k-triangle sphere, in batches of 1, 64 and 1,024, with and without shadowing. The
//! baseline, measured in the same run, verifies the same hypotheses one call (one
//! submission) each, so the batching gain shows as a ratio.
//!
//! A third table compares the rasterizers (src/render/raster/compute/): the same batches
//! verified with the graphics pipeline and with the compute rasterizer, in the same run, for
//! models of growing density (triangles per footprint pixel, which with the triangle count is
//! what `auto` reads, and its pick on this device); a fourth, the
//! compute rasterizer's issue's workloads: a model filling the image, at 256² and 1024², with
//! label-mode and depth-mode shadows. Both take the fastest of five batches per rasterizer,
//! the rasterizers in turn (`fastest_in_turn`). Between them, the compute rasterizer covering
//! one hypothesis a coverage dispatch against four (`Renderer::with_hypotheses_per_dispatch`),
//! in runs of 4 slots, 16 and 64 (`Verifier::with_slots`), one to four chunks in flight
//! (`Verifier::with_chunks_in_flight`), and under each model where a chunk's time goes: its
//! wall time in runs of 16 with one chunk in flight and with three, and the device's by stage.
//! Before them all, a table of the peak resident memory while verifying batches of 16, 1,024
//! and 4,096 with each rasterizer (a chunk, one submission, is at most 1,024). `-- --rasters` runs only these four.
//!
//! A pinhole rig beside the scanner on the same triangles and pixel count (`rig_costs`; `-- --rigs`
//! runs only it).
//!
//! A second table gives each sensor effect's cost (src/effects.rs): milliseconds per
//! hypothesis for the box with depth-mode shadows in batches of 64, and the ratio to the same
//! batch without effects, measured in the same run (each the best of five).
//!
//! Cold start (`cold_start`; `-- --cold-start` runs only it): a fresh process's time from its
//! start to its first verified hypothesis (the sphere:100 in label mode against the sensed
//! scene, which it renders first), with an empty pipeline cache and then with the cache the
//! first process left (src/gpu/pipeline_cache.rs), in the same run.
//!
//! Run: `cargo run --release --example bench_verify` (add `-- --quick` for a short run).
//! RANGESYNTH_DEVICE picks the device.

use glam::{DMat4, DVec3};
use rangesynth::effects::Effects;
use rangesynth::gpu::ContextOptions;
use rangesynth::io::RangeImage;
use rangesynth::limits::Ledger;
use rangesynth::render::{Raster, COVERAGE_MEMBERS};
use rangesynth::scene::Scene;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, Verifier, VerifySettings};
use rangesynth::Renderer;
use std::path::Path;
use std::time::Instant;

const SENSED: &str = include_str!("../docs/example/sensed.toml");

fn main() -> anyhow::Result<()> {
    if std::env::args().any(|a| a == FIRST_HYPOTHESIS) {
        return first_hypothesis();
    }
    let quick = std::env::args().any(|a| a == "--quick");
    if std::env::args().any(|a| a == "--cold-start") {
        return cold_start();
    }
    let verifier = Verifier::new(Renderer::new(&ContextOptions::from_env())?.with_raster(Raster::Graphics))?;
    let scene = Scene::from_toml(SENSED, Path::new("."), &Ledger::default())?;
    let image = RangeImage::from(&verifier.renderer().render(&scene)?);
    let sensed = SensedImage::new(&image, &scene.sensor)?;
    println!("device: {}", verifier.renderer().context().device_name());
    println!("sensed image: {}×{}, {} valid pixels", sensed.width, sensed.height, sensed.valid);
    let compute = Verifier::new(Renderer::new(&ContextOptions::from_env())?.with_raster(Raster::Compute))?;
    // First, before other tables leave freed memory resident.
    memory_by_batch(&[&verifier, &compute], &sensed, &scene, quick)?;
    if std::env::args().any(|a| a == "--rigs") {
        return rig_costs([&verifier, &compute], &sensed, &scene);
    }
    if std::env::args().any(|a| a == "--rasters") {
        raster_costs(&[&verifier, &compute], &sensed, &scene, quick)?;
        grouping_costs(&sensed, &scene, quick)?;
        return filling_costs(&[&verifier, &compute], quick);
    }
    println!(
        "{:<22} {:>6} {:>6} {:>14} {:>16} {:>8}",
        "model (triangles)", "shadow", "batch", "batched hyp/s", "one-by-one hyp/s", "ratio"
    );
    let batches: &[usize] = if quick { &[1, 64] } else { &[1, 64, 1024] };
    for model_name in ["builtin:box", "builtin:sphere:100"] {
        let model = verifier.model(model_name, Path::new("."))?;
        for shadow in [ShadowMode::Depth, ShadowMode::None] {
            let settings = settings(scene.sensor.clone(), shadow);
            for &n in batches {
                let hypotheses = hypotheses(&model, n);
                // Warm up (pipelines, shader compilation in software drivers).
                verifier.verify(&sensed, &settings, &hypotheses[..1], &mut |_| {})?;
                let start = Instant::now();
                let batched = verifier.verify(&sensed, &settings, &hypotheses, &mut |_| {})?;
                let batched_rate = n as f64 / start.elapsed().as_secs_f64();
                let start = Instant::now();
                for h in &hypotheses {
                    verifier.verify(&sensed, &settings, std::slice::from_ref(h), &mut |_| {})?;
                }
                let single_rate = n as f64 / start.elapsed().as_secs_f64();
                assert_eq!(batched.len(), n);
                println!(
                    "{:<22} {:>6} {:>6} {:>14.1} {:>16.1} {:>7.2}×",
                    format!("{model_name} ({})", model.mesh.triangles.len()),
                    shadow.as_str(),
                    n,
                    batched_rate,
                    single_rate,
                    batched_rate / single_rate
                );
            }
        }
    }
    effect_costs(&verifier, &sensed, &scene)?;
    cold_start()?;
    rig_costs([&verifier, &compute], &sensed, &scene)?;
    raster_costs(&[&verifier, &compute], &sensed, &scene, quick)?;
    filling_costs(&[&verifier, &compute], quick)
}

/// This process's resident memory before and at its peak while each rasterizer verifies
/// batches of growing size (memory freed by one call stays resident for the next): it may
/// grow up to one chunk (the submission's commands and per-hypothesis tables), and beyond it
/// only by the results returned. On lavapipe GPU memory is host memory, so this counts both;
/// on a discrete GPU only the host's. Linux only (the peak is reset through
/// /proc/self/clear_refs); elsewhere the table says so and the bench goes on.
fn memory_by_batch(verifiers: &[&Verifier], sensed: &SensedImage, scene: &Scene, quick: bool) -> anyhow::Result<()> {
    let model_name = "builtin:sphere:100";
    println!(
        "memory by batch size: {model_name}, depth-mode shadows, 256², resident MiB before → peak while verifying"
    );
    println!("{:>6} {:>16} {:>16}", "batch", "graphics MiB", "compute MiB");
    let settings = settings(scene.sensor.clone(), ShadowMode::Depth);
    let batches: &[usize] = if quick { &[16, 256] } else { &[16, 1024, 4096] };
    for &n in batches {
        let mut cells = Vec::new();
        for verifier in verifiers {
            let hypotheses = hypotheses(&verifier.model(model_name, Path::new("."))?, n);
            verifier.verify(sensed, &settings, &hypotheses[..1], &mut |_| {})?;
            let Some(before) = reset_peak_resident() else {
                println!("(not measured: needs Linux's /proc/self/clear_refs)");
                return Ok(());
            };
            verifier.verify(sensed, &settings, &hypotheses, &mut |_| {})?;
            let peak = resident_kib("VmHWM").unwrap_or(f64::NAN);
            cells.push(format!("{:.1} → {:.1}", before / 1024.0, peak / 1024.0));
        }
        println!("{n:>6} {:>16} {:>16}", cells[0], cells[1]);
    }
    Ok(())
}

/// Resets this process's peak resident memory to its current one, and returns that (KiB);
/// `None` where /proc cannot.
fn reset_peak_resident() -> Option<f64> {
    std::fs::write("/proc/self/clear_refs", "5").ok()?;
    resident_kib("VmRSS")
}

/// A KiB figure of /proc/self/status (`VmRSS`, `VmHWM`).
fn resident_kib(field: &str) -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let value = status.lines().find_map(|line| line.strip_prefix(field)?.strip_prefix(':'))?;
    value.split_whitespace().next()?.parse().ok()
}

/// Milliseconds per hypothesis with each rasterizer for a model filling the image: its own
/// render as the sensed image, 16 poses about the true one, with label-mode and depth-mode
/// shadows (the fastest of five batches each, the rasterizers in turn).
fn filling_costs(verifiers: &[&Verifier], quick: bool) -> anyhow::Result<()> {
    // The same two rasterizers timing their stages, for a breakdown under each row (apart:
    // the timestamps are left out of the rows' own timings).
    let timed: Vec<Verifier> = [Raster::Graphics, Raster::Compute]
        .into_iter()
        .map(|raster| {
            Ok(Verifier::new(Renderer::new(&ContextOptions::from_env())?.with_raster(raster))?.with_stage_times())
        })
        .collect::<rangesynth::Result<_>>()?;
    println!("\nrasterizers, a model filling the image: batches of 16, ms per hypothesis");
    println!(
        "{:<34} {:>6} {:>12} {:>12} {:>10}",
        "model (triangles), image", "shadow", "graphics ms", "compute ms", "speed-up"
    );
    // (model, image side, extent in model units): the box fills about 40% of the image.
    let workloads: &[(&str, u32, f64)] = if quick {
        &[("builtin:box", 256, 1.6), ("builtin:sphere:320", 256, 1.05)]
    } else {
        &[("builtin:box", 256, 1.6), ("builtin:sphere:320", 256, 1.05), ("builtin:sphere:320", 1024, 1.05)]
    };
    for &(model_name, side, extent) in workloads {
        for mode in [ShadowMode::Label, ShadowMode::Depth] {
            let sensor = rangesynth::sensor::Sensor::square(side, extent, 45.0);
            let settings = settings(sensor.clone(), mode);
            let mut triangles = 0;
            let mut inputs = Vec::new();
            for verifier in verifiers {
                let model = verifier.model(model_name, Path::new("."))?;
                triangles = model.mesh.triangles.len();
                let (at, hypotheses) = centred_hypotheses(&model);
                let scene = Scene {
                    sensor: sensor.clone(),
                    shadow: settings.shadow,
                    effects: Effects::default(),
                    objects: vec![rangesynth::scene::SceneObject {
                        model_ref: model_name.into(),
                        mesh: model.mesh.clone(),
                        pose: at,
                        reflectivity: None,
                    }],
                };
                let sensed = SensedImage::new(&RangeImage::from(&verifiers[0].renderer().render(&scene)?), &sensor)?;
                verifier.verify(&sensed, &settings, &hypotheses[..1], &mut |_| {})?;
                inputs.push((sensed, hypotheses));
            }
            let jobs: Vec<_> = verifiers
                .iter()
                .zip(&inputs)
                .map(|(verifier, (sensed, hypotheses))| {
                    let settings = &settings;
                    move || verifier.verify(sensed, settings, hypotheses, &mut |_| {}).map(drop)
                })
                .collect();
            let seconds = fastest_in_turn(ROUNDS, &jobs)?;
            let millis: Vec<f64> = seconds.iter().map(|s| s * 1e3 / 16.0).collect();
            let name = format!("{model_name} ({triangles}), {side}²");
            println!(
                "{name:<34} {:>6} {:>12.2} {:>12.2} {:>9.2}×",
                mode.as_str(),
                millis[0],
                millis[1],
                millis[0] / millis[1]
            );
            for (verifier, (sensed, _)) in timed.iter().zip(&inputs) {
                println!("    {}", stage_breakdown(verifier, model_name, sensed, &settings)?);
            }
        }
    }
    Ok(())
}

/// The pose that centres a model's bounding sphere on the image (x, y), and 16 hypotheses of
/// it turned about z by 0.002 rad each.
fn centred_hypotheses(model: &std::sync::Arc<rangesynth::verify::Model>) -> (DMat4, Vec<Hypothesis>) {
    let (centre, _) = model.mesh.bounding_sphere();
    let at = DMat4::from_translation(DVec3::new(-centre.x, -centre.y, 0.0));
    let hypotheses = (0..16)
        .map(|i| Hypothesis {
            id: format!("h{i}"),
            model: model.clone(),
            pose: DMat4::from_rotation_z(0.002 * i as f64) * at,
            bindings: vec![(1, 1)],
        })
        .collect();
    (at, hypotheses)
}

/// A verifier's GPU time by stage (`Verifier::with_stage_times`), ms a hypothesis, over one
/// batch of 16 of the model about the image's centre.
fn stage_breakdown(
    verifier: &Verifier,
    model_name: &str,
    sensed: &SensedImage,
    settings: &VerifySettings,
) -> anyhow::Result<String> {
    let (_, hypotheses) = centred_hypotheses(&verifier.model(model_name, Path::new("."))?);
    let stages = stage_times(verifier, sensed, settings, &hypotheses, 16.0)?;
    Ok(format!("{} stages: {}", verifier.renderer().raster().as_str(), listed(&stages)))
}

/// Stage times as `name ms, name ms, …`.
fn listed(stages: &[(&str, f64)]) -> String {
    stages.iter().map(|(name, ms)| format!("{name} {ms:.2}")).collect::<Vec<_>>().join(", ")
}

/// A verifier's GPU time by stage (`Verifier::with_stage_times`), ms, over one verification of
/// `hypotheses` after one hypothesis to warm up, divided by `per` (hypotheses, or chunks'
/// lengths of hypotheses).
fn stage_times(
    verifier: &Verifier,
    sensed: &SensedImage,
    settings: &VerifySettings,
    hypotheses: &[Hypothesis],
    per: f64,
) -> anyhow::Result<Vec<(&'static str, f64)>> {
    verifier.verify(sensed, settings, &hypotheses[..1], &mut |_| {})?;
    verifier.take_stage_times();
    verifier.verify(sensed, settings, hypotheses, &mut |_| {})?;
    Ok(verifier.take_stage_times().into_iter().map(|(name, ms)| (name, ms / per)).collect())
}

/// Hypotheses per second with each rasterizer, depth-mode shadows, batches of 64.
fn raster_costs(verifiers: &[&Verifier], sensed: &SensedImage, scene: &Scene, quick: bool) -> anyhow::Result<()> {
    println!("\nrasterizers: depth-mode shadows, batches of 64 at {}×{}", sensed.width, sensed.height);
    // What `auto` takes on this device (Renderer::crossover), beside what ran faster.
    let crossover = verifiers[0].renderer().crossover();
    println!("auto's crossover on this device: compute for {crossover}");
    println!(
        "{:<26} {:>9} {:>14} {:>14} {:>10} {:>9}",
        "model (triangles)", "tri/px", "graphics hyp/s", "compute hyp/s", "ratio", "auto"
    );
    let models: &[&str] = if quick {
        &["builtin:box", "builtin:sphere:100"]
    } else {
        &[
            "builtin:box",
            "builtin:sphere:8",
            "builtin:sphere:16",
            "builtin:sphere:24",
            "builtin:sphere:32",
            // 1,224 and 1,520 triangles: either side of a GPU crossover's 1,500 (Crossover::GPU).
            "builtin:sphere:36",
            "builtin:sphere:40",
            "builtin:sphere:48",
            "builtin:sphere:64",
            "builtin:sphere:100",
            "builtin:sphere:320",
        ]
    };
    for model_name in models {
        let settings = settings(scene.sensor.clone(), ShadowMode::Depth);
        let mut triangles = 0;
        let mut density = 0.0;
        let mut footprint = 0;
        let mut batches = Vec::new();
        for verifier in verifiers {
            let model = verifier.model(model_name, Path::new("."))?;
            triangles = model.mesh.triangles.len();
            // Triangles per pixel of the footprint each hypothesis renders (what `auto` reads).
            let (centre, radius) = model.mesh.bounding_sphere();
            let grid = scene.sensor.scanner().expect("the scanner").range_grid((0.0, 0.0));
            let area =
                grid.footprint(hypotheses(&model, 1)[0].pose.transform_point3(centre), radius, 2).expect("in view");
            footprint = u64::from(area.width) * u64::from(area.height);
            density = triangles as f64 / footprint as f64;
            let hypotheses = hypotheses(&model, 64);
            verifier.verify(sensed, &settings, &hypotheses[..1], &mut |_| {})?;
            batches.push(hypotheses);
        }
        let rates = rates_in_turn(verifiers, sensed, &settings, &batches)?;
        let name = format!("{model_name} ({triangles})");
        let auto = if crossover.takes_compute(triangles as u64, footprint) { "compute" } else { "graphics" };
        println!(
            "{name:<26} {density:>9.3} {:>14.1} {:>14.1} {:>9.2}× {auto:>9}",
            rates[0],
            rates[1],
            rates[1] / rates[0]
        );
    }
    Ok(())
}

/// Hypotheses per second with the compute rasterizer covering one hypothesis a coverage
/// dispatch or COVERAGE_MEMBERS, in runs of 4 slots, 16 or 64 (`Verifier::with_slots`: one
/// barrier a stage for each run), one to four chunks in flight
/// (`Verifier::with_chunks_in_flight`: chunks recorded while the device runs another),
/// label-mode shadows at 256², in chunks of 1,024 on a GPU (the goal there: 100,000 a
/// second for a 10k-triangle model) and of 64 on a CPU device, batches of four chunks or two a
/// chunk in flight, so that every configuration runs chunks of one size (until 2026-11-26's
/// third session, batches of four chunks, which more lanes split into shorter ones).
fn grouping_costs(sensed: &SensedImage, scene: &Scene, quick: bool) -> anyhow::Result<()> {
    // (hypotheses a coverage dispatch, slots, chunks in flight): lavapipe's defaults, then
    // the GPU's with runs of four, then sixteen, then two, three and four chunks in flight,
    // then runs of 64 with two and four.
    let configurations = [
        (1, 4, 1),
        (COVERAGE_MEMBERS, 4, 1),
        (COVERAGE_MEMBERS, 16, 1),
        (COVERAGE_MEMBERS, 16, 2),
        (COVERAGE_MEMBERS, 16, 3),
        (COVERAGE_MEMBERS, 16, 4),
        (COVERAGE_MEMBERS, 64, 2),
        (COVERAGE_MEMBERS, 64, 4),
    ];
    let configured = |(members, slots, chunks): (usize, usize, usize)| -> rangesynth::Result<Verifier> {
        let renderer = Renderer::new(&ContextOptions::from_env())?.with_raster(Raster::Compute);
        let verifier = Verifier::new(renderer.with_hypotheses_per_dispatch(members))?;
        Ok(verifier.with_slots(slots).with_chunks_in_flight(chunks))
    };
    let verifiers: Vec<Verifier> = configurations.into_iter().map(configured).collect::<rangesynth::Result<_>>()?;
    // The third configuration (one chunk in flight) and the fifth (a GPU's default, three)
    // again, timing their stages on the device (which costs a little): with one chunk in
    // flight the device waits for the host's recording, with three it need not.
    let timed: Vec<(usize, Verifier)> = [2, 4]
        .into_iter()
        .map(|index| Ok((index, configured(configurations[index])?.with_stage_times())))
        .collect::<rangesynth::Result<_>>()?;
    // Chunks of 1,024 on a GPU; on a CPU device, fewer keep the run short.
    let chunk = match (quick, verifiers[0].renderer().context().is_cpu()) {
        (true, _) => 16,
        (false, true) => 64,
        (false, false) => 1024,
    };
    // Batches of four chunks, or two a lane where there are more lanes: a call goes in at least
    // two chunks a lane (verify/lanes.rs), so that every configuration runs chunks of up to
    // `chunk` (in lanes, a call's first chunks ramp up to it).
    let batch_of = |(_, _, chunks): (usize, usize, usize)| chunk * (2 * chunks).max(4);
    println!(
        "\ncompute rasterizer, hypotheses a coverage dispatch × slots a run × chunks in flight: label-mode shadows, \
         chunks of up to {chunk}, batches of four chunks or two a chunk in flight"
    );
    let names: String = configurations
        .iter()
        .map(|(members, slots, chunks)| format!(" {:>14}", format!("{members}×{slots}×{chunks} hyp/s")))
        .collect();
    println!("{:<26}{names} {:>40} {:>34}", "model (triangles)", "barriers a hyp.", "recording µs a hyp.");
    let settings = VerifySettings { chunk_size: chunk, ..settings(scene.sensor.clone(), ShadowMode::Label) };
    for model_name in ["builtin:box", "builtin:sphere:100", "builtin:sphere:320"] {
        let mut batches = Vec::new();
        for (verifier, &configuration) in verifiers.iter().zip(&configurations) {
            let hypotheses = hypotheses(&verifier.model(model_name, Path::new("."))?, batch_of(configuration));
            verifier.verify(sensed, &settings, &hypotheses[..1], &mut |_| {})?;
            batches.push(hypotheses);
        }
        let rates_by_configuration = rates_in_turn(&verifiers.iter().collect::<Vec<_>>(), sensed, &settings, &batches)?;
        // Barriers a GPU waits at, and the host's time recording command buffers (which chunks
        // in flight overlap with the device's work), a hypothesis: over one more batch of each
        // (more chunks in flight add no barriers: a configuration's barriers are its runs').
        let (mut barriers, mut recording) = (Vec::new(), Vec::new());
        for (verifier, hypotheses) in verifiers.iter().zip(&batches) {
            let context = verifier.renderer().context();
            let before = (context.barriers_recorded(), context.recording_time());
            verifier.verify(sensed, &settings, hypotheses, &mut |_| {})?;
            let n = hypotheses.len() as f64;
            barriers.push(format!("{:.2}", (context.barriers_recorded() - before.0) as f64 / n));
            recording.push(format!("{:.1}", (context.recording_time() - before.1).as_secs_f64() * 1e6 / n));
        }
        let name = format!("{model_name} ({})", batches[0][0].model.mesh.triangles.len());
        let (barriers, recording) = (barriers.join(" / "), recording.join(" / "));
        let rates: String = rates_by_configuration.iter().map(|rate| format!(" {rate:>14.1}")).collect();
        println!("{name:<26}{rates} {barriers:>40} {recording:>34}");
        for (index, verifier) in &timed {
            let (members, slots, chunks) = configurations[*index];
            // Its own model: a verifier's meshes live on its own device.
            let batch = batch_of(configurations[*index]);
            let timed_batch = hypotheses(&verifier.model(model_name, Path::new("."))?, batch);
            let stages = stage_times(verifier, sensed, &settings, &timed_batch, batch.div_ceil(chunk) as f64)?;
            let total: f64 = stages.iter().map(|(_, ms)| ms).sum();
            // Wall time a chunk's length of hypotheses, from this configuration's rate (in
            // lanes, a call's first chunks are shorter: verify/lanes.rs).
            let wall = chunk as f64 / rates_by_configuration[*index] * 1e3;
            let shape = format!("{members}×{slots}×{chunks}");
            println!(
                "    {shape}, ms a {chunk} hypotheses: {wall:.2} in all; the device's {total:.2} ({})",
                listed(&stages)
            );
        }
    }
    Ok(())
}

/// Hypotheses per second of each verifier verifying its batch: the fastest of ROUNDS, the
/// verifiers in turn.
fn rates_in_turn(
    verifiers: &[&Verifier],
    sensed: &SensedImage,
    settings: &VerifySettings,
    batches: &[Vec<Hypothesis>],
) -> anyhow::Result<Vec<f64>> {
    let jobs: Vec<_> = verifiers
        .iter()
        .zip(batches)
        .map(|(verifier, hypotheses)| move || verifier.verify(sensed, settings, hypotheses, &mut |_| {}).map(drop))
        .collect();
    Ok(fastest_in_turn(ROUNDS, &jobs)?.iter().zip(batches).map(|(s, batch)| batch.len() as f64 / s).collect())
}

/// Batches each rasterizer verifies in the rasterizer tables, in turn.
const ROUNDS: usize = 5;

/// The fastest of `rounds` timings (seconds) of each job, the jobs taken in turn (the first,
/// the second, the first, …), so that a change in this shared machine's load touches each
/// alike: timed one after the other, a ratio moved by up to ±30% from run to run.
fn fastest_in_turn(rounds: usize, jobs: &[impl Fn() -> rangesynth::Result<()>]) -> anyhow::Result<Vec<f64>> {
    let mut fastest = vec![f64::INFINITY; jobs.len()];
    for _ in 0..rounds {
        for (job, fastest) in jobs.iter().zip(&mut fastest) {
            let start = Instant::now();
            job()?;
            *fastest = fastest.min(start.elapsed().as_secs_f64());
        }
    }
    Ok(fastest)
}

/// Verification in shadow mode `mode` without effects, τ = 0.1, in chunks of 1,024.
fn settings(sensor: rangesynth::sensor::Sensor, mode: ShadowMode) -> VerifySettings {
    VerifySettings {
        sensor,
        shadow: ShadowSettings::of(mode),
        effects: Effects::default(),
        tolerance: 0.1,
        compare_shadow: false,
        chunk_size: 1024,
    }
}

/// `n` poses of `model` about the sensed step's, turning by 0.002 rad each.
fn hypotheses(model: &std::sync::Arc<rangesynth::verify::Model>, n: usize) -> Vec<Hypothesis> {
    (0..n)
        .map(|i| {
            let a = i as f64 * 0.002;
            let pose = DMat4::from_translation(DVec3::new(0.3, -0.2, 0.0)) * DMat4::from_rotation_z(0.44 + a);
            Hypothesis { id: format!("h{i}"), model: model.clone(), pose, bindings: vec![(1, 1), (2, 1)] }
        })
        .collect()
}

/// A pinhole rig beside the paper's scanner on the same triangles and pixel count: the
/// sphere:100 at 256², a batch of 64, in shadow modes `depth` and `label` (a rig's images drawn
/// on the GPU; docs/sensors-and-rigs.md, "What renders a rig"). The rig is a 256² camera whose
/// pixel covers the scanner's pitch at the model's depth (fx = 5 / 0.02) and a projector as far
/// to its side as the model is deep (the 45° the scanner's θ gives), and also the camera with a
/// lamp in the projector's direction (a directional witness, its image planned for each
/// hypothesis); each hypothesis is the scanner's turned to face the camera 5 units away. Each
/// with the graphics pipeline and the compute rasterizer (`verifiers`), each against the
/// scanner with the same rasterizer, and compute against graphics.
fn rig_costs(verifiers: [&Verifier; 2], sensed: &SensedImage, scene: &Scene) -> anyhow::Result<()> {
    let verifier = verifiers[0];
    use rangesynth::sensor::{Direction, Intrinsics, Pinhole, Sensor, View, Witness, WitnessGeometry};
    let model = verifier.model("builtin:sphere:100", Path::new("."))?;
    let k = Intrinsics { width: 256, height: 256, fx: 250.0, fy: 250.0, cx: 127.5, cy: 127.5 };
    let projector = Witness {
        name: "projector".into(),
        geometry: WitnessGeometry::Pinhole {
            pose: DMat4::from_translation(DVec3::new(5.0, 0.0, 0.0))
                * DMat4::from_rotation_y(-std::f64::consts::FRAC_PI_4),
            intrinsics: k,
        },
    };
    let rig = Sensor {
        reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY }),
        witnesses: vec![projector],
    };
    // The projector's direction as a distant lamp (a directional witness).
    let lamp = Witness {
        name: "lamp".into(),
        geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::new(1.0, 0.0, -1.0).normalize())),
    };
    let lamp_rig = Sensor { witnesses: vec![lamp], ..rig.clone() };
    let facing = DMat4::from_translation(DVec3::new(0.0, 0.0, 5.0)) * DMat4::from_rotation_x(std::f64::consts::PI);
    let scanner_hypotheses = hypotheses(&model, 64);
    let rig_hypotheses: Vec<Hypothesis> =
        scanner_hypotheses.iter().map(|h| Hypothesis { pose: facing * h.pose, ..h.clone() }).collect();
    let rig_scene = Scene {
        sensor: rig.clone(),
        objects: scene
            .objects
            .iter()
            .map(|o| rangesynth::scene::SceneObject { pose: facing * o.pose, ..o.clone() })
            .collect(),
        ..scene.clone()
    };
    let rig_sensed = SensedImage::new(&RangeImage::from(&verifier.renderer().render(&rig_scene)?), &rig)?;
    println!("a pinhole rig beside the scanner: sphere:100, 256², a batch of 64, with each rasterizer");
    println!(
        "{:<34} {:>13} {:>10} {:>13} {:>10} {:>9}",
        "sensor, shadow mode", "graphics hyp/s", "vs scanner", "compute hyp/s", "vs scanner", "compute÷"
    );
    let rate = |verifier: &Verifier, sensed: &SensedImage, settings: &VerifySettings, batch: &[Hypothesis]| {
        verifier.verify(sensed, settings, &batch[..1], &mut |_| {})?;
        let start = Instant::now();
        verifier.verify(sensed, settings, batch, &mut |_| {})?;
        anyhow::Ok(batch.len() as f64 / start.elapsed().as_secs_f64())
    };
    // Each mode's pair in turn, the scanner's rate the ratio's base: the fastest of three
    // runs each, taken by turns (this machine's runs vary by up to a third).
    let lamp_sensed = SensedImage::new(
        &RangeImage::from(&verifier.renderer().render(&Scene { sensor: lamp_rig.clone(), ..rig_scene.clone() })?),
        &lamp_rig,
    )?;
    for mode in [ShadowMode::Depth, ShadowMode::Label] {
        // [sensor][rasterizer]: the scanner, camera + projector, camera + lamp.
        let mut rates = [[0.0f64; 2]; 3];
        for _ in 0..3 {
            for (r, verifier) in verifiers.into_iter().enumerate() {
                let runs = [
                    (sensed, settings(scene.sensor.clone(), mode), &scanner_hypotheses),
                    (&rig_sensed, settings(rig.clone(), mode), &rig_hypotheses),
                    (&lamp_sensed, settings(lamp_rig.clone(), mode), &rig_hypotheses),
                ];
                for (k, (sensed, settings, batch)) in runs.iter().enumerate() {
                    rates[k][r] = rates[k][r].max(rate(verifier, sensed, settings, batch)?);
                }
            }
        }
        for (k, who) in ["the scanner", "camera + projector", "camera + lamp"].into_iter().enumerate() {
            let [graphics, compute] = rates[k];
            let [scanner_graphics, scanner_compute] = rates[0];
            println!(
                "{:<34} {:>13.1} {:>9.2}× {:>13.1} {:>9.2}× {:>8.2}×",
                format!("{who}, {}", mode.as_str()),
                graphics,
                graphics / scanner_graphics,
                compute,
                compute / scanner_compute,
                compute / graphics
            );
        }
    }
    Ok(())
}

/// Each effect's cost per hypothesis, against no effects.
fn effect_costs(verifier: &Verifier, sensed: &SensedImage, scene: &Scene) -> anyhow::Result<()> {
    let model = verifier.model("builtin:box", Path::new("."))?;
    let hypotheses = hypotheses(&model, 64);
    let cases = [
        ("none", ""),
        ("grazing", "[grazing]\nmax_incidence_deg = 70"),
        ("range", "[range]\nmin_z = 0.1\nmax_z = 1.0"),
        ("reflectivity", "[reflectivity]\nthreshold = 0.5"),
        ("edges (1 px)", "[edges]\njump = 0.1\nwidth_px = 1"),
        ("edges (3 px)", "[edges]\njump = 0.1\nwidth_px = 3"),
        ("dropout", "[dropout]\nprobability = 0.1"),
        ("noise", "[noise]\nsigma = 0.002"),
        ("quantize", "[quantize]\nz_step = 0.001"),
    ];
    // Every effect once (the 1-pixel edge filter).
    let all = cases.iter().filter(|(name, _)| *name != "edges (3 px)").map(|(_, text)| *text).collect::<Vec<_>>();
    let all = all.join("\n");
    println!("\neffects: builtin:box, depth-mode shadows, batches of 64 at {}×{}", sensed.width, sensed.height);
    println!("{:<14} {:>12} {:>10}", "effect", "ms/hyp", "vs none");
    let mut baseline = None;
    for (name, text) in cases.iter().copied().chain([("all", all.as_str())]) {
        let effects: Effects = toml::from_str(text)?;
        let settings = VerifySettings { effects, ..settings(scene.sensor.clone(), ShadowMode::Depth) };
        verifier.verify(sensed, &settings, &hypotheses[..1], &mut |_| {})?;
        let mut best = f64::INFINITY;
        for _ in 0..5 {
            let start = Instant::now();
            verifier.verify(sensed, &settings, &hypotheses, &mut |_| {})?;
            best = best.min(start.elapsed().as_secs_f64() * 1e3 / hypotheses.len() as f64);
        }
        let none = *baseline.get_or_insert(best);
        println!("{name:<14} {best:>12.3} {:>9.2}×", best / none);
    }
    Ok(())
}

/// The argument that makes this program the process `cold_start` times.
const FIRST_HYPOTHESIS: &str = "--first-hypothesis";

/// What a process started cold does before its first result: start Vulkan (with the pipeline
/// cache `RANGESYNTH_CACHE_DIR` names), render the sensed scene, verify one hypothesis; then
/// it says so on a line of its own.
fn first_hypothesis() -> anyhow::Result<()> {
    let verifier = Verifier::new(Renderer::new(&ContextOptions::from_env())?)?;
    let scene = Scene::from_toml(SENSED, Path::new("."), &Ledger::default())?;
    let image = RangeImage::from(&verifier.renderer().render(&scene)?);
    let sensed = SensedImage::new(&image, &scene.sensor)?;
    let model = verifier.model("builtin:sphere:100", Path::new("."))?;
    let scores =
        verifier.verify(&sensed, &settings(scene.sensor, ShadowMode::Label), &hypotheses(&model, 1), &mut |_| {})?;
    anyhow::ensure!(scores.len() == 1, "one hypothesis verified");
    println!("verified");
    Ok(())
}

/// Milliseconds from starting this program as a [`first_hypothesis`] process with its
/// pipeline cache in `cache_dir` to its first line (with an empty cache, that includes
/// writing it as the pipelines are built; its teardown is not counted).
fn time_to_first_hypothesis(cache_dir: &Path) -> anyhow::Result<f64> {
    use std::io::BufRead;
    let start = Instant::now();
    let mut child = std::process::Command::new(std::env::current_exe()?)
        .arg(FIRST_HYPOTHESIS)
        .env(rangesynth::gpu::CACHE_DIR_ENV, cache_dir)
        .stdout(std::process::Stdio::piped())
        .spawn()?;
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().expect("piped")).read_line(&mut line)?;
    let elapsed = start.elapsed().as_secs_f64() * 1e3;
    anyhow::ensure!(child.wait()?.success() && line.trim() == "verified", "the cold-start process failed");
    Ok(elapsed)
}

/// Process start to first verified hypothesis, with an empty pipeline cache and then three
/// times with the one the first process left (their best). A driver's own shader cache
/// (Mesa's, NVIDIA's) is left as it is: what it saves shows in both rows alike.
fn cold_start() -> anyhow::Result<()> {
    let dir = tempfile::tempdir()?;
    let empty = time_to_first_hypothesis(dir.path())?;
    let warm = (0..3).map(|_| time_to_first_hypothesis(dir.path())).collect::<anyhow::Result<Vec<f64>>>()?;
    let warm = warm.into_iter().fold(f64::INFINITY, f64::min);
    println!("\nprocess start to first verified hypothesis (sphere:100, label mode, 256²):");
    println!("  empty pipeline cache {empty:.0} ms, warm {warm:.0} ms ({:.2}× the empty one's time)", warm / empty);
    Ok(())
}
