//! The six scores on tiny hand-made inputs, each expected value worked out by hand from
//! docs/design.md "Verification scores". CPU only: counts are given directly.

use rangesynth::io::RangeImage;
use rangesynth::sensor::{Scanner, Sensor};
use rangesynth::verify::{score, Counts, SensedImage};

const PITCH: f64 = 0.5;

fn sensor(width: u32, height: u32) -> Sensor {
    Scanner { width, height, pitch: [PITCH, PITCH], origin: [0.0, 0.0], theta_deg: 45.0 }.into()
}

/// A sensed image from rows of labels (0 = no data), flat at z = 1.
fn sensed(rows: &[&[u32]]) -> SensedImage {
    let (w, h) = (rows[0].len() as u32, rows.len() as u32);
    let label: Vec<u32> = rows.iter().flat_map(|r| r.iter().copied()).collect();
    let z = label.iter().map(|&l| if l == 0 { f32::NAN } else { 1.0 }).collect::<Vec<_>>();
    let image = RangeImage {
        width: w,
        height: h,
        x: z.clone(),
        y: z.clone(),
        z,
        label,
        reason: None,
        witness: None,
        sensor: None,
        shadow: None,
        effects: None,
    };
    SensedImage::new(&image, &sensor(w, h)).unwrap()
}

/// Units of a flat area of `pixels` pixel areas.
fn units(pixels: u64) -> u64 {
    pixels * 65536
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300)
}

/// Sensed segments 10 (4 pixels, a 2×2 block: area 1 pixel) and 20 (2 pixels, no block).
fn two_segments() -> SensedImage {
    sensed(&[&[10, 10, 20], &[10, 10, 20], &[0, 0, 0]])
}

#[test]
fn each_score_by_hand() {
    let s = two_segments();
    assert_eq!(
        (s.valid, s.segment_population.clone(), s.segment_area_units.clone()),
        (6, vec![4, 2], vec![units(1), 0])
    );
    // Model surfaces 1 (4 px) and 2 (3 px); overlaps: (10,1) = 3, (20,1) = 1, (20,2) = 1.
    let counts = Counts {
        n1_plus: 3,
        n1_minus: 1,
        n0: 2,
        n1: 1,
        surface_population: vec![4, 3],
        overlap: vec![((0, 1), 3), ((1, 1), 1), ((1, 2), 1)],
        surface_area_units: vec![units(2), units(1)],
    };
    let r = score(&counts, &s, &[(10, 1), (20, 2)]);
    assert!(close(r.s1, 3.0 / 4.0), "s1 {}", r.s1);
    // bound (10,1): 3²/(4·4); bound (20,2): 1²/(2·3); unbound (20,1): 1 − 1²/(2·4).
    let s2 = (9.0 / 16.0) * (1.0 / 6.0) * (1.0 - 1.0 / 8.0);
    assert!(close(r.s2, s2), "s2 {} vs {s2}", r.s2);
    assert!(close(r.s3, 4.0 / 5.0), "s3 {}", r.s3);
    // (10,1): r = 1/2 → ½; (20,2): A_S = 0, A_M = 1 → r = 0 → 0.
    assert_eq!(r.s4, 0.0);
    // N_i = 6 < N_s = 7 → 6/7.
    assert!(close(r.s5, 6.0 / 7.0));
    // (6 − 2)(7 − 1)/(6·7)
    assert!(close(r.s6, 24.0 / 42.0));
    assert_eq!(r.s, 0.0);
    assert_eq!(r.rejected, None);
}

fn one_binding_counts(model_area_units: u64, population: u64) -> Counts {
    Counts {
        n1_plus: 4,
        n1_minus: 0,
        n0: 0,
        n1: 0,
        surface_population: vec![population],
        overlap: vec![((0, 1), population.min(4))],
        surface_area_units: vec![model_area_units],
    }
}

#[test]
fn s4_at_ratios_exactly_1_and_2_and_beyond() {
    let s = sensed(&[&[10, 10], &[10, 10]]); // A_S = 1 pixel area
    let at = |model_units| score(&one_binding_counts(model_units, 4), &s, &[(10, 1)]);
    assert_eq!(at(units(1)).s4, 1.0, "r = 1 → 1");
    assert_eq!(at(units(2)).s4, 0.5, "r = 1/2 → 1/2");
    let half = at(units(1) / 2); // r = 2 exactly → 1/r
    assert_eq!(half.s4, 0.5);
    assert_eq!(half.rejected, None);
    let beyond = at(units(1) / 2 - 1); // r just above 2 → rejected
    assert_eq!(beyond.s4, 0.0);
    assert_eq!(beyond.s, 0.0);
    assert!(beyond.rejected.as_deref().unwrap().contains("> 2"), "{:?}", beyond.rejected);
}

/// s4 leaves out a binding where neither the segment nor the surface has a 2×2 block (A_S =
/// A_M = 0: no ratio), and rejects one whose surface has no block where its segment has one
/// (r = ∞).
#[test]
fn s4_leaves_out_a_binding_without_blocks_and_rejects_one_whose_surface_has_none() {
    let blockless = sensed(&[&[10, 10, 10, 10]]); // A_S = 0
    let neither = score(&one_binding_counts(0, 4), &blockless, &[(10, 1)]);
    assert_eq!((neither.s4, neither.rejected.clone()), (1.0, None), "left out: s4 stays 1");
    assert!(neither.notes.iter().any(|n| n.contains("left out of s4")), "{:?}", neither.notes);
    let s = sensed(&[&[10, 10], &[10, 10]]); // A_S = 1 pixel area
    let surface_only_thin = score(&one_binding_counts(0, 4), &s, &[(10, 1)]);
    assert_eq!(surface_only_thin.s4, 0.0);
    assert!(surface_only_thin.rejected.as_deref().unwrap().contains("∞"), "{:?}", surface_only_thin.rejected);
}

#[test]
fn s5_at_ratio_exactly_2_and_beyond() {
    let s = sensed(&[&[10, 10], &[10, 10]]); // N_i = 4
    let with_ns = |ns: u64| score(&one_binding_counts(units(1), ns), &s, &[(10, 1)]);
    assert_eq!(with_ns(2).s5, 0.5, "N_i/N_s = 2 → N_s/N_i");
    assert_eq!(with_ns(2).rejected, None);
    assert_eq!(with_ns(4).s5, 1.0);
    assert_eq!(with_ns(8).s5, 0.5, "N_i < N_s → N_i/N_s");
    let too_few = with_ns(1); // N_i/N_s = 4 > 2
    assert_eq!((too_few.s5, too_few.s), (0.0, 0.0));
    assert!(too_few.rejected.as_deref().unwrap().contains("N_i/N_s = 4/1 > 2"));
}

#[test]
fn s6_with_a_negative_numerator_is_zero() {
    let s = sensed(&[&[10, 0], &[0, 0]]); // N_i = 1
                                          // N_s = 3, N0 = 3 (none overlaps): N_i − N0 = −2.
    let counts =
        Counts { n0: 3, n1: 1, surface_population: vec![3], surface_area_units: vec![0], ..Default::default() };
    let r = score(&counts, &s, &[(10, 1)]);
    assert_eq!(r.s6, 0.0);
    assert!(r.s.is_finite());
}

#[test]
fn empty_images_and_missing_bindings_give_defined_scores_and_reasons() {
    let empty = sensed(&[&[0, 0], &[0, 0]]);
    let nothing = Counts { surface_population: vec![0, 0], surface_area_units: vec![0, 0], ..Default::default() };
    let r = score(&nothing, &empty, &[(10, 1)]);
    for v in [r.s1, r.s2, r.s3, r.s4, r.s5, r.s6, r.s] {
        assert!(v.is_finite(), "{r:?}");
    }
    assert_eq!(r.s, 0.0);
    assert!(r.rejected.as_deref().unwrap().contains("no valid pixel"));

    // One image empty, the other not: s6 = 0 with a note, either way round.
    let s = sensed(&[&[10, 10], &[10, 10]]);
    for (counts, sensed) in [(&nothing, &s), (&one_binding_counts(units(1), 4), &empty)] {
        let r = score(counts, sensed, &[(10, 1)]);
        assert_eq!(r.s6, 0.0, "{r:?}");
        assert!(r.notes.iter().any(|n| n.contains("s6 = 0")), "{:?}", r.notes);
    }

    // No bindings: s3 = 0 with a note; nothing is NaN.
    let r = score(&one_binding_counts(units(1), 4), &s, &[]);
    assert_eq!(r.s3, 0.0);
    assert!(r.notes.iter().any(|n| n.contains("no bindings")));
    assert!(r.s2.is_finite() && r.s == 0.0);

    // A binding to a model surface absent from the image (2 has no pixels) is left out.
    let counts = Counts {
        surface_population: vec![4, 0],
        surface_area_units: vec![units(1), 0],
        ..one_binding_counts(units(1), 4)
    };
    let with = score(&counts, &s, &[(10, 1), (10, 2)]);
    let without = score(&counts, &s, &[(10, 1)]);
    assert_eq!((with.s2, with.s4), (without.s2, without.s4));
    assert!(with
        .notes
        .iter()
        .any(|n| n.contains("binding (10, 2) left out") && n.contains("model surface has no pixels")));
    assert!(with.bindings.iter().any(|b| b.model_surface == 2 && b.absent));
    // And a binding to a scene label the image lacks.
    let r = score(&counts, &s, &[(10, 1), (99, 1)]);
    assert!(r.notes.iter().any(|n| n.contains("binding (99, 1)") && n.contains("scene segment has no pixels")));
}

#[test]
fn s2_over_300_segments_does_not_underflow() {
    // 400 segments of 2 pixels each; model surface 1 has 800 pixels; each segment overlaps it
    // fully: 400 unbound factors of 1 − 2²/(2·800) = 1 − 1/400, and one bound pair.
    let row: Vec<u32> = (1..=400).flat_map(|l| [l, l]).collect();
    let s = sensed(&[&row]);
    let counts = Counts {
        n1_plus: 800,
        surface_population: vec![800],
        overlap: (0..400).map(|k| ((k, 1), 2)).collect(),
        surface_area_units: vec![0],
        ..Default::default()
    };
    let r = score(&counts, &s, &[(1, 1)]);
    let expected = (4.0 / 1600.0) * (1.0f64 - 1.0 / 400.0).powi(399);
    assert!(close(r.s2, expected), "{} vs {expected}", r.s2);
    // 300 segments of 2 pixels, each overlapping its own 1-pixel model surface once, unbound:
    // 300 factors of 1 − 1²/(2·1) = ½, so s2 = 2^−300 ≈ 4.9e−91, far below what an f32
    // product can hold (it underflows after 150 factors).
    let row: Vec<u32> = (1..=300).flat_map(|l| [l, l]).collect();
    let s = sensed(&[&row]);
    let counts = Counts {
        surface_population: vec![1; 300],
        overlap: (0..300).map(|k| ((k, k + 1), 1)).collect(),
        surface_area_units: vec![0; 300],
        ..Default::default()
    };
    let r = score(&counts, &s, &[]);
    assert!(close(r.s2, 2f64.powi(-300)), "{} vs 2^-300", r.s2);
    // Bound instead, each pair's factor is 1²/(2·1) = ½ too.
    let bindings: Vec<(u32, u32)> = (1..=300).map(|l| (l, l)).collect();
    assert!(close(score(&counts, &s, &bindings).s2, 2f64.powi(-300)));
}

mod any_counts {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Whatever the counts (even inconsistent ones a caller made up, naming segments and
        /// surfaces that do not exist), scoring does not panic, every score is a number in
        /// [0, 1], and a rejected hypothesis has s = 0.
        #[test]
        fn scores_are_never_nan_and_stay_in_0_1(
            labels in proptest::collection::vec(0u32..4, 9),
            scalars in proptest::collection::vec(0u64..20, 4),
            populations in proptest::collection::vec(0u64..20, 3),
            overlaps in proptest::collection::vec(((0u32..6, 0u32..6), 0u64..20), 0..8),
            areas in proptest::collection::vec(0u64..200_000, 3),
            bindings in proptest::collection::vec((0u32..5, 1u32..4), 0..4),
        ) {
            let rows: Vec<&[u32]> = labels.chunks(3).collect();
            let s = sensed(&rows);
            let mut overlap: Vec<((u32, u32), u64)> = overlaps
                .into_iter()
                .filter(|&(_, t)| t > 0)
                .collect();
            overlap.sort_unstable_by_key(|&(key, _)| key);
            overlap.dedup_by_key(|&mut (key, _)| key);
            let counts = Counts {
                n1_plus: scalars[0],
                n1_minus: scalars[1],
                n0: scalars[2],
                n1: scalars[3],
                surface_population: populations,
                overlap,
                surface_area_units: areas,
            };
            let r = score(&counts, &s, &bindings);
            for v in [r.s1, r.s2, r.s3, r.s4, r.s5, r.s6, r.s] {
                prop_assert!(v.is_finite() && (0.0..=1.0).contains(&v), "{:?}", r);
            }
            if r.rejected.is_some() {
                prop_assert_eq!(r.s, 0.0);
            }
        }
    }
}
