//! Outputs, as a long-running daemon writes them (issue "Hostile input, round two"): an output
//! path that is not a regular file (a device, a FIFO, a socket, a link to one) is refused and
//! left as it was, in every command; a render's or an experiment's directory is replaced whole
//! or not at all, whether the swap fails or the process is killed in the middle of it. The
//! device nodes are made here with mknod (the suite runs as root); the machine's own are never
//! touched. Each case failed before the change it names.

mod common;

use common::cli::{fresh_dir, rangesynth_command, text};
use std::collections::BTreeMap;
use std::ffi::CString;
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn rangesynth() -> Command {
    let mut c = rangesynth_command();
    c.env_remove("RANGESYNTH_MEMORY_BUDGET").env_remove("RANGESYNTH_TEST_COMMIT");
    c
}

fn run(args: &[&str]) -> Output {
    rangesynth().args(args).output().expect("the binary runs")
}

fn dir(name: &str) -> PathBuf {
    fresh_dir("outputs", name)
}

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

/// Asserts a clean refusal (exit code 1, no panic) that says each of `expected`.
fn refused(out: &Output, what: &str, expected: &[&str]) {
    for e in expected {
        common::cli::refused(out, what, e);
    }
}

fn succeeded(out: &Output, what: &str) {
    assert!(out.status.success(), "{what}: {}", text(&out.stderr));
}

fn c_path(path: &Path) -> CString {
    CString::new(s(path)).unwrap()
}

/// A character device with /dev/null's numbers, made here.
fn make_char_device(path: &Path) {
    // SAFETY: a valid NUL-terminated path; mknod only creates the node.
    let rc = unsafe { libc::mknod(c_path(path).as_ptr(), libc::S_IFCHR | 0o666, libc::makedev(1, 3)) };
    assert_eq!(rc, 0, "mknod {}: {}", path.display(), std::io::Error::last_os_error());
}

fn make_fifo(path: &Path) {
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c_path(path).as_ptr(), 0o666) }, 0, "mkfifo {}", path.display());
}

/// A unix socket; it stays a socket on disk after the listener is gone.
fn make_socket(path: &Path) {
    drop(std::os::unix::net::UnixListener::bind(path).unwrap());
}

/// Makes a node at a path.
type Make<'a> = dyn Fn(&Path) + 'a;

/// What a path is now, not following a link (a link's own target too).
fn what_is(path: &Path) -> String {
    let meta = std::fs::symlink_metadata(path).unwrap();
    let t = meta.file_type();
    match () {
        _ if t.is_symlink() => format!("link to {}", std::fs::read_link(path).unwrap().display()),
        _ if t.is_char_device() => format!("char device {:x}", meta.rdev()),
        _ if t.is_fifo() => "fifo".into(),
        _ if t.is_socket() => "socket".into(),
        _ if t.is_dir() => "directory".into(),
        _ => "regular file".into(),
    }
}

/// Every file under `root`: its path below `root` and its bytes (a link: where it points).
fn snapshot(root: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut todo = vec![root.to_path_buf()];
    while let Some(d) = todo.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            let relative = path.strip_prefix(root).unwrap().to_path_buf();
            match std::fs::symlink_metadata(&path).unwrap() {
                m if m.is_dir() => todo.push(path),
                m if m.file_type().is_symlink() => {
                    files.insert(relative, std::fs::read_link(&path).unwrap().into_os_string().into_encoded_bytes());
                }
                _ => {
                    files.insert(relative, std::fs::read(&path).unwrap());
                }
            }
        }
    }
    files
}

/// The names in `d`, sorted.
fn names(d: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

const SENSOR: &str = "[sensor]\nkind = \"orthographic\"\nwidth = 32\nheight = 24\npitch = [0.1, 0.1]\norigin = [-1.5, 1.1]\ntheta_deg = 30.0\n[shadow]\nmode = \"depth\"\n";

/// A scene file of one built-in model.
fn scene(d: &Path, name: &str, model: &str) -> PathBuf {
    let path = d.join(name);
    std::fs::write(&path, format!("{SENSOR}[[object]]\nmodel = \"{model}\"\n")).unwrap();
    path
}

fn render(scene: &Path, out: &Path) -> Output {
    run(&["render", s(scene), "--out", s(out)])
}

/// Starts `command` with the commit hook stopping it at `point`, waits until it is there (its
/// marker file appears) and kills it with SIGKILL.
fn kill_at(mut command: Command, point: &str, d: &Path) {
    let marker = d.join(format!("{point}.marker"));
    let _ = std::fs::remove_file(&marker);
    let mut child = command
        .env("RANGESYNTH_TEST_COMMIT", format!("{point}:{}", marker.display()))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !marker.exists() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("{point}: the process ended ({status}) without stopping in its commit");
        }
        assert!(start.elapsed() < Duration::from_secs(300), "{point}: no marker after 300 s");
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
}

#[test]
fn verify_outputs_onto_devices_fifos_sockets_and_links_to_them_are_refused() {
    let d = dir("verify_nodes");
    assert!(render(&scene(&d, "sensed.toml", "builtin:box"), &d.join("sensed")).status.success());
    let exr = d.join("sensed/range.exr");
    let hyps = d.join("h.json");
    let pose = "[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]";
    std::fs::write(
        &hyps,
        format!(
            "{{\"hypotheses\": [{{\"id\": \"a\", \"model\": \"builtin:box\", \"pose\": {pose}, \"bindings\": []}}]}}"
        ),
    )
    .unwrap();
    let verify = |out: &Path| run(&["verify", s(&hyps), "--scene", s(&exr), "--out", s(out)]);

    let device = d.join("null");
    make_char_device(&device);
    let cases: [(&str, &Make, &str); 5] = [
        ("null", &|_| {}, "is a character device"),
        ("fifo", &make_fifo, "is a FIFO"),
        ("socket", &make_socket, "is a socket"),
        ("link", &|p| std::os::unix::fs::symlink(&device, p).unwrap(), "character device (through a symbolic link)"),
        ("dir", &|p| std::fs::create_dir(p).unwrap(), "is a directory"),
    ];
    for (name, make, says) in cases {
        let out = d.join(name);
        make(&out);
        let before = what_is(&out);
        refused(&verify(&out), name, &[s(&out), says, "refusing to replace it"]);
        assert_eq!(what_is(&out), before, "{name} was replaced");
        assert_eq!(what_is(&device), "char device 103", "the device was replaced");
    }
    // No temporary file was left beside them.
    assert!(names(&d).iter().all(|n| !n.ends_with(".tmp")), "{:?}", names(&d));

    // A link to a regular file is replaced itself, as before: the file it named stays.
    let kept = d.join("kept.jsonl");
    std::fs::write(&kept, "mine\n").unwrap();
    let link = d.join("to_kept.jsonl");
    std::os::unix::fs::symlink(&kept, &link).unwrap();
    succeeded(&verify(&link), "a link to a regular file");
    assert_eq!(what_is(&link), "regular file");
    assert!(std::fs::read_to_string(&link).unwrap().contains("\"id\":\"a\""));
    assert_eq!(std::fs::read_to_string(&kept).unwrap(), "mine\n");
}

#[test]
fn render_and_accuracy_outputs_onto_devices_and_fifos_are_refused() {
    let d = dir("render_nodes");
    let box_scene = scene(&d, "box.toml", "builtin:box");
    // DIR itself a device.
    let device = d.join("null");
    make_char_device(&device);
    refused(&render(&box_scene, &device), "render --out a device", &[s(&device), "is a character device"]);
    assert_eq!(what_is(&device), "char device 103");

    // One of the set's files a device, a FIFO, a socket or a link to the device; or something
    // beside the set that cannot be carried into the new one: the previous set stays whole.
    let out = d.join("out");
    succeeded(&render(&box_scene, &out), "first render");
    let before = snapshot(&out);
    let step = scene(&d, "step.toml", "builtin:step");
    let cases: [(&str, &Make, &str); 5] = [
        ("range.exr", &make_char_device, "is a character device"),
        ("labels.json", &make_fifo, "is a FIFO"),
        ("label.png", &make_socket, "is a socket"),
        ("range.png", &|p| std::os::unix::fs::symlink(&device, p).unwrap(), "(through a symbolic link)"),
        ("a_fifo_of_mine", &make_fifo, "only regular files and symbolic links are carried over"),
    ];
    for (name, make, says) in cases {
        let path = out.join(name);
        let saved = std::fs::read(&path).ok();
        let _ = std::fs::remove_file(&path);
        make(&path);
        let node = what_is(&path);
        refused(&render(&step, &out), name, &[s(&path), says]);
        assert_eq!(what_is(&path), node, "{name} was replaced");
        std::fs::remove_file(&path).unwrap();
        if let Some(bytes) = saved {
            std::fs::write(&path, bytes).unwrap();
        }
        assert!(snapshot(&out) == before, "{name}: the refused render changed the previous set");
    }
    assert_eq!(names(&d), ["box.toml", "null", "out", "step.toml"], "a staging directory was left behind");

    // accuracy refuses before its sweep.
    let acc = d.join("acc");
    std::fs::create_dir(&acc).unwrap();
    make_fifo(&acc.join("accuracy.csv"));
    // Refused before its sweep, before it even opens a device: with none to be found, the
    // refusal it gives is still the FIFO's.
    let out = rangesynth()
        .env("RANGESYNTH_DEVICE", "no device has this name")
        .args(["accuracy", "--quick", "--out", s(&acc)])
        .output()
        .expect("the binary runs");
    refused(&out, "accuracy", &["accuracy.csv", "is a FIFO"]);
    assert_eq!(what_is(&acc.join("accuracy.csv")), "fifo");
}

#[test]
fn a_render_whose_swap_fails_leaves_the_previous_set_byte_identical() {
    let d = dir("render_swap_fails");
    let out = d.join("out");
    succeeded(&render(&scene(&d, "box.toml", "builtin:box"), &out), "first render");
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let before = snapshot(&out);
    // As a file system without RENAME_EXCHANGE fails it.
    let step = scene(&d, "step.toml", "builtin:step");
    let failed = rangesynth()
        .args(["render", s(&step), "--out", s(&out)])
        .env("RANGESYNTH_TEST_COMMIT", "fail")
        .output()
        .unwrap();
    refused(&failed, "a failed swap", &["RENAME_EXCHANGE", "the previous ones are as they were"]);
    assert!(snapshot(&out) == before, "the failed swap changed the previous set");
    assert_eq!(names(&d), ["box.toml", "out", "step.toml"], "a staging directory was left behind");
    // Without the failure the new set replaces the old one whole, the user's file carried over.
    succeeded(&render(&step, &out), "second render");
    let after = snapshot(&out);
    assert_eq!(after.keys().collect::<Vec<_>>(), before.keys().collect::<Vec<_>>());
    assert_eq!(after[Path::new("notes.txt")], b"mine");
    assert!(rangesynth::render_set::RENDER_FILES.iter().all(|f| after[Path::new(f)] != before[Path::new(f)]));
    assert_eq!(names(&d), ["box.toml", "out", "step.toml"], "the old set was left behind");
}

#[test]
fn a_render_killed_during_its_commit_leaves_one_whole_set() {
    let d = dir("render_killed");
    let (box_scene, step) = (scene(&d, "box.toml", "builtin:box"), scene(&d, "step.toml", "builtin:step"));
    let reference = d.join("reference");
    succeeded(&render(&step, &reference), "the reference render");
    let new = snapshot(&reference);
    let out = d.join("out");
    for (point, old_stays) in [("stop-before", true), ("stop-after", false)] {
        succeeded(&render(&box_scene, &out), "first render");
        let old = snapshot(&out);
        let mut command = rangesynth();
        command.args(["render", s(&step), "--out", s(&out)]);
        kill_at(command, point, &d);
        let now = snapshot(&out);
        match old_stays {
            true => assert!(now == old, "{point}: the killed render changed the previous set"),
            false => assert!(now == new, "{point}: the set is not the new render's whole"),
        }
        // The killed process's lock went with it.
        succeeded(&render(&box_scene, &out), "a render after the kill");
    }
}

#[test]
fn an_experiment_rerun_replaces_the_directory_whole() {
    let d = dir("experiment");
    let out = d.join("out");
    let experiment = |seed: &str| {
        let mut c = rangesynth();
        c.args(["experiment", "--quick", "--seed", seed, "--out", s(&out)]);
        c
    };
    succeeded(&experiment("3").output().unwrap(), "first run");
    let views = names(&out.join("views"));
    // A view of a larger earlier run, and a file of the user's.
    let stale = out.join("views/extra-9");
    std::fs::create_dir(&stale).unwrap();
    std::fs::copy(out.join("views").join(&views[0]).join("range.exr"), stale.join("range.exr")).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let before = snapshot(&out);

    // Killed as it swaps the new run in: the previous run's directory stays whole.
    kill_at(experiment("4"), "stop-before", &d);
    assert!(snapshot(&out) == before, "the killed run changed the previous directory");
    // (It leaves its staging directory, hidden, beside `out`.)
    let left = names(&d);

    succeeded(&experiment("4").output().unwrap(), "second run");
    assert_eq!(names(&out.join("views")), views, "views of another run were left");
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
    let after = snapshot(&out);
    assert_ne!(after[Path::new("summary.json")], before[Path::new("summary.json")]);
    for view in &views {
        let scores = Path::new("views").join(view).join("scores.jsonl");
        assert_ne!(after[&scores], before[&scores], "{view}: scores of the first run");
    }
    assert_eq!(names(&d), left, "the old directory or the staging one was left behind");
}

/// A test's directory and, in it, a working directory `work` holding the scene `box.toml`.
fn working_directory_with_a_box(name: &str) -> (PathBuf, PathBuf) {
    let d = dir(name);
    let work = d.join("work");
    std::fs::create_dir(&work).unwrap();
    scene(&work, "box.toml", "builtin:box");
    (d, work)
}

#[test]
fn a_render_into_a_new_directory_named_bare_lands_in_the_working_directory() {
    let (_, work) = working_directory_with_a_box("render_bare");
    let out = rangesynth().args(["render", "box.toml", "--out", "fresh"]).current_dir(&work).output().unwrap();
    succeeded(&out, "a bare name");
    let mut expected: Vec<&str> = rangesynth::render_set::RENDER_FILES.to_vec();
    expected.sort();
    assert_eq!(names(&work.join("fresh")), expected);
    assert_eq!(names(&work), ["box.toml", "fresh"]);
}

#[test]
fn a_render_into_the_working_directory_replaces_it_and_keeps_its_other_files() {
    let (d, work) = working_directory_with_a_box("render_dot");
    for round in 0..2 {
        let out = rangesynth().args(["render", "box.toml", "--out", "."]).current_dir(&work).output().unwrap();
        succeeded(&out, &format!("round {round}"));
        assert!(text(&out.stdout).contains("wrote ./range.exr"), "{}", text(&out.stdout));
        let mut expected: Vec<&str> = rangesynth::render_set::RENDER_FILES.to_vec();
        expected.push("box.toml");
        expected.sort();
        assert_eq!(names(&work), expected, "round {round}");
        assert_eq!(names(&d), ["work"], "round {round}");
    }
}

/// A report that cannot be written is an error that names it, not a panic (exit 101): stdout
/// on a full device (/dev/full's numbers, made here) fails each command with exit code 1;
/// stderr on one leaves a failing run's exit code 1, with nothing said.
#[test]
fn a_report_that_cannot_be_written_fails_the_run_by_name() {
    let d = dir("full");
    let full = d.join("full");
    // SAFETY: a valid NUL-terminated path; mknod only creates the node.
    let rc = unsafe { libc::mknod(c_path(&full).as_ptr(), libc::S_IFCHR | 0o666, libc::makedev(1, 7)) };
    assert_eq!(rc, 0, "mknod {}: {}", full.display(), std::io::Error::last_os_error());
    let to_full = || std::fs::OpenOptions::new().write(true).open(&full).unwrap();
    let box_scene = scene(&d, "box.toml", "builtin:box");
    let out =
        rangesynth().args(["render", s(&box_scene), "--out", s(&d.join("set"))]).stdout(to_full()).output().unwrap();
    refused(&out, "render's summary", &["writing to standard output"]);
    let acc = d.join("accuracy");
    let out = rangesynth().args(["accuracy", "--quick", "--out", s(&acc)]).stdout(to_full()).output().unwrap();
    refused(&out, "accuracy's table", &["writing to standard output"]);
    let mut missing = rangesynth();
    missing.args(["render", s(&d.join("missing.toml")), "--out", s(&d.join("x"))]);
    let out = missing.stdout(Stdio::null()).stderr(to_full()).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "a refusal with stderr full: {:?}", out.status);
}
