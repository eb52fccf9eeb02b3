//! The paper's six scores (§4) from exact counts, in f64, with the decisions of docs/design.md
//! "Verification scores": s4's middle case is 1/r, s5 follows the formula as printed, s2 is a
//! sum of logs. Every score is defined for every input (never NaN), with a reason wherever
//! a rule forces it to zero.
//!
//! A binding whose scene segment or model surface has no pixels (a surface facing away, fully
//! shadowed, or a segment missing from the sensed image) takes no part in s2 and s4: this is
//! what the paper's Fig. 6 example reports (shadowing removed model segment 1 and s2 *rose*).
//! Such bindings are listed in `absent_bindings`.

use super::counts::Counts;
use super::sensed::SensedImage;
use serde::Serialize;

#[derive(Debug, Clone, PartialEq, Serialize)]
#[non_exhaustive]
pub struct Scores {
    pub s1: f64,
    pub s2: f64,
    pub s3: f64,
    pub s4: f64,
    pub s5: f64,
    pub s6: f64,
    /// Π s_k, or 0 when rejected.
    pub s: f64,
    /// Why the hypothesis was rejected (s4: a binding with area ratio above 2; s5: N_i/N_s
    /// above 2 or an empty synthetic image), or null.
    pub rejected: Option<String>,
    /// Why a score is 0 or a binding was left out, for people reading the output.
    pub notes: Vec<String>,
    pub bindings: Vec<BindingDetail>,
}

impl Scores {
    /// Bytes its texts and bindings hold on the heap.
    pub(crate) fn heap_bytes(&self) -> u64 {
        let texts = self.rejected.iter().chain(&self.notes).map(String::capacity).sum::<usize>();
        (texts + self.notes.capacity() * size_of::<String>() + self.bindings.capacity() * size_of::<BindingDetail>())
            as u64
    }
}

/// The numbers behind one binding's factors in s2, s3 and s4.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BindingDetail {
    pub scene_label: u32,
    pub model_surface: u32,
    /// t: pixels where both carry this binding's labels.
    pub overlap: u64,
    pub scene_population: u64,
    pub model_population: u64,
    pub scene_area: f64,
    pub model_area: f64,
    /// Whether the segment or the surface has no pixels (left out of s2 and s4).
    pub absent: bool,
}

/// Scores a hypothesis' counts against the sensed image for its bindings (scene label, model
/// surface). Duplicate bindings count once.
pub fn score(counts: &Counts, sensed: &SensedImage, bindings: &[(u32, u32)]) -> Scores {
    let mut notes = Vec::new();
    let mut rejected: Option<String> = None;
    let mut bound: Vec<(u32, u32)> = bindings.to_vec();
    bound.sort_unstable();
    bound.dedup();

    let n_i = sensed.valid;
    let n_s = counts.synthetic_valid();
    let overlap_of = |k: u32, m: u32| {
        counts.overlap.binary_search_by_key(&(k, m), |&(key, _)| key).map_or(0, |i| counts.overlap[i].1)
    };
    let details: Vec<BindingDetail> = bound
        .iter()
        .map(|&(scene_label, surface)| {
            let k = sensed.segment_index(scene_label);
            let m_index = surface.checked_sub(1).map(|m| m as usize);
            let model_population = m_index.and_then(|m| counts.surface_population.get(m)).copied().unwrap_or(0);
            let model_units = m_index.and_then(|m| counts.surface_area_units.get(m)).copied().unwrap_or(0);
            let (scene_population, scene_units, overlap) = match k {
                Some(k) => (
                    sensed.segment_population[k as usize],
                    sensed.segment_area_units[k as usize],
                    overlap_of(k, surface),
                ),
                None => (0, 0, 0),
            };
            BindingDetail {
                scene_label,
                model_surface: surface,
                overlap,
                scene_population,
                model_population,
                scene_area: sensed.blocks.area(scene_units),
                model_area: sensed.blocks.area(model_units),
                absent: scene_population == 0 || model_population == 0,
            }
        })
        .collect();
    for d in details.iter().filter(|d| d.absent) {
        notes.push(format!(
            "binding ({}, {}) left out of s2 and s4: the {} has no pixels",
            d.scene_label,
            d.model_surface,
            if d.scene_population == 0 { "scene segment" } else { "model surface" }
        ));
    }
    if bound.is_empty() {
        notes.push("the hypothesis has no bindings".into());
    }

    // s1: depth agreement over pixels valid in both.
    let s1 = match counts.n1_plus.saturating_add(counts.n1_minus) {
        0 => {
            notes.push("s1 = 0: no pixel is valid in both images".into());
            0.0
        }
        n => counts.n1_plus as f64 / n as f64,
    };

    // s2: Π over bound pairs of t²/(N_M·N_S), over unbound overlapping pairs of 1 − t²/(N_M·N_S).
    let is_bound =
        |k: u32, m: u32| sensed.segments.get(k as usize).is_some_and(|&label| bound.binary_search(&(label, m)).is_ok());
    let mut log_s2 = 0.0f64;
    for &((k, m), t) in &counts.overlap {
        if !is_bound(k, m) {
            let scene = sensed.segment_population.get(k as usize).copied().unwrap_or(0);
            let model = m.checked_sub(1).and_then(|m| counts.surface_population.get(m as usize)).copied().unwrap_or(0);
            let x = fraction(t, scene, model);
            log_s2 += (-x).ln_1p();
        }
    }
    for d in details.iter().filter(|d| !d.absent) {
        log_s2 += fraction(d.overlap, d.scene_population, d.model_population).ln();
    }
    let s2 = log_s2.exp();

    // s3: bound overlap / all overlap.
    let all_overlap: u64 = counts.overlap.iter().map(|&(_, t)| t).sum();
    let bound_overlap: u64 = details.iter().map(|d| d.overlap).sum();
    let s3 = if all_overlap == 0 {
        notes.push("s3 = 0: no segment overlaps a model surface".into());
        0.0
    } else {
        bound_overlap as f64 / all_overlap as f64
    };

    // s4: Π over bindings of r (r ≤ 1) or 1/r (1 < r ≤ 2); r > 2 rejects.
    let mut s4 = 1.0;
    for d in details.iter().filter(|d| !d.absent) {
        if d.scene_area == 0.0 && d.model_area == 0.0 {
            notes.push(format!(
                "binding ({}, {}) left out of s4: neither has a 2×2 block of pixels",
                d.scene_label, d.model_surface
            ));
            continue;
        }
        let r = d.scene_area / d.model_area;
        if r <= 1.0 {
            s4 *= r;
        } else if r <= 2.0 {
            s4 *= 1.0 / r;
        } else {
            s4 = 0.0;
            rejected.get_or_insert(format!(
                "s4: binding ({}, {}) has area ratio A_S/A_M = {} > 2",
                d.scene_label,
                d.model_surface,
                if r.is_finite() { format!("{r:.4}") } else { "∞".into() }
            ));
        }
    }

    // s5: valid-pixel counts, as printed.
    let s5 = if n_s == 0 {
        rejected.get_or_insert("s5: the synthetic image has no valid pixel".into());
        0.0
    } else if n_i < n_s {
        n_i as f64 / n_s as f64
    } else if n_i <= 2 * n_s {
        n_s as f64 / n_i as f64
    } else {
        rejected.get_or_insert(format!("s5: N_i/N_s = {n_i}/{n_s} > 2"));
        0.0
    };

    // s6: (N_i − N0)(N_s − N1)/(N_i·N_s), clamped to [0, 1].
    let s6 = if n_i == 0 || n_s == 0 {
        notes.push("s6 = 0: an image has no valid pixel".into());
        0.0
    } else {
        let numerator = (i128::from(n_i) - i128::from(counts.n0)) * (i128::from(n_s) - i128::from(counts.n1));
        (numerator as f64 / (n_i as f64 * n_s as f64)).clamp(0.0, 1.0)
    };

    let product = s1 * s2 * s3 * s4 * s5 * s6;
    Scores {
        s1,
        s2,
        s3,
        s4,
        s5,
        s6,
        s: if rejected.is_some() { 0.0 } else { product },
        rejected,
        notes,
        bindings: details,
    }
}

/// t² / (N_S·N_M) in f64; every value is at most the pixel count, so the products are exact.
/// Counts from the GPU keep t ≤ min(N_S, N_M), so this is at most 1; counts a caller made up
/// are clamped to [0, 1] so that no score can become NaN.
fn fraction(t: u64, scene: u64, model: u64) -> f64 {
    let x = (t as f64 * t as f64) / (scene as f64 * model as f64);
    if x.is_nan() {
        0.0
    } else {
        x.clamp(0.0, 1.0)
    }
}
