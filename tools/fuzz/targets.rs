//! The fuzz targets, defined once for both harnesses: cargo-fuzz (`tools/fuzz/fuzz_targets/`,
//! nightly, libFuzzer) and the seeded smoke run in the test suite (`tests/fuzz_smoke.rs`).
//! Each takes arbitrary bytes and must return, with a value or an error: never panic, abort,
//! hang or allocate past its budget. Seeds for each are in `tools/fuzz/seeds/<target>/`.

use rangesynth::io::parse_range_image;
use rangesynth::limits::MemoryBudget;
use rangesynth::mesh::parse_obj;
use rangesynth::verify::HypothesisFile;
use rangesynth::Scene;
use std::path::Path;

/// The budget the targets run under; the harnesses cap the process's memory well above it.
pub const BUDGET: MemoryBudget = MemoryBudget::new(256 << 20);

/// A scene file. Model paths resolve in a directory that does not exist, so nothing outside
/// the input is read; built-in models are built.
pub fn scene_toml(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = Scene::from_toml(text, Path::new("/nonexistent-fuzz-models"), BUDGET);
    }
}

pub fn hypothesis_json(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = HypothesisFile::from_json(text);
    }
}

pub fn obj(data: &[u8]) {
    let _ = parse_obj(data, "fuzz.obj");
}

pub fn range_exr(data: &[u8]) {
    let _ = parse_range_image(data, Path::new("fuzz.exr"), BUDGET);
}

/// A target: bytes in, nothing out.
pub type Target = fn(&[u8]);

/// Every target by name.
pub const TARGETS: [(&str, Target); 4] =
    [("scene_toml", scene_toml), ("hypothesis_json", hypothesis_json), ("obj", obj), ("range_exr", range_exr)];
