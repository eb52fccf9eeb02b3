//! One line of `verify`'s JSON-lines output: a hypothesis' scores with the counts they came
//! from (docs/design.md "Interfaces").

use super::{Counts, Scores, SensedImage, Verification};
use serde::Serialize;

#[derive(Serialize)]
pub struct Record<'a> {
    pub id: &'a str,
    #[serde(flatten)]
    pub scores: ScoresRecord<'a>,
    /// With `--compare-shadow`: the same hypothesis scored without shadowing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unshadowed: Option<ScoresRecord<'a>>,
}

/// s1…s6, s, rejected, notes and bindings, then the counts.
#[derive(Serialize)]
pub struct ScoresRecord<'a> {
    #[serde(flatten)]
    pub scores: &'a Scores,
    pub counts: CountsRecord,
}

#[derive(Serialize)]
pub struct CountsRecord {
    pub n1_plus: u64,
    pub n1_minus: u64,
    /// N_i, N_s: valid pixels of the sensed and the synthetic image.
    pub n_i: u64,
    pub n_s: u64,
    /// Synthetic valid where the sensed image is not, and the reverse.
    pub n0: u64,
    pub n1: u64,
    /// Every non-zero t: [scene label, model surface, pixels].
    pub overlaps: Vec<[u64; 3]>,
    /// N_M of each model surface, surface 1 first.
    pub surface_population: Vec<u64>,
}

impl<'a> Record<'a> {
    pub fn new(v: &'a Verification, sensed: &SensedImage) -> Self {
        let scores = |counts: &'a Counts, scores: &'a Scores| ScoresRecord {
            scores,
            counts: CountsRecord {
                n1_plus: counts.n1_plus,
                n1_minus: counts.n1_minus,
                n_i: sensed.valid,
                n_s: counts.synthetic_valid(),
                n0: counts.n0,
                n1: counts.n1,
                overlaps: counts
                    .overlap
                    .iter()
                    .map(|&((k, m), t)| [u64::from(sensed.segments[k as usize]), u64::from(m), t])
                    .collect(),
                surface_population: counts.surface_population.clone(),
            },
        };
        Record {
            id: &v.id,
            scores: scores(&v.counts, &v.scores),
            unshadowed: v.unshadowed.as_ref().map(|(c, s)| scores(c, s)),
        }
    }
}
