//! GPU renders against the independent CPU reference (tests/common/reference.rs) over five
//! scenes × several poses, random rotations included.
//!
//! Allowances (stated, and printed with `--nocapture`):
//! - hit masks and labels: identical except within one pixel (8-neighbourhood) of a change
//!   of label in the reference: silhouettes and surface edges, where a pixel centre within
//!   the rasterizer's sub-pixel snapping of an edge may go either way;
//! - z, wherever the labels agree away from the edge band, measured from the nearest plane
//!   the rasterizer may rightly pick (the hit triangle's, or a neighbour's within 1/16 pixel of
//!   the centre, Vulkan's minimum sub-pixel precision): ≤ 1e-5 · max(1, |z_ref|) on facets within
//!   84° of face-on (|n_z| ≥ 0.1), and the same bound on the error perpendicular to the surface,
//!   |z_gpu − z_ref| · |n_z|, everywhere. On a facet seen nearly edge-on, z at a fixed pixel
//!   is ill-conditioned: one f32 ulp of lateral position moves it by ulp × slope;
//! - `depth` shadow masks: equal to exact shadowing except within one pixel of a shadow
//!   boundary, measured in the range image (8-neighbourhood) and in the camera's view, where
//!   the shadow test works: within one shadow-buffer pixel of a silhouette or surface edge as
//!   the camera sees it. The second matters at a curved surface's terminator, where the
//!   surface is tangent to the camera ray and many range pixels fall within one shadow pixel;
//! - `label` shadow masks: the paper's test evaluated exactly (shadowed where the camera sees
//!   another surface at the point, so a surface hiding part of itself goes unnoticed), with
//!   the same allowance; its rim of false shadow along surface edges lies within it. And pixel
//!   for pixel, with no allowance, against the label test as rangesynth runs it (nearest
//!   shadow pixel, or the four around p'; one or two columns a range column) evaluated on
//!   exact geometry (`reference::label_test`), wherever exact geometry decides it: everywhere
//!   but where p' lies within the f32 error of a boundary between shadow pixels or a shadow
//!   pixel's centre within a rasterizer's snapping of a change of label, and every way those
//!   may go does not give the same answer.

// Per-pixel arrays (GPU output, reference, allowances) are read side by side by pixel index.
#![allow(clippy::needless_range_loop)]

mod common;

use common::compare::{compare_labels, near_label_change, LabelDiff};
use common::reference::{label_test, reference_render, Reference};
use common::*;
use glam::{DMat4, DQuat, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangesynth::mesh::builtin_mesh;
use rangesynth::shadow::{Neighbourhood, ShadowMode, ShadowSettings};
use rangesynth::{RenderOutput, Scene};

const SIZE: u32 = 128;
const Z_TOLERANCE: f64 = 1e-5;
/// |n_z| from which the plain z bound applies (facets within 84° of face-on).
const FACE_ON_ENOUGH: f64 = 0.1;

/// Pose that rotates a model about its bounding-sphere centre and puts that centre at `at`.
fn about_centre(model: &str, rotation: DQuat, at: DVec3) -> DMat4 {
    let (centre, _) = builtin_mesh(model).expect("built-in").bounding_sphere();
    DMat4::from_translation(at) * DMat4::from_quat(rotation) * DMat4::from_translation(-centre)
}

fn random_rotation(rng: &mut ChaCha8Rng) -> DQuat {
    // Uniform on SO(3) (Shoemake).
    let (u1, u2, u3): (f64, f64, f64) = (rng.gen(), rng.gen(), rng.gen());
    let tau = std::f64::consts::TAU;
    DQuat::from_xyzw(
        (1.0 - u1).sqrt() * (tau * u2).sin(),
        (1.0 - u1).sqrt() * (tau * u2).cos(),
        u1.sqrt() * (tau * u3).sin(),
        u1.sqrt() * (tau * u3).cos(),
    )
}

/// Rotations for each scene: identity, two fixed tilts, three seeded random ones.
fn rotations(seed: u64) -> Vec<DQuat> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut r = vec![
        DQuat::IDENTITY,
        DQuat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.7),
        DQuat::from_euler(glam::EulerRot::XYZ, -0.6, 0.5, 2.1),
    ];
    r.extend((0..3).map(|_| random_rotation(&mut rng)));
    r
}

struct Checked {
    labels: LabelDiff,
    shadow: LabelDiff,
    max_z_error: f64,
    /// Pixels the label test is not checked on (label mode only): where exact geometry does
    /// not decide it, or the range view shows another surface than the reference's.
    label_test_unchecked: usize,
}

fn check(name: &str, scene: &Scene, out: &RenderOutput, reference: &Reference) -> Checked {
    let (w, h) = (reference.width, reference.height);
    let edges = near_label_change(&reference.label, w, h);
    let labels = compare_labels(&format!("{name}_labels"), w, h, &out.label_unshadowed, &reference.label, &edges);
    assert_eq!(labels.outside_allowance, 0, "{name}: {labels:?} label mismatches away from edges");

    let mut max_z_error = 0.0f64;
    for i in 0..w * h {
        if reference.label[i] != 0 && out.label_unshadowed[i] == reference.label[i] && !edges[i] {
            let (lo, hi) = reference.z_bracket[i];
            let z = f64::from(out.z[i]);
            let error = (lo - z).max(z - hi).max(0.0) / reference.z[i].abs().max(1.0);
            let perpendicular = error * reference.lit_normal[i].z;
            assert!(perpendicular <= Z_TOLERANCE, "{name}: pixel {i}: z error across the surface {perpendicular:e}");
            if reference.lit_normal[i].z >= FACE_ON_ENOUGH {
                max_z_error = max_z_error.max(error);
            }
        }
    }
    assert!(max_z_error <= Z_TOLERANCE, "{name}: z differs by {max_z_error:e} (relative) from the reference");

    let expected: Vec<u32> = match scene.shadow.mode {
        ShadowMode::None => reference.label.clone(),
        ShadowMode::Depth | ShadowMode::Exact => reference.label_shadowed(),
        ShadowMode::Label => reference.label_paper_shadowed(),
        other => panic!("the conformance suite has no reference for shadow mode {other:?}"),
    };
    let near_boundary = near_label_change(&expected, w, h);
    let allowed: Vec<bool> =
        (0..w * h).map(|i| edges[i] || near_boundary[i] || reference.near_camera_edge[i]).collect();
    let shadow = compare_labels(&format!("{name}_shadowed"), w, h, &out.label, &expected, &allowed);
    assert_eq!(shadow.outside_allowance, 0, "{name}: {shadow:?} shadow mismatches away from boundaries");

    // Label mode, pixel for pixel against the same test on exact geometry, wherever exact
    // geometry decides it and the range view shows the reference's surface.
    let label_test_unchecked = if scene.shadow.mode == ShadowMode::Label {
        let test = label_test(scene, reference);
        let unchecked: Vec<bool> =
            (0..w * h).map(|i| test.undecided[i] || out.label_unshadowed[i] != reference.label[i]).collect();
        let diff = compare_labels(&format!("{name}_label_test"), w, h, &out.label, &test.label, &unchecked);
        assert_eq!(diff.outside_allowance, 0, "{name}: {diff:?} label-test mismatches where exact geometry decides");
        diff.allowance_pixels
    } else {
        0
    };
    Checked { labels, shadow, max_z_error, label_test_unchecked }
}

/// Most pixels, summed over a model's thirty cases, that may differ from the reference inside
/// the allowance, for hit labels and for shadowed labels: each the count measured when the
/// allowance was given caps (the same with either rasterizer, on lavapipe), plus a quarter,
/// so that an error confined to the edge band, a boundary moved or widened by a pixel along
/// its length, fails where a few more pixels on a rounding tie do not. And, capped the same
/// way, the pixels the label test is not checked on, so that a reference that decided less
/// and less would fail.
struct Caps {
    labels: usize,
    shadowed: usize,
    label_test_unchecked: usize,
}

fn conformance(name: &str, objects: &[(&str, DVec3)], extent: f64, seed: u64, caps: Caps) {
    let pitch = extent / f64::from(SIZE);
    let mut totals = (LabelDiff::default(), LabelDiff::default(), 0.0f64, 0usize);
    // Mode, θ, and the label test's settings: the paper's (nearest pixel, one column a range
    // column) and the finest (four pixels around p', two columns).
    let paper = ShadowSettings::of(ShadowMode::Label);
    let finest = ShadowSettings { columns: 2, neighbourhood: Neighbourhood::Square2, ..paper };
    let cases = [
        (ShadowSettings::of(ShadowMode::None), 0.0),
        (ShadowSettings::of(ShadowMode::Depth), 45.0),
        (paper, 45.0),
        (ShadowSettings::of(ShadowMode::Depth), -30.0),
        (finest, -30.0),
    ];
    for (k, rotation) in rotations(seed).into_iter().enumerate() {
        for (shadow, theta) in cases {
            let posed: Vec<(&str, DMat4)> =
                objects.iter().map(|&(model, at)| (model, about_centre(model, rotation, at))).collect();
            let s = centred_sensor(SIZE, SIZE, pitch, [0.0, 0.0], theta);
            let scene = Scene { shadow, ..scene(s, shadow.mode, &posed) };
            let out = render(&scene);
            let reference = reference_render(&scene);
            let case = format!("{name}_pose{k}_{}_{}_{theta}", shadow.mode.as_str(), shadow.columns);
            let c = check(&case, &scene, &out, &reference);
            assert!(out.label_unshadowed.iter().any(|&l| l != 0), "{case}: the model is in view");
            for (total, d) in [(&mut totals.0, c.labels), (&mut totals.1, c.shadow)] {
                total.pixels += d.pixels;
                total.mismatched += d.mismatched;
                total.allowance_pixels += d.allowance_pixels;
            }
            totals.2 = totals.2.max(c.max_z_error);
            totals.3 += c.label_test_unchecked;
        }
    }
    eprintln!(
        "{name}: labels {} mismatches in {} edge-allowance pixels of {}; shadowed labels {} in {}; max relative z error {:e}; label test not checked on {} pixels",
        totals.0.mismatched, totals.0.allowance_pixels, totals.0.pixels, totals.1.mismatched, totals.1.allowance_pixels, totals.2, totals.3
    );
    assert!(
        totals.0.mismatched <= caps.labels,
        "{name}: {} label mismatches, more than {}",
        totals.0.mismatched,
        caps.labels
    );
    assert!(
        totals.1.mismatched <= caps.shadowed,
        "{name}: {} shadowed-label mismatches, more than {}",
        totals.1.mismatched,
        caps.shadowed
    );
    assert!(
        totals.3 <= caps.label_test_unchecked,
        "{name}: the label test is not checked on {} pixels, more than {}",
        totals.3,
        caps.label_test_unchecked
    );
}

#[test]
fn box_matches_the_reference() {
    conformance(
        "box",
        &[("builtin:box", DVec3::new(0.0, 0.0, 0.0))],
        2.0,
        1,
        Caps { labels: 13, shadowed: 403, label_test_unchecked: 1084 },
    );
}

#[test]
fn stepped_block_matches_the_reference() {
    conformance(
        "step",
        &[("builtin:step", DVec3::ZERO)],
        4.4,
        2,
        Caps { labels: 25, shadowed: 1119, label_test_unchecked: 1774 },
    );
}

#[test]
fn cylinder_matches_the_reference() {
    conformance(
        "cylinder",
        &[("builtin:cylinder:24", DVec3::ZERO)],
        1.8,
        3,
        Caps { labels: 2, shadowed: 705, label_test_unchecked: 2655 },
    );
}

#[test]
fn sphere_matches_the_reference() {
    conformance(
        "sphere",
        &[("builtin:sphere:32", DVec3::ZERO)],
        1.3,
        4,
        Caps { labels: 2, shadowed: 1904, label_test_unchecked: 3408 },
    );
}

#[test]
fn cluttered_scene_matches_the_reference() {
    conformance(
        "clutter",
        &[
            ("builtin:step", DVec3::new(-0.4, 0.6, 0.0)),
            ("builtin:box", DVec3::new(1.3, -0.9, 0.3)),
            ("builtin:cylinder:16", DVec3::new(-1.2, -1.1, -0.2)),
            ("builtin:sphere:24", DVec3::new(0.6, -0.2, 1.0)),
            ("builtin:sphere:12", DVec3::new(1.5, 1.4, -0.6)),
        ],
        5.0,
        5,
        Caps { labels: 63, shadowed: 1254, label_test_unchecked: 3780 },
    );
}
