//! The Visible Surface Discrepancy (Hodaň et al.), exactly as the BOP toolkit defines it
//! (`bop_toolkit_lib/pose_error.py`, `vsd`, and `visibility.py`, in its 'bop19' visibility
//! mode with the step cost, distances normalised by the object's diameter):
//!
//! 1. The depth images (mm; 0 where nothing) of the test scene and of the model rendered alone
//!    in the estimated and the ground-truth pose become distance images: the length of each
//!    pixel's point, √(X² + Y² + Z²) with X = ((c − cx)/fx)·Z, Y = ((r − cy)/fy)·Z, in f64 and
//!    in that order (`misc.depth_im_to_dist_im_fast`). The test depth is read as the toolkit
//!    reads it: the PNG's value times `depth_scale` in f32 (src/bop/mod.rs).
//! 2. The ground truth is visible where it was rendered and its distance is at most δ beyond
//!    the test's, or the test has no measurement there ('bop19': a missing measurement counts
//!    as visible; the difference is taken in f32, as the toolkit takes it). The estimate is
//!    visible by the same test, and also wherever the ground truth is visible and the estimate
//!    was rendered.
//! 3. For each τ: e = (the pixels of both masks whose distances differ by at least
//!    τ·diameter, plus the pixels of one mask only) / the pixels of either mask; e = 1 where
//!    neither mask has a pixel.
//!
//! τ runs over 0.05, 0.10, …, 0.50 (the toolkit's `np.arange(0.05, 0.51, 0.05)`), and so does
//! the correctness threshold θ of BOP's recall: an error counts as correct where e < θ.

use crate::error::{Error, Result};

/// The ten misalignment tolerances τ, and the ten correctness thresholds θ: 0.05 + k·0.05 in
/// f64, as numpy's arange computes them.
pub fn tolerances() -> [f64; 10] {
    std::array::from_fn(|k| 0.05 + k as f64 * 0.05)
}

/// One image's geometry for VSD: its size and intrinsics.
#[derive(Debug, Clone, Copy)]
pub struct VsdView {
    pub width: usize,
    pub height: usize,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

impl VsdView {
    /// The distance of pixel i's point at depth z (mm), as the toolkit's
    /// `depth_im_to_dist_im_fast` computes each pixel of a distance image.
    fn distance(&self, i: usize, z: f64) -> f64 {
        let (c, r) = ((i % self.width) as f64, (i / self.width) as f64);
        let x = (c - self.cx) / self.fx * z;
        let y = (r - self.cy) / self.fy * z;
        (x * x + y * y + z * z).sqrt()
    }
}

/// The toolkit's 'bop19' visibility test of a rendered distance against the test's.
fn visible(model: f64, test: f64, delta: f64) -> bool {
    ((model as f32 - test as f32) <= delta as f32 || test == 0.0) && model > 0.0
}

/// The ten VSD errors, one for each of [`tolerances`], of the estimate's depth image against
/// the ground truth's, in the test image, for an object of `diameter` (mm) with visibility
/// tolerance `delta` (mm). The depth images are row by row, `view.width` a row; images of
/// another size are refused.
pub fn vsd_errors(
    view: &VsdView,
    test: &[f64],
    estimate: &[f64],
    truth: &[f64],
    diameter: f64,
    delta: f64,
) -> Result<[f64; 10]> {
    let pixels = view.width * view.height;
    if [test.len(), estimate.len(), truth.len()] != [pixels; 3] {
        return Err(Error::Scene(format!(
            "VSD of a {}×{} view takes images of {pixels} pixels; these have {}, {} and {}",
            view.width,
            view.height,
            test.len(),
            estimate.len(),
            truth.len()
        )));
    }
    let mut differences = Vec::new();
    let (mut union, mut intersection) = (0usize, 0usize);
    // Only a rendered pixel can be visible: the others' distances are never read.
    for i in (0..test.len()).filter(|&i| estimate[i] > 0.0 || truth[i] > 0.0) {
        let distance = |depth: &[f64]| view.distance(i, depth[i]);
        let (test, estimate, truth) = (distance(test), distance(estimate), distance(truth));
        let truth_visible = visible(truth, test, delta);
        let estimate_visible = visible(estimate, test, delta) || (truth_visible && estimate > 0.0);
        if truth_visible || estimate_visible {
            union += 1;
        }
        if truth_visible && estimate_visible {
            intersection += 1;
            differences.push((truth - estimate).abs() / diameter);
        }
    }
    Ok(tolerances().map(|tau| match union {
        0 => 1.0,
        _ => {
            let costly = differences.iter().filter(|&&d| d >= tau).count();
            (costly + union - intersection) as f64 / union as f64
        }
    }))
}

/// A row's VSD as `rangesynth bop` reports it: the mean of its ten errors, and the fraction of
/// the 100 pairs (τ, θ) whose error is below θ (the row's share of BOP's AR_VSD).
pub fn vsd_summary(errors: &[f64; 10]) -> (f64, f64) {
    let mean = errors.iter().sum::<f64>() / 10.0;
    let thresholds = tolerances();
    let correct = errors.iter().map(|&e| thresholds.iter().filter(|&&theta| e < theta).count()).sum::<usize>();
    (mean, correct as f64 / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tolerances are numpy's arange(0.05, 0.51, 0.05): its third is 0.15000000000000002.
    #[test]
    fn the_tolerances_are_numpys() {
        let t = tolerances();
        assert_eq!(t[0], 0.05);
        assert_eq!(t[2], 0.15000000000000002);
        assert!((t[9] - 0.5).abs() < 1e-15);
    }

    /// An error of 0.0784 is below nine of the ten thresholds (0.10 up); an error of 1 below
    /// none: four errors of 1 and six of 0.0784 give a recall of 54/100.
    #[test]
    fn the_recall_counts_pairs_below_their_threshold() {
        let errors = [1.0, 1.0, 1.0, 1.0, 0.0784, 0.0784, 0.0784, 0.0784, 0.0784, 0.0784];
        let (mean, recall) = vsd_summary(&errors);
        assert!((mean - 0.44704).abs() < 1e-12);
        assert_eq!(recall, 0.54);
    }
}
