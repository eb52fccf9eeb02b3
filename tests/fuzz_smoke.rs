//! A bounded, seeded smoke run of every fuzz target (tools/fuzz/targets.rs), on stable Rust
//! in the ordinary test suite. The long runs use cargo-fuzz (tools/fuzz/README.md); this one
//! catches a regression in seconds.
//!
//! Each target runs in a child process — this same test binary, re-run with
//! `FUZZ_SMOKE_CHILD` set — under a 2 GiB address-space cap and a time limit, because the
//! failures that matter here are the ones a test cannot catch in-process: an allocation the
//! cap refuses aborts the child, and a hang outlives the limit. A panic fails the child too.
//! The child mutates the target's seed files with a seeded ChaCha generator (bit flips,
//! interesting bytes and integers, insertions, deletions, duplicated spans, tokens for text
//! formats), so every run tries the same inputs, and it saves the input it is on to a file
//! first, so a crash leaves the input that caused it.

#[path = "../tools/fuzz/targets.rs"]
mod targets;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const CHILD_ENV: &str = "FUZZ_SMOKE_CHILD";
const ITERATIONS: usize = 20_000;
const ADDRESS_SPACE_CAP: u64 = 2 << 30;
const TIME_LIMIT: Duration = Duration::from_secs(120);

/// Text that moves a mutated text input toward interesting places.
const TOKENS: &[&[u8]] = &[
    b"builtin:sphere:1024",
    b"builtin:cylinder:4096",
    b"builtin:plane:1e38",
    b"nan",
    b"inf",
    b"-1",
    b"1e308",
    b"4294967295",
    b"18446744073709551616",
    b"[[",
    b"]]",
    b"{",
    b"}",
    b",",
    b"\"",
    b"\n[[object]]\nmodel = \"builtin:box\"\n",
    b"\nf 1 2 3\n",
    b"\nf -1 -2 -3 -4 -5\n",
    b"\nv 1e30 -1e30 0\n",
    b"\ng \n",
    b"\nmtllib /dev/zero\n",
    b"\nl 1 2 3\n",
    b"\np 1\n",
    b"\xef\xbb\xbf",
    b"\r\n",
    b"\r",
    b"\nnewmtl m\n",
    b"\nKd 0.5\n",
    b"\nKs 1 1\n",
    b"\nKa spectral x.rfl\n",
    b"\nKd xyz 1\n",
    b"\nd\n",
    b"\nillum\n",
    b"#",
    b"\nelement vertex 4294967295\n",
    b"\nelement face 1\nproperty list uint int vertex_indices\n",
    b"\nproperty list uchar float vertex_indices\n",
    b"\nproperty double x\n",
    b"\nproperty int surface\n",
    b"\nelement edge 2\nproperty list uchar int vertex_indices\n",
    b"\ncomment \n",
    b"end_header\n",
    b"format binary_big_endian 1.0\n",
    b"format ascii 1.0\n",
    b"\n255 0 1 2\n",
    b"\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n",
    b"endsolid",
    b"solid ",
];

fn seeds(target: &str) -> Vec<Vec<u8>> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tools/fuzz/seeds").join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    let seeds: Vec<Vec<u8>> = files.iter().map(|f| std::fs::read(f).unwrap()).collect();
    assert!(!seeds.is_empty(), "no seeds in {}", dir.display());
    seeds
}

fn mutate(rng: &mut ChaCha8Rng, input: &mut Vec<u8>) {
    for _ in 0..rng.gen_range(1..=4) {
        let len = input.len();
        let at = if len == 0 { 0 } else { rng.gen_range(0..len) };
        match rng.gen_range(0..7) {
            0 if len > 0 => input[at] ^= 1 << rng.gen_range(0..8),
            1 if len > 0 => input[at] = [0, 1, 0x7f, 0x80, 0xff][rng.gen_range(0..5)],
            2 if len >= 4 => {
                let value: u32 = [0, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 1 << 29, 16384][rng.gen_range(0..7)];
                let at = at.min(len - 4);
                input[at..at + 4].copy_from_slice(&value.to_le_bytes());
            }
            3 => {
                let token = TOKENS[rng.gen_range(0..TOKENS.len())];
                input.splice(at..at, token.iter().copied());
            }
            4 if len > 0 => {
                let end = (at + rng.gen_range(1..=16)).min(len);
                input.drain(at..end);
            }
            5 if len > 0 => {
                let end = (at + rng.gen_range(1..=64)).min(len);
                let span = input[at..end].to_vec();
                input.splice(at..at, span);
            }
            _ => input.truncate(at),
        }
    }
}

/// In the child: runs the target over the mutated seeds.
fn run_child(target: &str, crash_file: &PathBuf) {
    let run = targets::TARGETS.iter().find(|(name, _)| *name == target).expect("a known target").1;
    let seeds = seeds(target);
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed);
    for seed in &seeds {
        std::fs::write(crash_file, seed).unwrap();
        run(seed);
    }
    for _ in 0..ITERATIONS {
        let mut input = seeds[rng.gen_range(0..seeds.len())].clone();
        mutate(&mut rng, &mut input);
        std::fs::write(crash_file, &input).unwrap();
        run(&input);
    }
    std::fs::remove_file(crash_file).unwrap();
    // What the parent reads to know the child ran the target (a child that matched no test
    // would exit successfully too).
    std::fs::write(ran_file(crash_file), (seeds.len() + ITERATIONS).to_string()).unwrap();
}

/// Where a child says how many inputs it ran.
fn ran_file(crash_file: &Path) -> PathBuf {
    crash_file.with_extension("ran")
}

fn smoke(target: &str, test_name: &str) {
    let crash_file = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("fuzz-smoke-{target}.input"));
    if std::env::var(CHILD_ENV).is_ok() {
        return run_child(target, &crash_file);
    }
    let mut command = Command::new(std::env::current_exe().unwrap());
    command
        .args(["--exact", test_name, "--test-threads=1", "--nocapture"])
        .env(CHILD_ENV, "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    // SAFETY: between fork and exec the closure only calls setrlimit, which is
    // async-signal-safe.
    unsafe {
        command.pre_exec(|| {
            let cap = libc::rlimit { rlim_cur: ADDRESS_SPACE_CAP, rlim_max: ADDRESS_SPACE_CAP };
            match libc::setrlimit(libc::RLIMIT_AS, &cap) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        })
    };
    let _ = std::fs::remove_file(ran_file(&crash_file));
    let mut child = command.spawn().unwrap();
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            panic!("{target}: still running after {TIME_LIMIT:?}: a hang; the input is in {}", crash_file.display());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    assert!(
        status.success(),
        "{target}: the child failed ({status:?}, signal {:?}); the input is in {}:\n{stderr}",
        status.signal(),
        crash_file.display()
    );
    let ran = std::fs::read_to_string(ran_file(&crash_file)).unwrap_or_default();
    assert!(
        ran.parse::<usize>().is_ok_and(|n| n > ITERATIONS),
        "{target}: the child exited without running the target (it reported {ran:?} inputs)"
    );
}

#[test]
fn fuzz_smoke_scene_toml() {
    smoke("scene_toml", "fuzz_smoke_scene_toml");
}

#[test]
fn fuzz_smoke_hypothesis_json() {
    smoke("hypothesis_json", "fuzz_smoke_hypothesis_json");
}

#[test]
fn fuzz_smoke_obj() {
    smoke("obj", "fuzz_smoke_obj");
}

#[test]
fn fuzz_smoke_mtl() {
    smoke("mtl", "fuzz_smoke_mtl");
}

#[test]
fn fuzz_smoke_ply() {
    smoke("ply", "fuzz_smoke_ply");
}

#[test]
fn fuzz_smoke_stl() {
    smoke("stl", "fuzz_smoke_stl");
}

#[test]
fn fuzz_smoke_range_exr() {
    smoke("range_exr", "fuzz_smoke_range_exr");
}
