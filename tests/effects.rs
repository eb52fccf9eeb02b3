//! Sensor effects (src/effects.rs) against values worked out by hand, against statistical
//! bounds, or against their rule recomputed on the CPU; and verification with effects on.

mod common;

use common::scorer::{as_cpu, cpu_counts, Images};
use common::*;
use glam::{DMat4, DVec3};
use rangesynth::effects::Reason;
use rangesynth::io::RangeImage;
use rangesynth::limits::Ledger;
use rangesynth::scene::Scene;
use rangesynth::sensor::Sensor;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, VerifySettings};
use rangesynth::RenderOutput;
use std::path::Path;

fn effects(text: &str) -> Effects {
    let effects: Effects = toml::from_str(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    effects.validate().unwrap();
    effects
}

fn with(scene: &Scene, text: &str) -> Scene {
    Scene { effects: effects(text), ..scene.clone() }
}

/// A square plate of side 8, tilted by `alpha_deg` about y (its normal (sin α, 0, cos α)) and
/// lifted by `lift`, filling a `size`² image of pitch 0.01; no shadow pass.
fn plate(alpha_deg: f64, lift: f64, theta: f64, size: u32) -> Scene {
    let s = centred_sensor(size, size, 0.01, [0.0, 0.0], theta);
    let pose = DMat4::from_translation(DVec3::new(0.0, 0.0, lift)) * DMat4::from_rotation_y(alpha_deg.to_radians());
    scene(s, ShadowMode::None, &[("builtin:plane:8", pose)])
}

fn pixels(out: &RenderOutput) -> usize {
    out.label.len()
}

/// Mean and standard deviation.
fn moments(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let variance = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, variance.sqrt())
}

#[test]
fn grazing_loses_plates_tilted_beyond_the_limit_from_the_projector_or_the_camera() {
    // θ = 30°: the camera looks along (sin 30°, 0, cos 30°), so a plate tilted by α is seen at
    // |α| from the projector and |α − 30°| from the camera. The limit is 50°.
    let cases = [(0.0, false), (40.0, false), (-15.0, false), (55.0, true), (75.0, true), (-25.0, true)];
    for (alpha, lost) in cases {
        let out = render(&with(&plate(alpha, 0.0, 30.0, 64), "[grazing]\nmax_incidence_deg = 50"));
        assert!(out.label_unshadowed.iter().all(|&l| l != 0), "α = {alpha}: the plate fills the image");
        let expected = if lost { Reason::Grazing } else { Reason::Valid };
        let wrong = out.reason.iter().filter(|&&r| r != expected).count();
        assert_eq!(wrong, 0, "α = {alpha}: {wrong} pixels are not {expected:?}");
        let points = (0..pixels(&out)).filter(|&i| out.point(i).is_some()).count();
        assert_eq!(points, if lost { 0 } else { pixels(&out) }, "α = {alpha}");
    }
}

#[test]
fn noise_has_the_asked_mean_and_sigma_and_is_reproducible_per_seed() {
    let base = plate(0.0, 0.0, 0.0, 256);
    let clean = render(&base);
    let noisy_scene = with(&base, "[noise]\nsigma = 0.01\nseed = 1");
    let noisy = render(&noisy_scene);
    assert_eq!(noisy.label, clean.label, "noise loses no point");
    let n = pixels(&noisy) as f64;
    let d: Vec<f64> = common::paired(&noisy.z, &clean.z).map(|(a, b)| f64::from(*a) - f64::from(*b)).collect();
    let (mean, sd) = moments(&d);
    // Five standard errors: of the mean, σ/√n; of the sample deviation, σ/√(2n).
    assert!(mean.abs() < 5.0 * 0.01 / n.sqrt(), "mean {mean}");
    assert!((sd / 0.01 - 1.0).abs() < 5.0 / (2.0 * n).sqrt(), "σ {sd}");
    // Gaussian: 68.27% within one σ.
    let within = d.iter().filter(|v| v.abs() < 0.01).count() as f64 / n;
    assert!((within - 0.6827).abs() < 5.0 * (0.6827f64 * 0.3173 / n).sqrt(), "{within} within 1σ");

    let again = render(&noisy_scene);
    let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&again.z), bits(&noisy.z), "bit-identical across runs");
    let other_seed = render(&with(&base, "[noise]\nsigma = 0.01\nseed = 2"));
    let same = common::paired(&other_seed.z, &noisy.z).filter(|(a, b)| a == b).count();
    assert!(same < pixels(&noisy) / 100, "{same} pixels equal under another seed");
}

#[test]
fn noise_grows_with_depth_and_incidence_as_the_axial_model_says() {
    // σ = sigma + depth_coefficient·(z − depth_reference)² + incidence_coefficient·α²/(π/2 − α)².
    // A flat plate at z = 3 against a reference of 1: 0.002 + 0.001·2² = 0.006.
    // A plate at α = 45°, where α²/(π/2 − α)² = 1: 0.001 + 0.002 = 0.003.
    let cases = [
        (plate(0.0, 3.0, 0.0, 192), "sigma = 0.002\ndepth_coefficient = 0.001\ndepth_reference = 1.0", 0.006),
        (plate(45.0, 0.0, 0.0, 192), "sigma = 0.001\nincidence_coefficient = 0.002", 0.003),
    ];
    for (base, terms, sigma) in cases {
        let clean = render(&base);
        let noisy = render(&with(&base, &format!("[noise]\nseed = 5\n{terms}")));
        let d: Vec<f64> = common::paired(&noisy.z, &clean.z).map(|(a, b)| f64::from(*a) - f64::from(*b)).collect();
        let (_, sd) = moments(&d);
        assert!((sd / sigma - 1.0).abs() < 5.0 / (2.0 * d.len() as f64).sqrt() + 1e-3, "{terms}: σ {sd}, not {sigma}");
    }
}

#[test]
fn quantization_stores_exact_multiples_of_the_step() {
    let base = plate(20.0, 0.0, 0.0, 128);
    let clean = render(&base);
    for (text, step) in [("[quantize]\nz_step = 0.25", 0.25f32), ("[quantize]\nz_step = 0.1", 0.1f32)] {
        let out = render(&with(&base, text));
        for (i, (&q, &z)) in common::paired(&out.z, &clean.z).enumerate() {
            let k = (f64::from(q) / f64::from(step)).round();
            assert_eq!(q, k as f32 * step, "{text}: pixel {i}: {q} is not a multiple");
            assert!(f64::from((q - z).abs()) <= f64::from(step) / 2.0 + 1e-6, "{text}: pixel {i}: {z} → {q}");
        }
        let levels: std::collections::BTreeSet<u32> = out.z.iter().map(|z| z.to_bits()).collect();
        assert!(levels.len() > 2, "{text}: the tilted plate spans several steps");
    }
    // After noise, what is stored is still a multiple.
    let out = render(&with(&base, "[noise]\nsigma = 0.3\n[quantize]\nz_step = 0.25"));
    assert!(out.z.iter().all(|&q| (q * 4.0).fract() == 0.0), "noisy z quantized");
}

#[test]
fn dropout_loses_the_asked_fraction() {
    let base = plate(0.0, 0.0, 0.0, 256);
    let n = 256.0 * 256.0;
    for p in [0.0f64, 0.3, 1.0] {
        let out = render(&with(&base, &format!("[dropout]\nprobability = {p}\nseed = 11")));
        let lost = out.pixels_lost_to(Reason::Dropout) as f64;
        assert_eq!(out.reason.iter().filter(|&&r| r != Reason::Valid && r != Reason::Dropout).count(), 0);
        let bound = 5.0 * (p * (1.0 - p) / n).sqrt();
        assert!((lost / n - p).abs() <= bound, "p = {p}: lost {}", lost / n);
    }
    let a = render(&with(&base, "[dropout]\nprobability = 0.3\nseed = 11"));
    let b = render(&with(&base, "[dropout]\nprobability = 0.3\nseed = 12"));
    let again = render(&with(&base, "[dropout]\nprobability = 0.3\nseed = 11"));
    assert_eq!(again.label, a.label, "reproducible");
    assert_ne!(b.label, a.label, "another seed, other losses");
}

/// pcg4d (Jarzynski and Olano, "Hash Functions for GPU Rendering", JCGT 2020), from the paper:
/// the hash the effects draw from (shaders/stages/random.glsl).
fn pcg4d(mut v: [u32; 4]) -> [u32; 4] {
    for x in &mut v {
        *x = x.wrapping_mul(1664525).wrapping_add(1013904223);
    }
    let mix = |v: &mut [u32; 4]| {
        v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
        v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
        v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
        v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
    };
    mix(&mut v);
    for x in &mut v {
        *x ^= *x >> 16;
    }
    mix(&mut v);
    v
}

/// Dropout's draw at a pixel: the first of its two uniform variates (24 bits) for (seed,
/// pixel, stream 1), as docs/effects.md states the rule.
fn dropout_draw(seed: u32, col: u32, row: u32) -> f32 {
    (pcg4d([col, row, seed, 1])[0] >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Dropout loses exactly the measured points whose draw falls below the probability, on a
/// scene with background and shadows: no neighbour's, no shadowed or empty pixel's.
#[test]
fn dropout_loses_exactly_the_points_its_draws_pick() {
    let base = cluttered(160);
    let before = render(&base);
    let (p, seed) = (0.3f32, 7u32);
    let out = render(&with(&base, &format!("[dropout]\nprobability = {p}\nseed = {seed}")));
    let mut lost = 0;
    for row in 0..160u32 {
        for col in 0..160u32 {
            let i = (row * 160 + col) as usize;
            let picked = dropout_draw(seed, col, row) < p;
            match before.reason[i] {
                Reason::Valid => {
                    let expected = if picked { Reason::Dropout } else { Reason::Valid };
                    assert_eq!(out.reason[i], expected, "pixel ({col}, {row})");
                    lost += usize::from(picked);
                }
                earlier => assert_eq!(out.reason[i], earlier, "pixel ({col}, {row}): a point not measured"),
            }
        }
    }
    assert!(lost > 1000, "{lost} points lost");
}

/// The demo's stepped block and cylinder on a table at θ = 45°, depth-mode shadows.
fn cluttered(size: u32) -> Scene {
    let s = centred_sensor(size, size, 5.0 / f64::from(size), [-0.5, 0.0], 45.0);
    let step = DMat4::from_translation(DVec3::new(0.4, 0.7, 0.0)) * DMat4::from_rotation_z(20f64.to_radians());
    let cylinder = DMat4::from_translation(DVec3::new(-0.9, -1.5, 0.0));
    let objects = [("builtin:step", step), ("builtin:cylinder:48", cylinder), ("builtin:plane:6", DMat4::IDENTITY)];
    scene(s, ShadowMode::Depth, &objects)
}

#[test]
fn edges_lose_what_the_mixed_pixel_rule_recomputed_on_the_cpu_loses() {
    let base = cluttered(160);
    let before = render(&base);
    let (jump, width) = (0.3f32, 2i64);
    let out = render(&with(&base, &format!("[edges]\njump = {jump}\nwidth_px = {width}")));
    let (w, h) = (160i64, 160i64);
    let (mut holes, mut jumps) = (0, 0);
    for r in 0..h {
        for c in 0..w {
            let i = (r * w + c) as usize;
            let expected = if before.reason[i] != Reason::Valid {
                before.reason[i]
            } else {
                let mut near_hole = false;
                let mut near_jump = false;
                for rr in (r - width).max(0)..=(r + width).min(h - 1) {
                    for cc in (c - width).max(0)..=(c + width).min(w - 1) {
                        let j = (rr * w + cc) as usize;
                        near_hole |= before.label[j] == 0;
                        near_jump |= before.label[j] != 0 && (before.z[j] - before.z[i]).abs() > jump;
                    }
                }
                holes += usize::from(near_hole);
                jumps += usize::from(near_jump && !near_hole);
                if near_hole || near_jump {
                    Reason::Edge
                } else {
                    Reason::Valid
                }
            };
            assert_eq!(out.reason[i], expected, "pixel ({c}, {r})");
        }
    }
    assert!(holes > 100 && jumps > 100, "both parts of the rule are exercised: {holes} by holes, {jumps} by jumps");
    assert_eq!(out.label_unshadowed, before.label_unshadowed);
}

#[test]
fn the_working_volume_loses_points_outside_it() {
    let base = plate(20.0, 0.0, 0.0, 128);
    let clean = render(&base);
    let out = render(&with(&base, "[range]\nmin_z = -0.1\nmax_z = 0.15"));
    // z as stored (f32) against the bounds in f32, as the GPU compares them.
    let (mut below, mut above) = (0, 0);
    for (i, &z) in clean.z.iter().enumerate() {
        let outside = !(-0.1..=0.15).contains(&z);
        below += usize::from(z < -0.1);
        above += usize::from(z > 0.15);
        assert_eq!(out.reason[i], if outside { Reason::OutOfRange } else { Reason::Valid }, "pixel {i}, z = {z}");
    }
    assert!(below > 0 && above > 0);
    let only_max = render(&with(&base, "[range]\nmax_z = 0.15"));
    assert_eq!(only_max.pixels_lost_to(Reason::OutOfRange), above);
}

#[test]
fn surfaces_darker_than_the_threshold_are_lost() {
    let s = centred_sensor(96, 96, 0.05, [0.0, 0.0], 30.0);
    let left = DMat4::from_translation(DVec3::new(-1.2, 0.0, 0.0));
    let right = DMat4::from_translation(DVec3::new(1.2, 0.0, 0.0));
    let mut sc = scene(
        s,
        ShadowMode::Depth,
        &[("builtin:box", left), ("builtin:box", right), ("builtin:plane:6", DMat4::IDENTITY)],
    );
    // The left box is dark, the right one takes the default (dark too), the table is bright.
    sc.objects[0].reflectivity = Some(0.1);
    sc.objects[2].reflectivity = Some(0.9);
    let before = render(&sc);
    let out = render(&with(&sc, "[reflectivity]\nthreshold = 0.5\ndefault = 0.3"));
    let bases = sc.label_bases().unwrap();
    for (i, &surface) in before.label.iter().enumerate() {
        let expected = match surface {
            0 => before.reason[i],
            l if l > bases[2] => Reason::Valid,
            _ => Reason::Dark,
        };
        assert_eq!(out.reason[i], expected, "pixel {i}, label {surface}");
    }
    assert!(out.pixels_lost_to(Reason::Dark) > 500);
    // A brighter default keeps the right box.
    let kept = render(&with(&sc, "[reflectivity]\nthreshold = 0.5\ndefault = 0.6"));
    let right_box = (bases[1] + 1..=bases[2]).collect::<Vec<_>>();
    assert!(kept.label.iter().any(|l| right_box.contains(l)));
    assert!(!kept.label.iter().any(|&l| l >= 1 && l <= bases[1]), "the left box stays dark");
}

#[test]
fn an_effect_free_scene_records_the_passes_it_always_did_and_effects_add_theirs_in_order() {
    let base = cluttered(64);
    let names = |out: &RenderOutput| out.timings.iter().map(|t| t.name).collect::<Vec<_>>();
    assert_eq!(names(&render(&base)), ["range", "shadow", "shadow mask"]);
    let all = "[quantize]\nz_step = 0.01\n[noise]\nsigma = 0.001\n[dropout]\nprobability = 0.1\n\
               [edges]\njump = 0.2\n[reflectivity]\nthreshold = 0.1\n[range]\nmax_z = 5\n\
               [grazing]\nmax_incidence_deg = 80\n";
    let expected = [
        "range",
        "shadow",
        "shadow mask",
        "grazing",
        "working volume",
        "reflectivity",
        "edges",
        "dropout",
        "noise",
        "quantize",
    ];
    assert_eq!(names(&render(&with(&base, all))), expected);
    let no_shadow = Scene { shadow: rangesynth::shadow::ShadowSettings::of(ShadowMode::None), ..base.clone() };
    assert_eq!(names(&render(&with(&no_shadow, "[noise]\nsigma = 0.01"))), ["range", "noise"]);
    // Effects that lose nothing and change nothing leave the image as it was.
    let idle = render(&with(&base, "[dropout]\nprobability = 0\n[grazing]\nmax_incidence_deg = 90"));
    let plain = render(&base);
    assert_eq!(idle.label, plain.label);
    assert_eq!(idle.reason, plain.reason);
}

// Verification with effects.

const TOLERANCE: f64 = 0.05;
const EFFECTS: &str = "[grazing]\nmax_incidence_deg = 80\n[edges]\njump = 0.2\nwidth_px = 1\n\
                       [dropout]\nprobability = 0.05\nseed = 3\n[noise]\nsigma = 0.004\nseed = 4\n\
                       [quantize]\nz_step = 0.002\n";

fn step_pose() -> DMat4 {
    DMat4::from_translation(DVec3::new(0.3, -0.2, 0.0)) * DMat4::from_rotation_z(25f64.to_radians())
}

fn step_scene(sensor: impl Into<Sensor>, pose: DMat4) -> Scene {
    with(&scene(sensor, ShadowMode::Depth, &[("builtin:step", pose)]), EFFECTS)
}

fn hypothesis(id: &str, pose: DMat4) -> Hypothesis {
    let bindings = (1..=8).map(|l| (l, l)).collect();
    Hypothesis { id: id.into(), model: VERIFIER.model("builtin:step", Path::new(".")).unwrap(), pose, bindings }
}

fn verify_settings(sensor: impl Into<Sensor>) -> VerifySettings {
    VerifySettings {
        sensor: sensor.into(),
        shadow: ShadowSettings::of(ShadowMode::Depth),
        effects: effects(EFFECTS),
        tolerance: TOLERANCE,
        compare_shadow: true,
        chunk_size: 1024,
    }
}

#[test]
fn verification_with_the_sensed_images_effects_scores_the_true_pose_1_and_matches_the_cpu_scorer() {
    let sensor = centred_sensor(128, 128, 0.035, [0.0, 0.0], 45.0);
    let sensed_out = render(&step_scene(sensor, step_pose()));
    assert!(sensed_out.pixels_lost_to(Reason::Dropout) > 0 && sensed_out.pixels_lost_to(Reason::Edge) > 0);
    let image = RangeImage::from(&sensed_out);
    let sensed = SensedImage::new(&image, &sensor.into()).unwrap();
    let wrong = step_pose() * DMat4::from_translation(DVec3::new(0.05, 0.0, 0.02));
    let hypotheses = [hypothesis("true", step_pose()), hypothesis("wrong", wrong)];
    let results = VERIFIER.verify(&sensed, &verify_settings(sensor), &hypotheses, &mut |_| {}).unwrap();
    assert_no_validation_messages();
    assert_eq!(results[0].scores.s, 1.0, "{:?}", results[0].scores);
    assert!(results[1].scores.s < 0.9);
    for (h, v) in common::paired(&hypotheses, &results) {
        let synthetic = render(&step_scene(sensor, h.pose));
        let images = Images::of(&image, &synthetic);
        let cpu = cpu_counts(&images, TOLERANCE as f32);
        // Every count, overlap, population and area, not only the scalars.
        assert_eq!(as_cpu(&v.counts, &sensed, sensed.valid), cpu, "{}", h.id);
    }
    // The unshadowed score sees every loss the effects found at the range view's surface
    // pixels, so it scores the image the same effects give without a shadow pass; but for the
    // edge filter, which loses pixels beside the shadowed image's holes, and is left out here.
    let no_edges = Effects { edges: None, ..effects(EFFECTS) };
    let settings = VerifySettings { effects: no_edges, ..verify_settings(sensor) };
    let results = VERIFIER.verify(&sensed, &settings, &hypotheses, &mut |_| {}).unwrap();
    assert_no_validation_messages();
    for (h, v) in common::paired(&hypotheses, &results) {
        let unshadowed_scene =
            Scene { shadow: ShadowSettings::of(ShadowMode::None), effects: no_edges, ..step_scene(sensor, h.pose) };
        let synthetic = render(&unshadowed_scene);
        let cpu = cpu_counts(&Images::of(&image, &synthetic), TOLERANCE as f32);
        let (counts, _) = v.unshadowed.as_ref().expect("compare_shadow scores the unshadowed image");
        assert_eq!(as_cpu(counts, &sensed, sensed.valid), cpu, "{}: unshadowed", h.id);
    }
    // Without the sensor's effects, the true pose no longer reproduces the sensed image.
    let plain = VerifySettings { effects: Effects::default(), ..verify_settings(sensor) };
    let without = VERIFIER.verify(&sensed, &plain, &hypotheses[..1], &mut |_| {}).unwrap();
    assert!(without[0].scores.s < 0.9, "{:?}", without[0].scores);
}

#[test]
fn counts_with_effects_do_not_depend_on_the_batch_or_the_order() {
    let sensor = centred_sensor(96, 96, 0.045, [0.0, 0.0], 45.0);
    let image = RangeImage::from(&render(&step_scene(sensor, step_pose())));
    let sensed = SensedImage::new(&image, &sensor.into()).unwrap();
    let hypotheses: Vec<Hypothesis> = (0..7)
        .map(|k| {
            let pose = step_pose()
                * DMat4::from_rotation_z(0.04 * f64::from(k))
                * DMat4::from_translation(DVec3::new(0.03 * f64::from(k), 0.0, 0.0));
            hypothesis(&format!("h{k}"), pose)
        })
        .collect();
    let counts = |settings: &VerifySettings, hs: &[Hypothesis]| {
        let out = VERIFIER.verify(&sensed, settings, hs, &mut |_| {}).unwrap();
        assert_no_validation_messages();
        out.into_iter().map(|v| (v.id, v.counts, v.unshadowed.map(|(c, _)| c))).collect::<Vec<_>>()
    };
    let alone: Vec<_> =
        hypotheses.iter().flat_map(|h| counts(&verify_settings(sensor), std::slice::from_ref(h))).collect();
    for chunk_size in [3, 1024] {
        let settings = VerifySettings { chunk_size, ..verify_settings(sensor) };
        assert_eq!(counts(&settings, &hypotheses), alone, "chunks of {chunk_size}");
    }
    let mut reversed = counts(&verify_settings(sensor), &hypotheses.iter().rev().cloned().collect::<Vec<_>>());
    reversed.reverse();
    assert_eq!(reversed, alone, "reversed order");
}

#[test]
fn verification_reads_each_models_material_reflectivity_at_its_place_in_the_batch() {
    // An OBJ model of two raised squares side by side, one dark (Kd mean 0.1), one bright (0.9).
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("effects_materials");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl dark\nKd 0.1 0.1 0.1\nnewmtl bright\nKd 0.9 0.9 0.9\n").unwrap();
    let obj = "mtllib m.mtl\nv -1 -0.8 0.2\nv 0 -0.8 0.2\nv 0 0.8 0.2\nv -1 0.8 0.2\nv 1 -0.8 0.2\nv 1 0.8 0.2\n\
               g dark\nusemtl dark\nf 1 2 3 4\ng bright\nusemtl bright\nf 2 5 6 3\n";
    std::fs::write(dir.join("squares.obj"), obj).unwrap();
    let sensor = centred_sensor(64, 64, 0.04, [0.0, 0.0], 30.0);
    let text = format!(
        "[sensor]\nkind = \"orthographic\"\nwidth = 64\nheight = 64\npitch = [0.04, 0.04]\norigin = {:?}\n\
         theta_deg = 30.0\n[shadow]\nmode = \"depth\"\n[effects.reflectivity]\nthreshold = 0.5\n\
         [[object]]\nmodel = \"squares.obj\"\n",
        sensor.origin
    );
    let sensed_scene = Scene::from_toml(&text, &dir, &Ledger::default()).unwrap();
    let out = render(&sensed_scene);
    let dark_lost = out.pixels_lost_to(Reason::Dark);
    assert!(dark_lost > 500 && out.label.iter().all(|&l| l != 1), "the dark square is lost: {dark_lost}");
    assert!(out.label.iter().filter(|&&l| l == 2).count() > 500, "the bright square is kept");
    let image = RangeImage::from(&out);
    let sensed = SensedImage::new(&image, &sensor.into()).unwrap();
    let squares = Hypothesis {
        id: "squares".into(),
        model: VERIFIER.model("squares.obj", &dir).unwrap(),
        pose: DMat4::IDENTITY,
        bindings: vec![(2, 2)],
    };
    let boxed = Hypothesis {
        id: "box".into(),
        model: VERIFIER.model("builtin:box", Path::new(".")).unwrap(),
        pose: DMat4::from_translation(DVec3::new(0.2, 0.1, 0.0)),
        bindings: vec![(2, 1)],
    };
    let settings = VerifySettings { effects: sensed_scene.effects, ..verify_settings(sensor) };
    let alone = VERIFIER.verify(&sensed, &settings, std::slice::from_ref(&squares), &mut |_| {}).unwrap();
    let batch = VERIFIER.verify(&sensed, &settings, &[boxed, squares], &mut |_| {}).unwrap();
    assert_no_validation_messages();
    assert_eq!(alone[0].scores.s, 1.0, "{:?}", alone[0].scores);
    assert_eq!(batch[1].counts, alone[0].counts, "the same after another model in the batch");
    assert_eq!(alone[0].counts.surface_population[0], 0, "the dark surface has no synthetic pixels");
}
