//! The persistent pipeline cache (src/gpu/pipeline_cache.rs) never fails a run: each test
//! starts renderers on a cache directory of its own, in a state a user's disk may be in
//! (none yet, a cache of its own, corrupt, stale, unwritable, a device or a FIFO where the
//! file would be), renders the same scene, and checks that the images are those of a renderer
//! with no cache, that validation stays quiet, and what the cache reports and leaves on disk.
//!
//! The file's layout is the module's: a 28-byte header (magic `RSPIPES\0`, format, build key,
//! payload length, payload CRC-32, little-endian), then the driver's data, which begins with
//! the driver's own 32-byte header (size, version, vendor id, device id, pipelineCacheUUID).

mod common;

use common::*;
use glam::{DMat4, DVec3};
use rangesynth::gpu::{CacheLoad, ContextOptions, PipelineCacheReport, MAX_PIPELINE_CACHE_BYTES};
use rangesynth::render::Raster;
use rangesynth::shadow::ShadowMode;
use rangesynth::{RenderOutput, Renderer, Scene};
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::sync::LazyLock;

const HEADER_BYTES: usize = 28;

/// A box and a ball on a plane, in depth mode, drawn by the compute rasterizer: the graphics
/// pipelines of the renderer and the compute ones built on first use both go through the
/// cache.
fn test_scene() -> Scene {
    let ball = DMat4::from_translation(DVec3::new(0.8, -0.6, 0.0));
    scene(
        centred_sensor(64, 64, 3.0 / 64.0, [0.0, 0.0], 30.0),
        ShadowMode::Depth,
        &[
            ("builtin:plane:4", DMat4::IDENTITY),
            ("builtin:box", DMat4::from_rotation_z(0.3)),
            ("builtin:sphere:24", ball),
        ],
    )
}

/// The scene as a renderer with no persistent cache draws it.
static WITHOUT_CACHE: LazyLock<RenderOutput> = LazyLock::new(|| render_with(None).1);

/// A fresh directory for one test's cache.
fn cache_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rangesynth-pipeline-cache-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Renders the scene on a renderer whose cache lives in `dir` (none: no persistent cache),
/// and returns what the cache reported after the render (as its last pipeline build left it)
/// with the output.
fn render_with(dir: Option<&Path>) -> (PipelineCacheReport, RenderOutput) {
    let options = ContextOptions {
        validation: true,
        pipeline_cache_dir: dir.map(Path::to_path_buf),
        ..ContextOptions::from_env()
    };
    let renderer = Renderer::new(&options).unwrap_or_else(|e| panic!("a renderer starts whatever its cache: {e}"));
    let renderer = renderer.with_raster(Raster::Compute);
    let out = renderer.render(&test_scene()).unwrap_or_else(|e| panic!("a run never fails for its cache: {e}"));
    let messages = renderer.context().take_validation_messages();
    assert!(messages.is_empty(), "validation reported:\n{}", messages.join("\n"));
    let report = renderer.context().pipeline_cache_report();
    (report, out)
}

/// Renders with the cache in `dir` and asserts the images are the uncached renderer's.
fn render_checked(dir: &Path) -> PipelineCacheReport {
    let (report, out) = render_with(Some(dir));
    let expected = &*WITHOUT_CACHE;
    assert_eq!(out.label, expected.label, "labels with the cache in {}", dir.display());
    assert_eq!(out.label_unshadowed, expected.label_unshadowed, "surfaces hit");
    let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&out.z), bits(&expected.z), "z");
    report
}

/// The path of the cache file in `dir` (a first run there names it).
fn cache_file(dir: &Path) -> PathBuf {
    let report = render_checked(dir);
    report.path.expect("a directory was given")
}

/// A cache written by this build for this device, as bytes.
fn valid_cache(dir: &Path) -> (PathBuf, Vec<u8>) {
    let path = cache_file(dir);
    let bytes = std::fs::read(&path).expect("the first run wrote its cache");
    (path, bytes)
}

/// Asserts that a run replaced the cache file at `path` (its report `written`) with one the
/// next run loads.
fn assert_written_anew(what: &str, path: &Path, written: &PipelineCacheReport) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"RSPIPES\0", "{what}: a cache was written");
    assert_eq!(written.last_save, Some(Ok(bytes.len() as u64)), "{what}");
    let next = render_checked(path.parent().unwrap());
    assert_eq!(next.load, CacheLoad::Loaded { bytes: (bytes.len() - HEADER_BYTES) as u64 }, "{what}: read back");
}

/// Writes each of `cases` (what it is, its bytes) as the cache file at `path` in turn, and
/// asserts a run ignores it for a reason that says `why` and writes the cache anew.
fn assert_each_ignored(path: &Path, cases: &[(&str, Vec<u8>)], why: &str) {
    for (what, bytes) in cases {
        std::fs::write(path, bytes).unwrap();
        let report = render_checked(path.parent().unwrap());
        assert_ignored(&report, why);
        assert_written_anew(what, path, &report);
    }
}

fn assert_ignored(report: &PipelineCacheReport, why: &str) {
    match &report.load {
        CacheLoad::Ignored(reason) => assert!(reason.contains(why), "ignored for {reason:?}, expected {why:?}"),
        other => panic!("the cache was {other:?}, expected ignored for {why:?}"),
    }
}

/// `bytes` with the payload's CRC-32 recomputed, so that only the change made is wrong.
fn with_crc(mut bytes: Vec<u8>) -> Vec<u8> {
    let crc = crc32fast::hash(&bytes[HEADER_BYTES..]);
    bytes[24..28].copy_from_slice(&crc.to_le_bytes());
    bytes
}

#[test]
fn a_cache_is_written_where_there_was_none_and_read_by_the_next_run() {
    let dir = cache_dir("fresh");
    // Its directory is made, a level deeper than any that exists.
    let nested = dir.join("a").join("b");
    let first = render_checked(&nested);
    assert_eq!(first.load, CacheLoad::Missing);
    let written = first.last_save.clone().expect("the pipelines built were written").expect("written");
    let path = first.path.expect("a path");
    assert_eq!(std::fs::metadata(&path).unwrap().len(), written);
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(name.starts_with("pipelines-") && name.ends_with(".bin"), "{name}");
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[..8], b"RSPIPES\0");
    let second = render_checked(&nested);
    assert_eq!(second.load, CacheLoad::Loaded { bytes: written - HEADER_BYTES as u64 });
    // Nothing new was built: the file is left as it was (unless a driver's data, read back,
    // differs in its bytes, which it may: then it is written whole again).
    match second.last_save {
        None => assert_eq!(std::fs::read(&path).unwrap(), bytes),
        Some(saved) => assert!(saved.is_ok(), "{saved:?}"),
    }
}

#[test]
fn corrupt_caches_are_ignored_and_written_anew() {
    let dir = cache_dir("corrupt");
    let (path, valid) = valid_cache(&dir);
    let mut flipped = valid.clone();
    *flipped.last_mut().unwrap() ^= 0x40;
    let mut longer = valid.clone();
    longer.push(0);
    let corruptions: [(&str, Vec<u8>); 5] = [
        ("empty", Vec::new()),
        ("garbage", b"not a cache at all, just some bytes".to_vec()),
        ("cut short", valid[..valid.len() - 1].to_vec()),
        ("one byte longer", longer),
        ("a data bit flipped", flipped),
    ];
    assert_each_ignored(&path, &corruptions, "corrupt");
}

#[test]
fn stale_caches_are_ignored_and_written_anew() {
    let dir = cache_dir("stale");
    let (path, valid) = valid_cache(&dir);
    let changed = |at: usize| {
        let mut bytes = valid.clone();
        bytes[at] ^= 1;
        bytes
    };
    let stale = [
        ("another format", changed(8)),
        ("another build", changed(12)),
        // The driver's header, with the CRC made right: another vendor, device, or UUID.
        ("another vendor", with_crc(changed(HEADER_BYTES + 8))),
        ("another device", with_crc(changed(HEADER_BYTES + 12))),
        ("another driver", with_crc(changed(HEADER_BYTES + 16))),
    ];
    assert_each_ignored(&path, &stale, "stale");
}

#[test]
fn an_oversized_cache_is_not_read() {
    let dir = cache_dir("oversized");
    let path = cache_file(&dir);
    // Sparse: no disk is used, and a reader that read it would take seconds.
    std::fs::File::create(&path).unwrap().set_len(MAX_PIPELINE_CACHE_BYTES + 1).unwrap();
    let report = render_checked(&dir);
    assert_ignored(&report, "larger than");
    assert_written_anew("oversized", &path, &report);
}

fn c_path(path: &Path) -> std::ffi::CString {
    std::ffi::CString::new(path.to_str().unwrap()).unwrap()
}

#[test]
fn an_unwritable_cache_never_fails_a_run() {
    let dir = cache_dir("unwritable");
    let path = cache_file(&dir);
    let name = path.file_name().unwrap();

    // Its directory cannot be made: a regular file stands on its path.
    let file = dir.join("a-file");
    std::fs::write(&file, b"a user's file").unwrap();
    let report = render_checked(&file.join("cache"));
    assert_eq!(report.load, CacheLoad::Missing);
    assert!(matches!(&report.last_save, Some(Err(why)) if why.contains("could not be made")), "{:?}", report.last_save);
    assert_eq!(std::fs::read(&file).unwrap(), b"a user's file");

    // A directory where the file would be: not read, not replaced.
    let with_dir = dir.join("with-dir");
    std::fs::create_dir_all(with_dir.join(name)).unwrap();
    let report = render_checked(&with_dir);
    assert_ignored(&report, "a directory");
    assert!(matches!(report.last_save, Some(Err(_))), "{:?}", report.last_save);
    assert!(with_dir.join(name).is_dir());

    // A character device (made here, as /dev/null is: 1, 3) and a FIFO: neither read (a
    // FIFO would block a reader) nor replaced.
    for (kind, mode, device) in
        [("a character device", libc::S_IFCHR, libc::makedev(1, 3)), ("a FIFO", libc::S_IFIFO, 0)]
    {
        let nodes = dir.join(kind.replace(' ', "-"));
        std::fs::create_dir_all(&nodes).unwrap();
        let node = nodes.join(name);
        // SAFETY: a valid NUL-terminated path; mknod only creates the node.
        let rc = unsafe { libc::mknod(c_path(&node).as_ptr(), mode | 0o666, device) };
        assert_eq!(rc, 0, "mknod {}: {}", node.display(), std::io::Error::last_os_error());
        let report = render_checked(&nodes);
        assert_ignored(&report, kind);
        assert!(matches!(report.last_save, Some(Err(_))), "{kind}: {:?}", report.last_save);
        let file_type = std::fs::symlink_metadata(&node).unwrap().file_type();
        assert!(file_type.is_char_device() || file_type.is_fifo(), "{kind} left as it was");
    }
}
