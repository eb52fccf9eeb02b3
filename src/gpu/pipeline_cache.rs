//! What the driver compiled for the product's pipelines, kept on disk between runs: a
//! `VkPipelineCache` loaded when a context starts and written back whenever pipelines were
//! built, so that a process's first hypothesis does not wait for every shader to be compiled
//! again (docs/performance.md, "Cold start").
//!
//! Where: `$RANGESYNTH_CACHE_DIR`, else `$XDG_CACHE_HOME/rangesynth`, else
//! `~/.cache/rangesynth` ([`default_cache_dir`]), one file per device and driver version,
//! `pipelines-<device UUID>-<driver version>.bin`: two cards, or a driver update, never read
//! each other's.
//!
//! What the file holds: a header of ours (a magic, the format, a key of this build's shaders
//! and version, the payload's length and CRC-32), then the driver's data, whose own header
//! (vendor, device, `pipelineCacheUUID`) must match the device. A driver is not required to
//! survive data it did not write, so nothing reaches it that fails any of these checks.
//!
//! It never fails a run. A file that is missing, corrupt (short, a wrong magic, length or
//! CRC), stale (another build of rangesynth, another driver), larger than
//! [`MAX_PIPELINE_CACHE_BYTES`] or not a regular file (which is not even opened) is ignored,
//! and the pipelines are built as without one; a cache that cannot be written (no home, a
//! read-only or missing directory, a device or directory at the file's path) is left as it
//! is; a driver that makes no cache builds the pipelines without one. What happened is in
//! [`PipelineCacheReport`], which the command line prints when it is not what a user would
//! expect. Writes go through a temporary file renamed over the old one (src/io/atomic.rs), so
//! processes sharing the cache each leave it whole; the last to write wins.

use crate::io::{file_kind, read_input_file, write_atomically};
use crate::limits::{Ledger, MemoryBudget};
use ash::vk;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Environment variable naming the pipeline cache's directory.
pub const CACHE_DIR_ENV: &str = "RANGESYNTH_CACHE_DIR";

/// The largest cache file read or written: a driver's data for the product's few dozen
/// pipelines is far smaller, so a larger file is not ours.
pub const MAX_PIPELINE_CACHE_BYTES: u64 = 256 << 20;

const MAGIC: &[u8; 8] = b"RSPIPES\0";
const FORMAT: u32 = 1;
/// Magic, format, build key, payload length (u64), payload CRC-32.
const HEADER_BYTES: usize = 8 + 4 + 4 + 8 + 4;
/// The driver's own header (VkPipelineCacheHeaderVersionOne): its size, its version, the
/// vendor and device ids, the `pipelineCacheUUID`.
const DRIVER_HEADER_BYTES: usize = 4 + 4 + 4 + 4 + vk::UUID_SIZE;

/// The directory a context's pipeline cache lives in: `$RANGESYNTH_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/rangesynth` (an absolute path, as the XDG specification requires), else
/// `$HOME/.cache/rangesynth`; none where none of them is set.
pub fn default_cache_dir() -> Option<PathBuf> {
    cache_dir_from(|name| std::env::var_os(name))
}

/// [`default_cache_dir`] with the environment read through `env` (an empty value counts as
/// none).
fn cache_dir_from(env: impl Fn(&str) -> Option<std::ffi::OsString>) -> Option<PathBuf> {
    let var = |name: &str| env(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    var(CACHE_DIR_ENV)
        .or_else(|| var("XDG_CACHE_HOME").filter(|p| p.is_absolute()).map(|p| p.join("rangesynth")))
        .or_else(|| var("HOME").map(|home| home.join(".cache").join("rangesynth")))
}

/// What a context found in its cache file when it started.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CacheLoad {
    /// No directory was given: nothing is read or written.
    Off,
    /// No file yet: the pipelines are built, then written there.
    Missing,
    /// The driver's data was handed to it.
    Loaded { bytes: u64 },
    /// A file was there but not used, for this reason; it is replaced at the next write.
    Ignored(String),
}

/// Where a context's pipeline cache is, what it found there, and how its last write went.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PipelineCacheReport {
    pub path: Option<PathBuf>,
    pub load: CacheLoad,
    /// The bytes written, or why nothing could be; `None` before any write was needed.
    pub last_save: Option<Result<u64, String>>,
}

/// Which device and driver the driver's data must come from.
struct DriverIdentity {
    vendor: u32,
    device: u32,
    uuid: [u8; vk::UUID_SIZE],
}

pub(crate) struct PipelineCache {
    pub(crate) raw: vk::PipelineCache,
    build_key: u32,
    state: Mutex<SaveState>,
}

struct SaveState {
    report: PipelineCacheReport,
    /// The CRC-32 of the driver's data as last read or written: a write that would change
    /// nothing is skipped.
    saved_crc: Option<u32>,
}

impl PipelineCache {
    /// The cache of `device` (whose properties and UUID are given) in `dir`: loaded from its
    /// file where that passes every check, else empty.
    pub(crate) fn open(
        device: &ash::Device,
        properties: &vk::PhysicalDeviceProperties,
        device_uuid: &str,
        dir: Option<&Path>,
    ) -> Self {
        let identity = DriverIdentity {
            vendor: properties.vendor_id,
            device: properties.device_id,
            uuid: properties.pipeline_cache_uuid,
        };
        let build_key = build_key();
        let path = dir.map(|dir| dir.join(format!("pipelines-{device_uuid}-{:08x}.bin", properties.driver_version)));
        let found = path.as_deref().map(|path| {
            read_cache_file(path).and_then(|file| file.map(|bytes| payload(&bytes, build_key, &identity)).transpose())
        });
        let (data, mut load) = match found {
            None => (Vec::new(), CacheLoad::Off),
            Some(Ok(None)) => (Vec::new(), CacheLoad::Missing),
            Some(Ok(Some(data))) => {
                let bytes = data.len() as u64;
                (data, CacheLoad::Loaded { bytes })
            }
            Some(Err(why)) => (Vec::new(), CacheLoad::Ignored(why)),
        };
        let create = |data: &[u8]| {
            let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
            // SAFETY: valid device; `data` passed every check on its header and CRC.
            unsafe { device.create_pipeline_cache(&info, None) }
        };
        // Pipelines are built without a cache (a null handle) where the driver makes none.
        let raw = match create(&data) {
            Ok(raw) => raw,
            Err(e) if !data.is_empty() => {
                load = CacheLoad::Ignored(format!("the driver did not take it ({e})"));
                create(&[]).unwrap_or(vk::PipelineCache::null())
            }
            Err(_) => vk::PipelineCache::null(),
        };
        let saved_crc = matches!(load, CacheLoad::Loaded { .. }).then(|| crc32fast::hash(&data));
        let report = PipelineCacheReport { path, load, last_save: None };
        Self { raw, build_key, state: Mutex::new(SaveState { report, saved_crc }) }
    }

    /// Writes the driver's data to the cache file where it changed since it was last read or
    /// written. A failure is recorded in the report, never returned.
    pub(crate) fn save(&self, device: &ash::Device) {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        let Some(path) = state.report.path.clone().filter(|_| self.raw != vk::PipelineCache::null()) else { return };
        // SAFETY: valid device and cache; the driver synchronizes the cache internally.
        let data = match unsafe { device.get_pipeline_cache_data(self.raw) } {
            Ok(data) => data,
            Err(e) => {
                state.report.last_save = Some(Err(format!("the driver did not return its data ({e})")));
                return;
            }
        };
        let crc = crc32fast::hash(&data);
        if state.saved_crc == Some(crc) {
            return;
        }
        let written = write_cache_file(&path, &data, self.build_key, crc);
        if written.is_ok() {
            state.saved_crc = Some(crc);
        }
        state.report.last_save = Some(written.map(|()| (HEADER_BYTES + data.len()) as u64));
    }

    pub(crate) fn report(&self) -> PipelineCacheReport {
        self.state.lock().unwrap_or_else(|p| p.into_inner()).report.clone()
    }

    /// # Safety
    /// No pipeline is being created from it, and it is not used again.
    pub(crate) unsafe fn destroy(&self, device: &ash::Device) {
        // SAFETY: forwarded from the caller; destroying a null handle does nothing.
        unsafe { device.destroy_pipeline_cache(self.raw, None) };
    }
}

include!(concat!(env!("OUT_DIR"), "/shader_set_key.rs"));

/// A key of this build's shaders and version: a cache written by another build holds other
/// pipelines, which would only grow the file.
fn build_key() -> u32 {
    let mut hasher = crc32fast::Hasher::new();
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    hasher.update(&SHADER_SET_KEY.to_le_bytes());
    hasher.finalize()
}

/// The driver's header as `identity`'s data must begin (the form of version one).
fn driver_header(identity: &DriverIdentity) -> Vec<u8> {
    let mut header = Vec::with_capacity(DRIVER_HEADER_BYTES);
    header.extend((DRIVER_HEADER_BYTES as u32).to_le_bytes());
    header.extend((vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32).to_le_bytes());
    header.extend(identity.vendor.to_le_bytes());
    header.extend(identity.device.to_le_bytes());
    header.extend(identity.uuid);
    header
}

/// The cache file's bytes; none where there is no file, and why not where it is not read.
fn read_cache_file(path: &Path) -> Result<Option<Vec<u8>>, String> {
    // Not opened unless it is a regular file: opening a device can act (a tape rewinds).
    match std::fs::metadata(path) {
        Ok(metadata) if !metadata.is_file() => {
            Err(format!("it is {}, not a regular file", file_kind(metadata.file_type())))
        }
        Ok(metadata) if metadata.len() > MAX_PIPELINE_CACHE_BYTES => {
            Err(format!("it is larger than {MAX_PIPELINE_CACHE_BYTES} bytes"))
        }
        // Read as any input is, within a budget of that size (a file swapped or grown since
        // is refused there).
        Ok(_) => {
            let budget = Ledger::new(MemoryBudget::new(MAX_PIPELINE_CACHE_BYTES));
            read_input_file(path, "pipeline cache", &budget).map(Some).map_err(|e| e.to_string())
        }
        // Nothing there, or a file where a directory on its path would be (a write fails then).
        Err(e) if matches!(e.kind(), std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory) => Ok(None),
        Err(e) => Err(format!("it could not be examined ({e})")),
    }
}

/// The driver's data in a cache file's bytes, where the file is whole, of this build and of
/// this device and driver; else why not.
fn payload(bytes: &[u8], build_key: u32, identity: &DriverIdentity) -> Result<Vec<u8>, String> {
    let corrupt = |what: &str| format!("it is corrupt ({what})");
    if bytes.len() < HEADER_BYTES || &bytes[..8] != MAGIC {
        return Err(corrupt("not a rangesynth pipeline cache"));
    }
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    if u32_at(8) != FORMAT {
        return Err(format!("it is stale (format {}, not {FORMAT})", u32_at(8)));
    }
    if u32_at(12) != build_key {
        return Err("it is stale (written by another build of rangesynth)".into());
    }
    let length = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let data = &bytes[HEADER_BYTES..];
    if length != data.len() as u64 {
        return Err(corrupt(&format!("{} bytes of data where its header says {length}", data.len())));
    }
    if crc32fast::hash(data) != u32_at(24) {
        return Err(corrupt("its CRC-32 does not match its data"));
    }
    let expected = driver_header(identity);
    if data.len() < DRIVER_HEADER_BYTES || data[..DRIVER_HEADER_BYTES] != expected[..] {
        return Err("it is stale (written for another device or driver)".into());
    }
    Ok(data.to_vec())
}

/// Writes `data` (of CRC-32 `crc`) as the cache file at `path`, its directory made where
/// missing.
fn write_cache_file(path: &Path, data: &[u8], build_key: u32, crc: u32) -> Result<(), String> {
    if (HEADER_BYTES + data.len()) as u64 > MAX_PIPELINE_CACHE_BYTES {
        return Err(format!("the driver's data is larger than {MAX_PIPELINE_CACHE_BYTES} bytes"));
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("its directory {} could not be made ({e})", dir.display()))?;
    }
    write_atomically(path, |file| {
        let mut header = Vec::with_capacity(HEADER_BYTES);
        header.extend(MAGIC);
        header.extend(FORMAT.to_le_bytes());
        header.extend(build_key.to_le_bytes());
        header.extend((data.len() as u64).to_le_bytes());
        header.extend(crc.to_le_bytes());
        file.write_all(&header).and_then(|()| file.write_all(data)).map_err(|e| crate::error::Error::io(path, e))
    })
    .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cache_directory_is_the_first_of_its_variables_that_is_set() {
        let dir = |vars: &[(&str, &str)]| {
            let vars: Vec<(String, String)> = vars.iter().map(|&(k, v)| (k.into(), v.into())).collect();
            cache_dir_from(|name| vars.iter().find(|(k, _)| k == name).map(|(_, v)| v.into()))
        };
        let all = [(CACHE_DIR_ENV, "/c"), ("XDG_CACHE_HOME", "/x"), ("HOME", "/h")];
        assert_eq!(dir(&all), Some(PathBuf::from("/c")));
        assert_eq!(dir(&all[1..]), Some(PathBuf::from("/x/rangesynth")));
        assert_eq!(dir(&all[2..]), Some(PathBuf::from("/h/.cache/rangesynth")));
        // Empty counts as unset; a relative XDG_CACHE_HOME is ignored, as its specification says.
        assert_eq!(
            dir(&[(CACHE_DIR_ENV, ""), ("XDG_CACHE_HOME", "x"), ("HOME", "/h")]),
            Some(PathBuf::from("/h/.cache/rangesynth"))
        );
        // No home: no cache, and nothing is read or written.
        assert_eq!(dir(&[]), None);
    }
}
