//! Expected values worked out by hand from the built-in models' geometry (src/mesh/builtin.rs).

mod common;

use common::*;
use glam::{DMat4, DVec3};
use rangesynth::shadow::ShadowMode;

const PITCH: f64 = 0.02;

/// The stepped block: low top (label 1) at z = 0.5 over x ∈ [−2, 0], high top (label 2) at
/// z = 1.5 over x ∈ [0, 1], y ∈ [−0.75, 0.75]. The riser (x = 0, 1.0 high) shadows the low
/// top over x ∈ [−tan θ, 0]: a band tan θ / dx pixels wide on every row. In `label` mode the
/// paper's rim of false shadow may also appear within one pixel of a surface edge (x = −2,
/// 0, 1); `depth` mode has none.
fn step_shadow_band(theta_deg: f64, mode: ShadowMode) {
    // Pixel centres at x = −2.19 + 0.02·c avoid landing exactly on x = 0, −2, 1 or −tan θ.
    let s = sensor(170, 80, PITCH, [-2.19, 0.79], theta_deg);
    let out = render(&scene(s, mode, &[("builtin:step", DMat4::IDENTITY)]));
    let w = s.width as usize;
    let tan = theta_deg.to_radians().tan();
    let expected_width = 1.0 * tan / PITCH;
    let mut rows_checked = 0;
    for row in 0..s.height {
        let (_, y) = s.pixel_centre(0, row);
        if y.abs() > 0.75 - 2.0 * PITCH {
            continue;
        }
        let near_edge = |x: f64| [-2.0, 0.0, 1.0].iter().any(|e| (x - e).abs() < PITCH);
        let rim_allowed = |x: f64| mode == ShadowMode::Label && near_edge(x);
        let shadowed: Vec<f64> = (0..s.width)
            .filter(|&c| {
                let i = row as usize * w + c as usize;
                out.label_unshadowed[i] == 1 && out.label[i] == 0
            })
            .map(|c| s.pixel_centre(c, row).0)
            .filter(|&x| !(rim_allowed(x) && x < -1.5))
            .collect();
        // Exactly the pixel centres over the band (none lies on its edges).
        let expected: Vec<f64> =
            (0..s.width).map(|c| s.pixel_centre(c, row).0).filter(|&x| -tan < x && x < 0.0).collect();
        assert!((expected.len() as f64 - expected_width).abs() <= 1.0, "the band is tan θ / dx pixels wide");
        assert_eq!(shadowed, expected, "θ = {theta_deg}°, {mode:?}, row {row}: the shadowed pixels' centres");
        // Nothing else is shadowed: the high top sees the camera.
        let high_shadowed = (0..s.width)
            .filter(|&c| {
                let i = row as usize * w + c as usize;
                out.label_unshadowed[i] == 2 && out.label[i] == 0 && !rim_allowed(s.pixel_centre(c, row).0)
            })
            .count();
        assert_eq!(high_shadowed, 0, "row {row}: the high top is never in shadow ({mode:?})");
        rows_checked += 1;
    }
    assert!(rows_checked > 60);
}

#[test]
fn step_casts_a_shadow_of_height_times_tan_theta_at_45_degrees() {
    step_shadow_band(45.0, ShadowMode::Depth);
    step_shadow_band(45.0, ShadowMode::Label);
}

#[test]
fn step_casts_a_shadow_of_height_times_tan_theta_at_30_degrees() {
    step_shadow_band(30.0, ShadowMode::Depth);
    step_shadow_band(30.0, ShadowMode::Label);
}

#[test]
fn nothing_is_shadowed_at_theta_zero_and_no_shadow_pass_runs() {
    for mode in [ShadowMode::Label, ShadowMode::Depth, ShadowMode::None] {
        let s = sensor(170, 80, PITCH, [-2.19, 0.79], 0.0);
        let out = render(&scene(s, mode, &[("builtin:step", DMat4::IDENTITY)]));
        assert!(!out.shadow_pass);
        assert_eq!(out.timings.iter().map(|t| t.name).collect::<Vec<_>>(), ["range"]);
        assert_eq!(out.label, out.label_unshadowed);
        assert!(out.label.iter().any(|&l| l != 0));
    }
    // Mode none skips the shadow pass at any angle.
    let s = sensor(170, 80, PITCH, [-2.19, 0.79], 45.0);
    let out = render(&scene(s, ShadowMode::None, &[("builtin:step", DMat4::IDENTITY)]));
    assert!(!out.shadow_pass);
    assert_eq!(out.label, out.label_unshadowed);
}

/// The unit box's top face (label 1, z = 1) seen face-on, turned about z by `degrees`.
fn box_face_on(degrees: f64) {
    let s = centred_sensor(96, 96, PITCH, [0.013, -0.007], 30.0);
    let pose = DMat4::from_rotation_z(degrees.to_radians());
    let out = render(&scene(s, ShadowMode::Depth, &[("builtin:box", pose)]));
    let mut covered = 0;
    for (i, &l) in out.label_unshadowed.iter().enumerate() {
        if l != 0 {
            assert_eq!(l, 1, "only the top face is visible face-on");
            assert_eq!(out.z[i], 1.0, "pixel {i}: z must be the top face's z exactly");
            covered += 1;
        }
    }
    // Area 1 / pixel area, within the face's perimeter in pixels (4 / pitch).
    let expected = 1.0 / (PITCH * PITCH);
    let perimeter = 4.0 / PITCH;
    assert!((covered as f64 - expected).abs() <= perimeter, "{covered} pixels, expected {expected} ± {perimeter}");
    // A lone box on no ground casts its shadow on nothing: the top face sees the camera.
    assert_eq!(out.shadowed_pixels(), 0);
}

#[test]
fn box_seen_face_on_has_its_top_face_z_everywhere() {
    box_face_on(0.0);
    box_face_on(30.0);
}

#[test]
fn label_populations_equal_face_area_over_pixel_area() {
    // Step seen from above at θ = 0: low top 2 × 1.5, high top 1 × 1.5.
    let s = sensor(170, 90, PITCH, [-2.19, 0.87], 0.0);
    let out = render(&scene(s, ShadowMode::None, &[("builtin:step", DMat4::IDENTITY)]));
    let count = |label| out.label.iter().filter(|&&l| l == label).count() as f64;
    for (label, (a, b)) in [(1, (2.0, 1.5)), (2, (1.0, 1.5))] {
        let expected = a * b / (PITCH * PITCH);
        let perimeter = 2.0 * (a + b) / PITCH;
        let n = count(label);
        assert!((n - expected).abs() <= perimeter, "label {label}: {n} pixels, expected {expected} ± {perimeter}");
    }
    // A cylinder's top disc: π r² / pixel area within its circumference in pixels.
    let s = centred_sensor(64, 64, PITCH, [0.0, 0.0], 0.0);
    let out = render(&scene(s, ShadowMode::None, &[("builtin:cylinder:64", DMat4::IDENTITY)]));
    let top = out.label.iter().filter(|&&l| l == 1).count() as f64;
    let r: f64 = 0.5;
    let polygon_area = 0.5 * 64.0 * r * r * (std::f64::consts::TAU / 64.0).sin();
    let expected = polygon_area / (PITCH * PITCH);
    let circumference = std::f64::consts::TAU * r / PITCH;
    assert!((top - expected).abs() <= circumference, "disc: {top} pixels, expected {expected:.0} ± {circumference:.0}");
}

#[test]
fn step_on_a_table_shadows_the_table_on_its_minus_x_side() {
    // The low end (x = −2, 0.5 high) shadows the table over x ∈ [−2.5, −2] at 45°.
    let s = sensor(60, 40, PITCH, [-2.79, 0.39], 45.0);
    let table = DMat4::from_translation(DVec3::new(0.0, 0.0, 0.0));
    let out = render(&scene(s, ShadowMode::Depth, &[("builtin:step", DMat4::IDENTITY), ("builtin:plane:8", table)]));
    let w = s.width as usize;
    let table_label = 9; // after the step's 8 surfaces
    for row in 0..s.height as usize {
        let shadowed =
            (0..w).filter(|&c| out.label_unshadowed[row * w + c] == table_label && out.label[row * w + c] == 0).count();
        assert!(
            (shadowed as f64 - 0.5 / PITCH).abs() <= 1.0,
            "row {row}: {shadowed} shadowed table pixels, expected 25 ± 1"
        );
    }
}

/// A renderer keeps meshes, render targets and command buffers between calls: reused across
/// scenes of other sizes, models and modes, and again on the first, it renders each exactly as
/// a fresh renderer does.
#[test]
fn a_reused_renderer_renders_each_scene_as_a_fresh_one_does() {
    let scenes = [
        scene(sensor(96, 64, PITCH, [-2.0, 1.2], 30.0), ShadowMode::Depth, &[("builtin:step", DMat4::IDENTITY)]),
        scene(
            sensor(48, 80, PITCH, [-1.0, 1.5], -20.0),
            ShadowMode::Label,
            &[("builtin:plane:4", DMat4::IDENTITY), ("builtin:sphere:24", DMat4::from_translation(DVec3::X * 0.2))],
        ),
        scene(sensor(96, 64, PITCH, [-2.0, 1.2], 0.0), ShadowMode::Depth, &[("builtin:box", DMat4::IDENTITY)]),
    ];
    let reused = test_renderer(None);
    for round in 0..2 {
        for (i, sc) in scenes.iter().enumerate() {
            let again = reused.render(sc).unwrap();
            let fresh = test_renderer(None).render(sc).unwrap();
            assert_no_validation_messages();
            assert_eq!(again.label, fresh.label, "scene {i}, round {round}");
            assert_eq!(again.label_unshadowed, fresh.label_unshadowed, "scene {i}, round {round}");
            let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&again.z), bits(&fresh.z), "scene {i}, round {round}");
        }
    }
}
