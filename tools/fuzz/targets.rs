//! The fuzz targets, defined once for both harnesses: cargo-fuzz (`tools/fuzz/fuzz_targets/`,
//! nightly, libFuzzer) and the seeded smoke run in the test suite (`tests/fuzz_smoke.rs`).
//! Each takes arbitrary bytes and must return, with a value or an error: never panic, abort,
//! hang or allocate past its budget. A dependency's parser that panics is caught by the
//! library (`Error::ParserPanic`) but still fails a target: the checks before it missed
//! something. Seeds for each are in `tools/fuzz/seeds/<target>/`.

use rangesynth::io::parse_range_image;
use rangesynth::limits::{Ledger, MemoryBudget};
use rangesynth::mesh::{load_obj, parse_obj, parse_ply, parse_stl};
use rangesynth::verify::HypothesisFile;
use rangesynth::{Error, Scene};
use std::path::Path;

/// The budget the targets run under; the harnesses cap the process's memory well above it.
pub const BUDGET: MemoryBudget = MemoryBudget::new(256 << 20);

/// A scene file. Model paths resolve in a directory that does not exist, so nothing outside
/// the input is read; built-in models are built.
pub fn scene_toml(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        no_parser_panic(Scene::from_toml(text, Path::new("/nonexistent-fuzz-models"), &Ledger::new(BUDGET)));
    }
}

pub fn hypothesis_json(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        no_parser_panic(HypothesisFile::from_json(text, &Ledger::new(BUDGET)));
    }
}

pub fn obj(data: &[u8]) {
    no_parser_panic(parse_obj(data, "fuzz.obj", &Ledger::new(BUDGET)));
}

/// A material library, as an OBJ that uses its materials reads it (from a file: libraries
/// are only read beside a model file).
pub fn mtl(data: &[u8]) {
    thread_local! {
        static DIR: tempfile::TempDir = tempfile::tempdir().expect("a temporary directory");
    }
    DIR.with(|dir| {
        let (obj, library) = (dir.path().join("m.obj"), dir.path().join("m.mtl"));
        std::fs::write(&library, data).expect("writing the library");
        if !obj.exists() {
            let text = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nusemtl a\nf 1 2 3\ng b\nusemtl b\nf 1 2 3\n";
            std::fs::write(&obj, text).expect("writing the model");
        }
        no_parser_panic(load_obj(&obj, &Ledger::new(BUDGET)));
    });
}

pub fn ply(data: &[u8]) {
    no_parser_panic(parse_ply(data, "fuzz.ply", &Ledger::new(BUDGET)));
}

pub fn stl(data: &[u8]) {
    no_parser_panic(parse_stl(data, "fuzz.stl", &Ledger::new(BUDGET)));
}

pub fn range_exr(data: &[u8]) {
    no_parser_panic(parse_range_image(data, Path::new("fuzz.exr"), &Ledger::new(BUDGET)));
}

/// Fails on a panic that the library caught inside a dependency's parser.
fn no_parser_panic<T>(result: rangesynth::Result<T>) {
    if let Err(e @ Error::ParserPanic { .. }) = result {
        panic!("{e}");
    }
}

/// A target: bytes in, nothing out.
pub type Target = fn(&[u8]);

/// Every target by name.
pub const TARGETS: [(&str, Target); 7] = [
    ("scene_toml", scene_toml),
    ("hypothesis_json", hypothesis_json),
    ("obj", obj),
    ("mtl", mtl),
    ("ply", ply),
    ("stl", stl),
    ("range_exr", range_exr),
];
