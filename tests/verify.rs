//! Verification on the GPU against the independent CPU scorer (tests/common/scorer.rs), batch
//! invariance, and the paper's claims on a synthetic scene: the correct hypothesis outscores a
//! wrong model and a wrong pose, and shadowing raises its score.

mod common;

use common::scorer::{as_cpu, cpu_counts, cpu_scores, Images};
use common::*;
use glam::{DMat4, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangesynth::io::RangeImage;
use rangesynth::limits::{MemoryBudget, DEFAULT_MEMORY_BUDGET};
use rangesynth::render::Raster;
use rangesynth::sensor::{Scanner, Sensor};
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, Model, SensedImage, Verification, Verifier, VerifySettings};
use std::path::Path;
use std::sync::Arc;

const TOLERANCE: f64 = 0.05;

fn step_pose() -> DMat4 {
    DMat4::from_translation(DVec3::new(0.3, -0.2, 0.0)) * DMat4::from_rotation_z(25f64.to_radians())
}

fn test_sensor(theta: f64) -> Scanner {
    centred_sensor(128, 128, 0.035, [0.0, 0.0], theta)
}

/// The sensed image: the stepped block, rendered with exact-enough (depth-mode) shadows.
fn sensed(sensor: impl Into<Sensor>) -> (RangeImage, SensedImage) {
    let sensor = sensor.into();
    let out = render(&scene(sensor.clone(), ShadowMode::Depth, &[("builtin:step", step_pose())]));
    let image = RangeImage::from(&out);
    let sensed = SensedImage::new(&image, &sensor).expect("valid sensed image");
    (image, sensed)
}

fn hypothesis(id: &str, model: &str, pose: DMat4, bindings: &[(u32, u32)]) -> Hypothesis {
    Hypothesis {
        id: id.into(),
        model: VERIFIER.model(model, Path::new(".")).unwrap(),
        pose,
        bindings: bindings.to_vec(),
    }
}

/// The step, as the test binary's verifier loaded it.
fn step_model() -> Arc<Model> {
    VERIFIER.model("builtin:step", Path::new(".")).unwrap()
}

/// The step's surfaces are labels 1..=8 in the sensed image: the correct binding is identity.
fn correct() -> Hypothesis {
    hypothesis("correct", "builtin:step", step_pose(), &(1..=8).map(|l| (l, l)).collect::<Vec<_>>())
}

/// `n` hypotheses of `model`: the step's pose turned about z by `step` radians more each,
/// with these bindings.
fn turning(model: &Arc<Model>, n: usize, step: f64, bindings: &[(u32, u32)]) -> Vec<Hypothesis> {
    (0..n)
        .map(|i| Hypothesis {
            id: format!("h{i}"),
            model: model.clone(),
            pose: step_pose() * DMat4::from_rotation_z(step * i as f64),
            bindings: bindings.to_vec(),
        })
        .collect()
}

fn settings(sensor: impl Into<Sensor>, shadow: ShadowMode) -> VerifySettings {
    VerifySettings {
        sensor: sensor.into(),
        shadow: ShadowSettings::of(shadow),
        effects: Effects::default(),
        tolerance: TOLERANCE,
        compare_shadow: false,
        chunk_size: 1024,
    }
}

fn verify(sensed: &SensedImage, settings: &VerifySettings, hypotheses: &[Hypothesis]) -> Vec<Verification> {
    let out = VERIFIER.verify(sensed, settings, hypotheses, &mut |_| {}).expect("verification runs");
    assert_no_validation_messages();
    out
}

fn assert_close(name: &str, gpu: f64, cpu: f64) {
    assert!(gpu.is_finite(), "{name}: {gpu}");
    let scale = gpu.abs().max(cpu.abs()).max(f64::MIN_POSITIVE);
    assert!((gpu - cpu).abs() <= 1e-12 * scale, "{name}: GPU {gpu} vs CPU {cpu}");
}

#[test]
fn gpu_counts_and_scores_match_the_cpu_scorer() {
    for (theta, mode) in [
        (45.0, ShadowMode::Depth),
        (45.0, ShadowMode::Label),
        (30.0, ShadowMode::None),
        (-30.0, ShadowMode::Depth),
        (45.0, ShadowMode::Exact),
    ] {
        let sensor = test_sensor(theta);
        let (image, sensed) = sensed(sensor);
        let wrong_pose =
            step_pose() * DMat4::from_rotation_z(0.3) * DMat4::from_translation(DVec3::new(0.2, 0.1, 0.05));
        let hypotheses = [
            correct(),
            hypothesis("wrong pose", "builtin:step", wrong_pose, &[(1, 1), (2, 2), (3, 3)]),
            hypothesis("wrong model", "builtin:box", step_pose(), &[(1, 1), (2, 2)]),
            hypothesis(
                "sphere",
                "builtin:sphere:24",
                DMat4::from_translation(DVec3::new(-0.5, 0.2, 0.3)),
                &[(1, 1), (9, 1)],
            ),
            // Past the image's bottom-right corner: the score pass's last column and row.
            hypothesis("at the corner", "builtin:box", DMat4::from_translation(DVec3::new(2.1, -2.1, 0.0)), &[(1, 1)]),
        ];
        // With the unshadowed image scored as well (`--compare-shadow`), checked the same way.
        let settings = VerifySettings { compare_shadow: true, ..settings(sensor, mode) };
        let results = verify(&sensed, &settings, &hypotheses);
        for (h, v) in common::paired(&hypotheses, &results) {
            let synthetic = render(&scene(sensor, mode, &[(h.model.mesh.name.as_str(), h.pose)]));
            let name = format!("{} ({mode:?}, θ = {theta})", h.id);
            let shadowed = Images::of(&image, &synthetic);
            let unshadowed = Images { synthetic_label: &synthetic.label_unshadowed, ..Images::of(&image, &synthetic) };
            let shadow_pass = synthetic.shadow_pass;
            assert!(!shadow_pass || v.unshadowed.is_some(), "{name}: an unshadowed score where a shadow pass ran");
            let scored = std::iter::once(("", &shadowed, &v.counts, &v.scores))
                .chain(v.unshadowed.as_ref().map(|(counts, scores)| (" unshadowed", &unshadowed, counts, scores)));
            for (which, images, counts, scores) in scored {
                let cpu = cpu_counts(images, TOLERANCE as f32);
                assert_eq!(as_cpu(counts, &sensed, sensed.valid), cpu, "{name}{which}: counts");
                assert!(cpu.n_s > 0 || h.id == "sphere", "{name}{which}: the model is in view");
                let expected = cpu_scores(&cpu, &h.bindings);
                let s = scores;
                for (k, (gpu, cpu)) in [s.s1, s.s2, s.s3, s.s4, s.s5, s.s6, s.s].iter().zip(expected).enumerate() {
                    assert_close(&format!("{name}{which} score {k}"), *gpu, cpu);
                }
            }
        }
    }
}

/// A sensed image's debug text says whether a verification has put a copy of it on the
/// device, and names that copy without its contents.
#[test]
fn a_sensed_images_debug_text_shows_its_device_copy_once_made() {
    let sensor = test_sensor(45.0);
    let (_, sensed) = sensed(sensor);
    assert!(!format!("{sensed:?}").contains("SensedGpu"), "no copy yet");
    verify(&sensed, &settings(sensor, ShadowMode::Label), &[correct()]);
    assert!(format!("{sensed:?}").contains("SensedGpu"), "the copy a verification made");
}

#[test]
fn correct_hypothesis_outscores_a_wrong_model_and_a_wrong_pose_and_shadowing_raises_it() {
    let sensor = test_sensor(45.0);
    let (_, sensed) = sensed(sensor);
    let wrong_pose = step_pose() * DMat4::from_rotation_z(0.15) * DMat4::from_translation(DVec3::new(0.1, 0.0, 0.0));
    let hypotheses = [
        correct(),
        hypothesis("wrong pose", "builtin:step", wrong_pose, &(1..=8).map(|l| (l, l)).collect::<Vec<_>>()),
        hypothesis("wrong model", "builtin:box", step_pose(), &[(1, 1), (2, 2)]),
    ];
    let settings = VerifySettings { compare_shadow: true, ..settings(sensor, ShadowMode::Depth) };
    let results = verify(&sensed, &settings, &hypotheses);
    let s: Vec<f64> = results.iter().map(|v| v.scores.s).collect();
    assert!(s[0] > 0.5, "the correct hypothesis scores high: {:?}", results[0].scores);
    assert!(s[0] > s[1] && s[0] > s[2], "correct {} vs wrong pose {} and wrong model {}", s[0], s[1], s[2]);
    let (_, unshadowed) = results[0].unshadowed.as_ref().expect("compare_shadow");
    assert!(
        s[0] > unshadowed.s && results[0].scores.s5 > unshadowed.s5 && results[0].scores.s6 > unshadowed.s6,
        "shadowing raises the correct score: {} (shadowed) vs {} (unshadowed)",
        s[0],
        unshadowed.s
    );
}

#[test]
fn a_hypothesis_scores_the_same_alone_or_in_any_batch() {
    let sensor = test_sensor(45.0);
    let (_, sensed) = sensed(sensor);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let models = ["builtin:step", "builtin:box", "builtin:cylinder:12", "builtin:sphere:16"];
    let mut hypotheses: Vec<Hypothesis> = (0..40)
        .map(|i| {
            let pose = DMat4::from_translation(DVec3::new(
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-0.5..0.5),
            )) * DMat4::from_rotation_z(rng.gen_range(0.0..6.3))
                * DMat4::from_rotation_x(rng.gen_range(-0.5..0.5));
            hypothesis(&format!("h{i}"), models[i % 4], pose, &[(1, 1), (2, 1)])
        })
        .collect();
    hypotheses.push(correct());
    let base = settings(sensor, ShadowMode::Depth);
    let alone: Vec<Verification> =
        hypotheses.iter().map(|h| verify(&sensed, &base, std::slice::from_ref(h)).remove(0)).collect();
    let same = |a: &Verification, b: &Verification| {
        assert_eq!(a.id, b.id);
        assert_eq!(a.counts, b.counts, "{}", a.id);
        assert_eq!(a.scores.s.to_bits(), b.scores.s.to_bits(), "{}", a.id);
    };
    for chunk_size in [1, 7, 1024] {
        let batch = verify(&sensed, &VerifySettings { chunk_size, ..base.clone() }, &hypotheses);
        common::paired(&alone, &batch).for_each(|(a, b)| same(a, b));
    }
    let reversed: Vec<Hypothesis> = hypotheses.iter().rev().cloned().collect();
    let batch = verify(&sensed, &base, &reversed);
    assert_eq!(alone.len(), batch.len());
    alone.iter().rev().zip(&batch).for_each(|(a, b)| same(a, b));
    // The sensed image's GPU copy is made once and kept: a clone shares it, and verifying
    // against another image in between changes nothing.
    let (_, other) = self::sensed(test_sensor(30.0));
    verify(&other, &settings(test_sensor(30.0), ShadowMode::Depth), &hypotheses[..3]);
    let batch = verify(&sensed.clone(), &base, &hypotheses);
    common::paired(&alone, &batch).for_each(|(a, b)| same(a, b));
}

#[test]
fn exact_mode_scores_the_same_alone_or_in_chunks() {
    let sensor = test_sensor(45.0);
    let (_, sensed) = sensed(sensor);
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let models = ["builtin:step", "builtin:box", "builtin:sphere:16"];
    let mut hypotheses: Vec<Hypothesis> = (0..19)
        .map(|i| {
            let pose = DMat4::from_translation(DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), 0.0))
                * DMat4::from_rotation_z(rng.gen_range(0.0..6.3));
            hypothesis(&format!("h{i}"), models[i % 3], pose, &[(1, 1), (2, 1)])
        })
        .collect();
    hypotheses.push(correct());
    let base = settings(sensor, ShadowMode::Exact);
    // 20 hypotheses: more than one exact-mode chunk (EXACT_CHUNK).
    assert!(hypotheses.len() > rangesynth::verify::EXACT_CHUNK);
    let batch = verify(&sensed, &VerifySettings { chunk_size: 1024, ..base.clone() }, &hypotheses);
    for (h, b) in common::paired(&hypotheses, &batch) {
        let alone = verify(&sensed, &base, std::slice::from_ref(h)).remove(0);
        assert_eq!(alone.counts, b.counts, "{}", h.id);
        assert_eq!(alone.scores.s.to_bits(), b.scores.s.to_bits(), "{}", h.id);
    }
    assert!(batch.last().unwrap().scores.s > 0.5, "the correct hypothesis scores high in exact mode");
}

#[test]
fn a_batch_of_1024_runs_in_chunks() {
    let sensor = centred_sensor(64, 64, 0.07, [0.0, 0.0], 45.0);
    let (_, sensed) = sensed(sensor);
    let hypotheses = turning(&step_model(), 1024, 0.001, &[(1, 1), (2, 2)]);
    let mut reports = Vec::new();
    let settings = VerifySettings { chunk_size: 256, ..settings(sensor, ShadowMode::Depth) };
    let results = VERIFIER.verify(&sensed, &settings, &hypotheses, &mut |done| reports.push(done)).unwrap();
    assert_no_validation_messages();
    // Chunks of 256; in lanes at least two chunks a lane, and the first chunks k = 0, 1, …
    // ramping up (src/verify/lanes.rs): (k + 1) eighths of the cap, no fewer than 64. Two lanes:
    // a cap of 256, chunks of 64, 64, 96, 128, 160, 192, 224, then 96 left. Three: a cap of
    // ⌈1024 / 6⌉ = 171, chunks of 64, 64, 64, 85, 106, 128, 149, 171, 171, then 22. Four: a cap
    // of 128, chunks of 64, 64, 64, 64, 80, 96, 112, 128, 128, 128, then 96 left.
    let chunks: Vec<usize> = match VERIFIER.chunks_in_flight() {
        1 => vec![256; 4],
        2 => vec![64, 64, 96, 128, 160, 192, 224, 96],
        3 => vec![64, 64, 64, 85, 106, 128, 149, 171, 171, 22],
        _ => vec![64, 64, 64, 64, 80, 96, 112, 128, 128, 128, 96],
    };
    let expected: Vec<usize> = chunks
        .iter()
        .scan(0, |done, chunk| {
            *done += chunk;
            Some(*done)
        })
        .collect();
    assert_eq!(reports, expected);
    assert_eq!(results.len(), 1024);
    assert!(results.iter().all(|v| v.scores.s.is_finite() && v.counts.synthetic_valid() > 0));
    // Poses differ by a thousandth of a radian each: the first is the correct one.
    assert!(results[0].scores.s >= results[1023].scores.s);
}

/// A call's chunks go to three lanes where the verifier asks for three chunks in flight (a
/// GPU's default; src/verify/lanes.rs): chunks are recorded while the device runs another, so
/// that a GPU does not wait for the host between chunks. A call of one chunk's length goes in
/// two chunks a lane there, of at most 86, its first ones no longer than 64 (the ramp,
/// src/verify/lanes.rs), which overlap. Eight chunks of 64: the context sees
/// three submissions in flight at once, and the results and progress come in order, the counts
/// those the test binary's verifier counts (one chunk of all 512 on lavapipe's default of one
/// lane).
#[test]
fn chunks_are_recorded_while_the_device_runs_another() {
    let sensor = centred_sensor(64, 64, 0.07, [0.0, 0.0], 45.0);
    let (_, sensed) = sensed(sensor);
    let one_chunk = settings(sensor, ShadowMode::Depth);
    let whole = verify(&sensed, &one_chunk, &turning(&step_model(), 512, 0.001, &[(1, 1), (2, 2)]));
    let verifier = Verifier::new(test_renderer(None)).expect("verifier").with_chunks_in_flight(3);
    let model = verifier.model("builtin:step", Path::new(".")).expect("model");
    let hypotheses = turning(&model, 512, 0.001, &[(1, 1), (2, 2)]);
    let mut reports = Vec::new();
    verifier.verify(&sensed, &one_chunk, &hypotheses, &mut |done| reports.push(done)).expect("eight chunks");
    assert_eq!(reports, [64, 128, 192, 256, 320, 384, 459, 512]);
    let mut reports = Vec::new();
    let chunked = VerifySettings { chunk_size: 64, ..one_chunk };
    let context = verifier.renderer().context();
    let recorded_before = context.recording_time();
    let lanes = verifier.verify(&sensed, &chunked, &hypotheses, &mut |done| reports.push(done)).expect("chunks");
    // The host's share, which the lanes overlap: counted in every lane's recordings.
    assert!(context.recording_time() > recorded_before, "the recording was timed");
    // On lavapipe a chunk runs for milliseconds, far longer than the other lanes take to record
    // and submit their own; a GPU may finish one before another is submitted.
    if context.is_cpu() {
        assert_eq!(context.most_submissions_in_flight(), 3);
    }
    assert_eq!(reports, (1..=8).map(|c| 64 * c).collect::<Vec<_>>());
    assert_eq!(lanes.len(), whole.len());
    for (chunked, whole) in lanes.iter().zip(&whole) {
        assert_eq!((&chunked.id, &chunked.counts), (&whole.id, &whole.counts));
    }
    let messages = context.take_validation_messages();
    assert!(messages.is_empty(), "validation reported:\n{}", messages.join("\n"));
}

/// `verify_each` hands the verifications chunk by chunk, in order, as `verify` returns them;
/// an error from the caller's handler stops the call, which returns it.
#[test]
fn verifications_come_chunk_by_chunk_and_a_handlers_error_stops_them() {
    let sensor = centred_sensor(64, 64, 0.07, [0.0, 0.0], 45.0);
    let (_, sensed) = sensed(sensor);
    let hypotheses = turning(&step_model(), 40, 0.01, &[(1, 1)]);
    let settings = VerifySettings { chunk_size: 16, ..settings(sensor, ShadowMode::Depth) };
    let whole = verify(&sensed, &settings, &hypotheses);
    let mut chunks = Vec::new();
    VERIFIER
        .verify_each(&sensed, &settings, &hypotheses, &mut |chunk| {
            chunks.push(chunk);
            Ok(())
        })
        .expect("verification runs");
    assert_eq!(chunks.iter().map(Vec::len).collect::<Vec<_>>(), [16, 16, 8]);
    assert_eq!(whole.len(), 40);
    for (v, w) in chunks.iter().flatten().zip(&whole) {
        assert_eq!((&v.id, &v.counts), (&w.id, &w.counts));
    }
    let mut handed = 0;
    let err = VERIFIER
        .verify_each(&sensed, &settings, &hypotheses, &mut |_| {
            handed += 1;
            Err(rangesynth::Error::Scene("the handler stops here".into()))
        })
        .unwrap_err();
    assert!(err.to_string().contains("the handler stops here"), "{err}");
    assert_eq!(handed, 1);
    assert_no_validation_messages();
}

#[test]
fn bad_verification_input_is_refused() {
    let sensor = test_sensor(45.0);
    let (image, sensed) = sensed(sensor);
    let err = VERIFIER.verify(
        &sensed,
        &settings(sensor, ShadowMode::Depth),
        &[hypothesis("h", "builtin:box", DMat4::IDENTITY, &[(1, 7)])],
        &mut |_| {},
    );
    assert!(err.unwrap_err().to_string().contains("binding (1, 7) names no surface"));
    let other = centred_sensor(64, 128, 0.035, [0.0, 0.0], 45.0);
    assert!(SensedImage::new(&image, &other.into())
        .unwrap_err()
        .to_string()
        .contains("128×128 but the sensor is 64×128"));
    let mut broken = image.clone();
    let i = broken.label.iter().position(|&l| l != 0).unwrap();
    broken.z[i] = f32::NAN;
    assert!(SensedImage::new(&broken, &sensor.into()).unwrap_err().to_string().contains("Z = NaN"));
    let finer = Scanner { pitch: [0.03, 0.035], ..sensor };
    let err = VERIFIER.verify(&sensed, &settings(finer, ShadowMode::Depth), &[correct()], &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("pitch"), "{err}");
    let nan_tolerance = VerifySettings { tolerance: f64::NAN, ..settings(sensor, ShadowMode::Depth) };
    let err = VERIFIER.verify(&sensed, &nan_tolerance, &[correct()], &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("tolerance NaN must be a finite number ≥ 0"), "{err}");
    // A pose given through the library is checked as one read from a file: a mirror would turn
    // the box's solid inside out for culling, a scale would stretch it.
    for pose in [DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)), DMat4::from_scale(DVec3::splat(2.0))] {
        let bad = [hypothesis("mirrored", "builtin:box", pose, &[(1, 1)])];
        let err = VERIFIER.verify(&sensed, &settings(sensor, ShadowMode::Depth), &bad, &mut |_| {}).unwrap_err();
        assert!(err.to_string().contains("hypothesis \"mirrored\": pose"), "{err}");
        assert!(err.to_string().contains("not a rigid transform"), "{err}");
        let mut scene = scene(sensor, ShadowMode::Depth, &[("builtin:box", pose)]);
        let err = renderer().render(&scene).unwrap_err();
        assert!(err.to_string().contains("object 1 (builtin:box): pose"), "{err}");
        scene.objects[0].pose = DMat4::IDENTITY;
        assert!(renderer().render(&scene).is_ok());
    }
}

#[test]
fn one_verifier_serves_several_threads_at_once() {
    let sensor = test_sensor(45.0);
    let (_, sensed) = sensed(sensor);
    let base = settings(sensor, ShadowMode::Depth);
    let hypotheses = turning(&step_model(), 12, 0.05, &[(1, 1), (2, 2)]);
    let sequential = verify(&sensed, &base, &hypotheses);
    std::thread::scope(|scope| {
        let runs: Vec<_> = (0..4)
            .map(|_| scope.spawn(|| VERIFIER.verify(&sensed, &base, &hypotheses, &mut |_| {}).unwrap()))
            .collect();
        for run in runs {
            let results = run.join().expect("no panic");
            for (a, b) in common::paired(&sequential, &results) {
                assert_eq!(
                    (a.id.as_str(), &a.counts, a.scores.s.to_bits()),
                    (b.id.as_str(), &b.counts, b.scores.s.to_bits())
                );
            }
        }
    });
    assert_no_validation_messages();
}

#[test]
fn an_overlap_table_too_large_for_a_batch_is_refused() {
    // 65,536 one-pixel segments against a 300-surface model: 65,536 × 300 counters (75 MiB)
    // exceed what one batch may hold (at most 64 MiB).
    let sensor = centred_sensor(256, 256, 0.02, [0.0, 0.0], 45.0);
    let n = 256 * 256;
    let image = RangeImage {
        width: 256,
        height: 256,
        x: vec![0.0; n],
        y: vec![0.0; n],
        z: vec![1.0; n],
        label: (1..=n as u32).collect(),
        reason: None,
        witness: None,
        sensor: Some(sensor.into()),
        shadow: None,
        effects: None,
    };
    let sensed = SensedImage::new(&image, &sensor.into()).unwrap();
    // Made here where it is missing: tools/device_kit.sh runs this binary where cargo did not.
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    std::fs::create_dir_all(&dir).unwrap();
    let mut obj = String::new();
    for g in 0..300 {
        let x = f64::from(g) * 0.01;
        obj += &format!("g s{g}\nv {x} 0 0\nv {} 0 0\nv {x} 1 0\nf -3 -2 -1\n", x + 0.01);
    }
    std::fs::write(dir.join("many_surfaces.obj"), obj).unwrap();
    let model = VERIFIER.model("many_surfaces.obj", &dir).unwrap();
    assert_eq!(model.mesh.surface_count(), 300);
    let h = Hypothesis { id: "big".into(), model, pose: DMat4::IDENTITY, bindings: vec![(1, 1)] };
    let err = VERIFIER.verify(&sensed, &settings(sensor, ShadowMode::Depth), &[h], &mut |_| {}).unwrap_err();
    let message = err.to_string();
    assert!(message.contains("65536 segments against 300 surfaces needs 75 MiB"), "{message}");
}

/// A batch records its hypotheses in runs of its slots, each run's passes side by side: one
/// barrier a stage for the run, where a GPU waits for the work before it, not one a pass for
/// each hypothesis. So two runs more add two runs' stages, whether a run is 4 hypotheses long
/// (a CPU device's default) or 16 (a GPU's): with the graphics pipeline, the rasters (one
/// barrier for both views' attachments), the masks and the scores; with the compute
/// rasterizer, the coverage's three (the words and the coverage buffers made ready, the
/// coverage dispatches, the large triangles'), whether it covers four hypotheses in one
/// dispatch or one a dispatch, then the masks and the scores. (Before the runs, each
/// hypothesis took its own: about 12 a run of four with the graphics pipeline; before the
/// coverage dispatches went side by side, one a dispatch took 14 a run of four.)
#[test]
fn a_batch_waits_once_a_stage_for_each_run_of_slots() {
    const PER_DISPATCH: usize = 4;
    let sensor = test_sensor(20.0);
    let (_, sensed) = sensed(sensor);
    let settings = settings(sensor, ShadowMode::Label);
    for (raster, barriers_a_run) in [(Raster::Graphics, 3), (Raster::Compute, 5)] {
        for slots in [4, 16] {
            let renderer = test_renderer(None).with_raster(raster).with_hypotheses_per_dispatch(PER_DISPATCH);
            let verifier = Verifier::new(renderer).expect("verifier").with_slots(slots);
            let model = verifier.model("builtin:step", Path::new(".")).expect("model");
            let barriers = |runs: usize| {
                barriers_verifying(&verifier, &sensed, &settings, &turning(&model, runs * slots, 0.01, &[(1, 1)])).0
            };
            // The first uploads the sensed image and the mesh, which take barriers of their own.
            barriers(1);
            let (one_run, three_runs) = (barriers(1), barriers(3));
            assert_eq!(
                three_runs - one_run,
                2 * barriers_a_run,
                "{raster:?}, runs of {slots}: {one_run} barriers for one run, {three_runs} for three"
            );
        }
    }
}

/// The barriers a verification records, and what it returns; fails on a validation message.
fn barriers_verifying(
    verifier: &Verifier,
    sensed: &SensedImage,
    settings: &VerifySettings,
    hypotheses: &[Hypothesis],
) -> (u64, rangesynth::Result<Vec<Verification>>) {
    let context = verifier.renderer().context();
    let before = context.barriers_recorded();
    let out = verifier.verify(sensed, settings, hypotheses, &mut |_| {});
    let messages = context.take_validation_messages();
    assert!(messages.is_empty(), "validation reported:\n{}", messages.join("\n"));
    (context.barriers_recorded() - before, out)
}

/// A batch keeps as many slots as the memory budget holds, up to those asked for, rather than
/// being refused: under a budget that holds one slot, a batch that asked for 16 runs its
/// hypotheses one a run (a run's stages for each: at least three barriers a hypothesis more
/// than in one run of 16), and counts what it counts with all 16.
#[test]
fn a_batch_keeps_the_slots_the_memory_budget_holds() {
    const SLOTS: usize = 16;
    let sensor = test_sensor(20.0);
    let (_, sensed) = sensed(sensor);
    let settings = settings(sensor, ShadowMode::Depth);
    let verifier_within = |budget: u64| {
        let renderer = test_renderer(None).with_memory_budget(MemoryBudget::new(budget));
        let verifier = Verifier::new(renderer).expect("verifier").with_slots(SLOTS);
        let model = verifier.model("builtin:step", Path::new(".")).expect("model");
        let hypotheses = turning(&model, SLOTS, 0.01, &(1..=8).map(|l| (l, l)).collect::<Vec<_>>());
        // The first uploads the sensed image and the mesh, which take barriers of their own.
        let _ = barriers_verifying(&verifier, &sensed, &settings, &hypotheses);
        barriers_verifying(&verifier, &sensed, &settings, &hypotheses)
    };
    let (barriers_all, counted_all) = verifier_within(DEFAULT_MEMORY_BUDGET);
    let counted_all = counted_all.expect("verification in 16 slots runs");
    // What one slot takes, beside the sensed image and the counts, on top of what the run
    // holds (the model): the figures a budget too small for any refuses with (one slot, the
    // fewest a batch keeps).
    let one_slot = match verifier_within(1 << 20).1 {
        Err(rangesynth::Error::TooLarge { needed, held, .. }) => needed.0 + held.0,
        other => panic!("a 1 MiB budget holds no slot of a 128² verification: {:?}", other.map(|v| v.len())),
    };
    // With room for the 16 verifications' counts the call gathers (a few KB), far short of a
    // second slot.
    let (barriers_one, counted_one) = verifier_within(one_slot + (64 << 10));
    let counted_one = counted_one.expect("a budget that holds one slot verifies the batch");
    // At least the three stages of a run (raster, mask, score) for each of 15 runs more.
    let more = barriers_one.saturating_sub(barriers_all);
    assert!(more >= 3 * (SLOTS as u64 - 1), "{barriers_one} barriers in one slot, {barriers_all} in 16");
    assert_eq!(counted_one.len(), counted_all.len());
    for (one, all) in counted_one.iter().zip(&counted_all) {
        assert_eq!(one.counts, all.counts, "{}", one.id);
    }
}

/// A call that gathers its verifications (`Verifier::verify`) holds them to the memory budget,
/// as everything else a run holds: where even the least each verification holds would not
/// fit, it is refused before anything runs, by a figure naming them; where their counts grow
/// past it (a model of a surface a triangle holds a count and an area a surface), it stops at
/// the first chunk past it, rather than gathering without bound until the host runs out.
#[test]
fn a_call_gathering_its_verifications_holds_them_to_the_budget() {
    let sensor = test_sensor(20.0);
    let (_, sensed) = sensed(sensor);
    let settings = VerifySettings { chunk_size: 8, ..settings(sensor, ShadowMode::Depth) };
    const BUDGET: u64 = 16 << 20;
    let verifier = Verifier::new(test_renderer(None).with_memory_budget(MemoryBudget::new(BUDGET))).expect("verifier");
    let refusal = |hypotheses: &[Hypothesis]| match verifier.verify(&sensed, &settings, hypotheses, &mut |_| {}) {
        Err(rangesynth::Error::TooLarge { what, .. }) => what,
        other => panic!("{} hypotheses gathered within 16 MiB: {:?}", hypotheses.len(), other.map(|v| v.len())),
    };
    // More verifications than 16 MiB holds even bare.
    let step = verifier.model("builtin:step", Path::new(".")).expect("model");
    let many = (BUDGET / Verification::LEAST_HELD_BYTES + 1) as usize;
    let what = refusal(&turning(&step, many, 1e-6, &[(1, 1)]));
    assert_eq!(what, format!("holding the verifications of {many} hypotheses"));
    // The sphere's 9,800 triangles, each a surface of its own: 157 KB of counts a verification
    // on the host, so 1,400 take 220 MB, though the plan's counts (2 × 64 MiB at most) and
    // slots fit 192 MiB.
    let verifier =
        Verifier::new(test_renderer(None).with_memory_budget(MemoryBudget::new(12 * BUDGET))).expect("verifier");
    let refusal = |hypotheses: &[Hypothesis]| match verifier.verify(&sensed, &settings, hypotheses, &mut |_| {}) {
        Err(rangesynth::Error::TooLarge { what, .. }) => what,
        other => panic!("{} hypotheses gathered within 192 MiB: {:?}", hypotheses.len(), other.map(|v| v.len())),
    };
    let sphere = verifier.model("builtin:sphere:100", Path::new(".")).expect("model");
    let mesh = &sphere.mesh;
    let positions = (0..mesh.positions.len() as u32).map(|v| mesh.vertex(v).to_array()).collect();
    let surfaces = mesh.triangles.len() as u32;
    let faceted = rangesynth::mesh::Mesh::new(
        "faceted sphere",
        positions,
        mesh.triangles.clone(),
        (1..=surfaces).collect(),
        (1..=surfaces).map(|s| format!("facet {s}")).collect(),
    )
    .expect("mesh");
    let faceted = verifier.model_of_mesh(Arc::new(faceted)).expect("model");
    let what = refusal(&turning(&faceted, 1400, 0.001, &[(1, 1)]));
    let gathered: usize = what
        .strip_prefix("holding the verifications of ")
        .and_then(|rest| rest.strip_suffix(" hypotheses"))
        .and_then(|count| count.parse().ok())
        .unwrap_or_else(|| panic!("refused for something else: {what}"));
    assert!((8..1400).contains(&gathered) && gathered.is_multiple_of(8), "stopped at {gathered} hypotheses");
    // And a verification that fits is verified under the same budget.
    assert_eq!(
        verifier.verify(&sensed, &settings, &turning(&faceted, 8, 0.01, &[(1, 1)]), &mut |_| {}).unwrap().len(),
        8
    );
}

/// A verifier that times its stages (`Verifier::with_stage_times`) reports the GPU time of
/// each stage it ran, by name, once: the rasters, masks and scores with the graphics
/// pipeline; the coverage's three, masks and scores with the compute rasterizer. One that does
/// not reports nothing.
#[test]
fn a_timed_verification_reports_each_stage_it_ran() {
    let sensor = test_sensor(20.0);
    let (_, sensed) = sensed(sensor);
    let settings = settings(sensor, ShadowMode::Label);
    let cases = [
        (Raster::Graphics, vec!["range", "shadow", "shadow mask", "score"]),
        (Raster::Compute, vec!["coverage: set-up", "coverage", "coverage: large triangles", "shadow mask", "score"]),
    ];
    for (raster, stages) in cases {
        let verifier = Verifier::new(test_renderer(None).with_raster(raster)).expect("verifier").with_stage_times();
        let model = verifier.model("builtin:step", Path::new(".")).expect("model");
        let (barriers, out) = barriers_verifying(&verifier, &sensed, &settings, &turning(&model, 8, 0.01, &[(1, 1)]));
        assert!(barriers > 0 && out.is_ok());
        let times = verifier.take_stage_times();
        for stage in &stages {
            let ms = times.iter().find(|(name, _)| name == stage).map(|&(_, ms)| ms);
            assert!(ms.is_some_and(|ms| ms >= 0.0), "{raster:?}: {stage:?} in {times:?}");
        }
        let busy = |stage: &str| times.iter().any(|&(name, ms)| name == stage && ms > 0.0);
        assert!(busy("shadow mask") && busy("score"), "{raster:?}: {times:?}");
        assert!(verifier.take_stage_times().is_empty(), "taken once");
    }
    assert!(VERIFIER.take_stage_times().is_empty(), "untimed by default");
}

/// Vulkan lets a device's square root err by a few ulp (NVIDIA's approximates it), and the
/// areas the GPU counts must be the host's to the bit (the CPU scorer's, and the sensed
/// image's own, for a ratio of exactly 1): the score pass corrects the device's root to the
/// IEEE one. Stood in for on lavapipe, whose root is exact, by putting it 2 ulp low and 3 high
/// before the correction (and as a GPU has it, corrected but not put off): every count, the
/// areas included, stays the exact root's.
#[test]
fn areas_are_the_hosts_bits_where_the_devices_square_root_errs() {
    let sensor = test_sensor(20.0);
    let (_, sensed) = sensed(sensor);
    let settings = settings(sensor, ShadowMode::Depth);
    let exact = verify(&sensed, &settings, &[correct()]);
    assert!(exact[0].counts.surface_area_units.iter().any(|&a| a > 0), "areas counted");
    for ulps in [0, -2, 3] {
        let verifier = Verifier::new(test_renderer(None)).and_then(|v| v.with_sqrt_error_for_tests(ulps));
        let verifier = verifier.expect("verifier");
        let model = verifier.model("builtin:step", Path::new(".")).expect("model");
        let h = Hypothesis { model, ..correct() };
        let out = verifier.verify(&sensed, &settings, &[h], &mut |_| {}).expect("verification runs");
        assert_eq!(out[0].counts, exact[0].counts, "the root {ulps} ulp off");
        let messages = verifier.renderer().context().take_validation_messages();
        assert!(messages.is_empty(), "validation reported:\n{}", messages.join("\n"));
    }
}
