//! Depth-only verification scores: a hypothesis against an unsegmented depth image, as BOP's
//! images are (docs/bop.md, "Depth-only scores").
//!
//! The hypothesis is rendered under the sensor's rig, so its image predicts two things: where
//! the sensor measured the model's surface (the valid pixels, after the rig's witnesses have
//! shadowed what they cannot see), and where the rig left holes on the model (pixels the
//! reference view sees on the model that a witness does not: the model's own projector
//! shadows). Each prediction is checked against the sensed depth, within δ:
//!
//! - at a valid pixel, a sensed depth within δ of the model's is an **inlier**; one more than δ
//!   *beyond* it is a **violation** (the sensor saw through where the model stands: evidence
//!   against the pose that no occlusion explains); one more than δ *nearer* is occluded
//!   (something else stands in front: no evidence either way); no measurement is missing;
//! - at a shadowed pixel, no measurement is an **explained hole**.
//!
//! `inlier` and `violation` are fractions of the valid pixels; `explained_holes` the fraction
//! of shadowed pixels the sensor left empty (none where the rig shadows nothing);
//! `depth_score` = (inliers + explained holes) / (valid pixels − occluded + shadowed pixels):
//! the share of the predictions the image could confirm that it did confirm. Without the rig's
//! shadows, the shadowed pixels would be valid, and the holes the sensor left there would count
//! as missing measurements against the pose; with them, those holes count for it.

/// One hypothesis' image, per pixel of the sensed image: its depth (mm) where its reference
/// view meets the model, 0 elsewhere, and whether the rig's witnesses all see that point.
pub struct Prediction<'a> {
    pub depth: &'a [f64],
    pub measured: &'a [bool],
}

/// The scores of one hypothesis; `explained_holes` is `None` where the rig shadows nothing of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthScores {
    pub inlier: f64,
    pub violation: f64,
    pub explained_holes: Option<f64>,
    pub depth_score: f64,
}

/// Scores a prediction against the sensed depth (mm, 0 where nothing was measured) with
/// tolerance `delta` (mm).
pub fn depth_scores(prediction: &Prediction, sensed: &[f64], delta: f64) -> DepthScores {
    let (mut valid, mut inliers, mut violations, mut occluded) = (0u64, 0u64, 0u64, 0u64);
    let (mut shadowed, mut explained) = (0u64, 0u64);
    for ((&depth, &measured), &sensed) in prediction.depth.iter().zip(prediction.measured).zip(sensed) {
        if depth <= 0.0 {
            continue;
        }
        if !measured {
            shadowed += 1;
            explained += u64::from(sensed == 0.0);
            continue;
        }
        valid += 1;
        if sensed == 0.0 {
            continue;
        }
        let beyond = sensed - depth;
        match beyond {
            b if b.abs() <= delta => inliers += 1,
            b if b > delta => violations += 1,
            _ => occluded += 1,
        }
    }
    let fraction = |n: u64, of: u64| if of == 0 { 0.0 } else { n as f64 / of as f64 };
    DepthScores {
        inlier: fraction(inliers, valid),
        violation: fraction(violations, valid),
        explained_holes: (shadowed > 0).then(|| fraction(explained, shadowed)),
        depth_score: fraction(inliers + explained, valid - occluded + shadowed),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ten pixels: four inliers (one at exactly δ), one violation, one occluded, one missing,
    /// two shadowed of which one the sensor left empty, one off the model.
    #[test]
    fn each_pixel_counts_as_the_module_says() {
        let depth = [100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 100.0, 0.0];
        let measured = [true, true, true, true, true, true, true, false, false, true];
        let sensed = [100.0, 105.0, 95.0, 115.0, 130.0, 70.0, 0.0, 0.0, 100.0, 50.0];
        let scores = depth_scores(&Prediction { depth: &depth, measured: &measured }, &sensed, 15.0);
        assert_eq!(scores.inlier, 4.0 / 7.0);
        assert_eq!(scores.violation, 1.0 / 7.0);
        assert_eq!(scores.explained_holes, Some(0.5));
        // (4 inliers + 1 explained) / (7 valid − 1 occluded + 2 shadowed).
        assert_eq!(scores.depth_score, 5.0 / 8.0);
    }

    #[test]
    fn nothing_shadowed_leaves_explained_holes_empty_and_nothing_predicted_scores_zero() {
        let scores = depth_scores(&Prediction { depth: &[0.0; 3], measured: &[true; 3] }, &[1.0; 3], 15.0);
        assert_eq!(scores, DepthScores { inlier: 0.0, violation: 0.0, explained_holes: None, depth_score: 0.0 });
    }
}
