//! Image comparison with a stated edge allowance, writing `*_actual`, `*_expected` and
//! `*_diff` PNGs under target/test-artifacts/ when a comparison fails.

use rangesynth::io::write_label_preview;
use std::path::PathBuf;

/// Pixels within one pixel (8-neighbourhood) of a change of label in `labels`: silhouettes,
/// surface edges and, in a shadowed image, shadow boundaries.
pub fn near_label_change(labels: &[u32], width: usize, height: usize) -> Vec<bool> {
    let mut near = vec![false; labels.len()];
    for r in 0..height {
        for c in 0..width {
            let here = labels[r * width + c];
            let r_range = r.saturating_sub(1)..=(r + 1).min(height - 1);
            let differs = r_range
                .into_iter()
                .any(|rr| (c.saturating_sub(1)..=(c + 1).min(width - 1)).any(|cc| labels[rr * width + cc] != here));
            near[r * width + c] = differs;
        }
    }
    near
}

/// Counts of a label comparison.
#[derive(Debug, Clone, Copy, Default)]
pub struct LabelDiff {
    pub pixels: usize,
    pub mismatched: usize,
    /// Mismatches outside the allowance: must be zero.
    pub outside_allowance: usize,
    pub allowance_pixels: usize,
}

pub fn compare_labels(
    name: &str,
    width: usize,
    height: usize,
    actual: &[u32],
    expected: &[u32],
    allowed: &[bool],
) -> LabelDiff {
    for (what, len) in [("actual", actual.len()), ("expected", expected.len()), ("allowance", allowed.len())] {
        assert_eq!(len, width * height, "{name}: the {what} image is not {width}×{height}");
    }
    let mut diff = LabelDiff { pixels: actual.len(), ..Default::default() };
    for i in 0..actual.len() {
        diff.allowance_pixels += usize::from(allowed[i]);
        if actual[i] != expected[i] {
            diff.mismatched += 1;
            diff.outside_allowance += usize::from(!allowed[i]);
        }
    }
    if diff.outside_allowance > 0 {
        write_artifacts(name, width, height, actual, expected);
    }
    diff
}

/// Writes actual, expected and diff (white where they differ) label previews.
pub fn write_artifacts(name: &str, width: usize, height: usize, actual: &[u32], expected: &[u32]) {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("test-artifacts");
    std::fs::create_dir_all(&dir).expect("artifact directory");
    let (w, h) = (width as u32, height as u32);
    let _ = write_label_preview(&dir.join(format!("{name}_actual.png")), w, h, actual, None);
    let _ = write_label_preview(&dir.join(format!("{name}_expected.png")), w, h, expected, None);
    assert_eq!(actual.len(), expected.len(), "{name}: the images differ in size");
    let diff: Vec<u32> = actual.iter().zip(expected).map(|(a, e)| u32::from(a != e)).collect();
    let _ = write_label_preview(&dir.join(format!("{name}_diff.png")), w, h, &diff, None);
    eprintln!("wrote {name}_actual/_expected/_diff.png to {}", dir.display());
}
