//! Scoring BOP results (docs/bop.md) on small BOP-format datasets the tests write: a 100 mm
//! box (its near face at the pose's depth, centred on its x and y) under a 640×480 camera of
//! fx = fy = 500, (cx, cy) = (319.5, 239.5), with a projector beside it. VSD and the depth-only
//! scores against values worked out by hand, VSD against the BOP toolkit's definition written
//! again here over the tests' own brute-force renderings (tests/common/rig_reference.rs), the
//! results file round trip, and each bad input refused by name.

mod common;

use common::bop_dataset::*;
use common::cli::{rangesynth_command, text};
use common::rig_reference::rig_reference;
use glam::{DMat4, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangesynth::bop::{BopScorer, BopSettings, Dataset, ResultRow, RowScores};
use rangesynth::limits::Ledger;
use rangesynth::sensor::Sensor;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use std::path::Path;

/// The rows' scores, the rig's images made in shadow mode `mode` (`depth`, `label` and `none`
/// on the GPU, with validation on).
fn score(root: &Path, baseline: f64, rows: &[ResultRow], mode: ShadowMode) -> Vec<RowScores> {
    let ledger = Ledger::default();
    let dataset = Dataset::open(root, "test", &ledger).unwrap();
    let settings = BopSettings { rig: rig(baseline), delta: DELTA, shadow: ShadowSettings::of(mode) };
    let renderer = (mode != ShadowMode::Exact).then(common::renderer);
    let mut scorer = BopScorer::new(&dataset, &settings, renderer, &ledger).unwrap();
    let scores = scorer.score_rows(rows).unwrap();
    common::assert_no_validation_messages();
    scores
}

/// The box's near face at 1000 mm covers |c − 319.5| ≤ 50·500/1000 = 25, columns 295 to 344,
/// and rows 215 to 264: 2,500 pixels, the depth image of image 1. At 1045 mm it covers
/// |c − 319.5| ≤ 23.92: 48 × 48 pixels, all within the ground truth's; at 970 mm,
/// |c − 319.5| ≤ 25.77: 52 × 52.
///
/// - The true pose: VSD 0 at every τ (recall 1); every pixel an inlier, depth score 1.
/// - 45 mm farther: its distances differ from the truth's by 45·|ray| ≈ 0.225 of the diameter,
///   so for τ ≤ 0.20 every pixel of the union costs (e = 1) and for τ ≥ 0.25 only the 196
///   pixels of the truth alone (e = 196/2500 = 0.0784): VSD (4 + 6 · 0.0784)/10 = 0.44704, and
///   0.0784 is below 9 of the 10 thresholds: recall 6 · 9 / 100 = 0.54. Every pixel sees the
///   sensed surface 45 mm nearer: occluded, no inlier, no violation, depth score 0.
/// - 30 mm nearer: the sensed surface lies 30 mm beyond it on its 2,500 pixels the image
///   measured, violations, of 2,704; the other 204 are missing: depth score 0.
///
/// In shadow mode `exact` (cast on the CPU), and `depth` and `label` (drawn on the GPU), with one
/// allowance for the label test's edge.
/// - Image 2's depth is 500 mm everywhere, something in front of the whole box: the truth is
///   visible nowhere, nor the estimate; VSD 1 (recall 0); every pixel occluded.
#[test]
fn vsd_and_the_depth_scores_take_their_hand_worked_values() {
    let truth = at(0.0, 0.0, 1000.0);
    let root = dataset(
        "hand",
        &[(1, square(295..=344, 215..=264, 1000), vec![truth]), (2, vec![500; 640 * 480], vec![truth])],
    );
    let rows = [row(1, truth), row(1, at(0.0, 0.0, 1045.0)), row(1, at(0.0, 0.0, 970.0)), row(2, truth)];
    // Cast on the CPU, and drawn on the GPU (the depth test's walk, and the paper's label test).
    for mode in [ShadowMode::Exact, ShadowMode::Depth, ShadowMode::Label] {
        let scores = score(&root, 75.0, &rows, mode);
        let [same, farther, nearer, hidden] = [scores[0], scores[1], scores[2], scores[3]];
        assert_eq!(same.vsd, Some((0.0, 1.0)), "{mode:?}");
        assert_eq!((same.depth.inlier, same.depth.violation, same.depth.depth_score), (1.0, 0.0, 1.0), "{mode:?}");
        assert_eq!(same.depth.explained_holes, None, "{mode:?}: the projector lights the whole near face");
        let (vsd, recall) = farther.vsd.unwrap();
        assert!((vsd - 0.44704).abs() < 1e-12 && recall == 0.54, "{mode:?}: {farther:?}");
        let farther_depth = (farther.depth.inlier, farther.depth.violation, farther.depth.depth_score);
        assert_eq!(farther_depth, (0.0, 0.0, 0.0), "{mode:?}");
        // The label test may lose a column of the 52 × 52 face to the projector's label edge
        // (within a pixel of it), which the rig then explains: 2,500 violations of 2,652
        // measured, and the 52 lost pixels explained holes of the depth score.
        let (violation, depth_score) = (nearer.depth.violation, nearer.depth.depth_score);
        match mode {
            ShadowMode::Exact | ShadowMode::Depth => assert_eq!((violation, depth_score), (2500.0 / 2704.0, 0.0)),
            _ => {
                let column_lost = (violation, depth_score) == (2500.0 / 2652.0, 52.0 / 2704.0);
                assert!(column_lost || (violation, depth_score) == (2500.0 / 2704.0, 0.0), "{mode:?}: {nearer:?}");
            }
        }
        assert_eq!(nearer.depth.inlier, 0.0, "{mode:?}");
        assert_eq!(hidden.vsd, Some((1.0, 0.0)), "{mode:?}");
        assert_eq!(hidden.depth.depth_score, 0.0, "{mode:?}");
        // Nothing on the box is shadowed: VSD under the rig is the same (but for the column
        // the label test may lose of the nearer estimate).
        for (i, s) in scores.iter().enumerate() {
            if !(mode == ShadowMode::Label && i == 2) {
                assert_eq!(s.vsd, s.vsd_shadowed, "{mode:?}: {s:?}");
            }
        }
    }
}

/// The box 200 mm to the right and 0.3 mm down (its near face at x = 150 to 250, columns 395 to
/// 444, and y = −49.7 to 50.3, rows 215 to 264) and a projector 300 mm to the right: the box's
/// left face (x = 150, facing −x) is turned away from the projector, so the camera's pixels on
/// it, columns 388 to 394 (c − 319.5 = 75,000/Z for Z from 1000 to 1100) and rows whose
/// r − 239.5 = 500·y/Z lies in [−49.7, 50.3]·(c − 319.5)/150 (no pixel centre on an edge), are
/// shadowed. An image that left
/// them empty explains every hole (explained_holes 1, depth score 1); one that measured the
/// face there explains none, and the depth score is 2500 / (2500 + the face's pixels).
#[test]
fn the_rigs_shadow_on_the_model_is_an_explained_hole_where_the_image_is_empty() {
    let truth = at(200.0, 0.3, 1000.0);
    let front = square(395..=444, 215..=264, 1000);
    let mut measured = front.clone();
    let mut face = 0;
    for c in 388..=394usize {
        let u = c as f64 - 319.5;
        for r in 0..480usize {
            if (-49.7 * u / 150.0..=50.3 * u / 150.0).contains(&(r as f64 - 239.5)) {
                measured[r * 640 + c] = (75_000.0 / u).round() as u16;
                face += 1;
            }
        }
    }
    let root = dataset("holes", &[(1, front, vec![truth]), (2, measured, vec![truth])]);
    for mode in [ShadowMode::Exact, ShadowMode::Depth, ShadowMode::Label] {
        let scores = score(&root, 300.0, &[row(1, truth), row(2, truth)], mode);
        let first = (scores[0].depth.explained_holes, scores[0].depth.depth_score);
        assert_eq!(first, (Some(1.0), 1.0), "{mode:?}: {:?}", scores[0]);
        assert_eq!(scores[0].depth.inlier, 1.0, "{mode:?}");
        assert_eq!(scores[1].depth.explained_holes, Some(0.0), "{mode:?}");
        let expected = 2500.0 / (2500.0 + f64::from(face));
        assert_eq!(scores[1].depth.depth_score, expected, "{mode:?}: {face} face pixels");
    }
}

/// VSD as the BOP toolkit defines it (pose_error.vsd, visibility 'bop19', step cost), written
/// again from that definition over depth images the tests' brute-force reference renders.
fn reference_vsd(test: &[f64], estimate: &[f64], truth: &[f64]) -> (f64, f64) {
    let dist = |depth: &[f64]| -> Vec<f64> {
        (0..depth.len())
            .map(|i| {
                let (u, v, z) = ((i % 640) as f64, (i / 640) as f64, depth[i]);
                let (x, y) = ((u - K[2]) / K[0] * z, (v - K[5]) / K[4] * z);
                (x * x + y * y + z * z).sqrt()
            })
            .collect()
    };
    let (dt, de, dg) = (dist(test), dist(estimate), dist(truth));
    let visible = |m: f64, t: f64| ((m as f32 - t as f32) <= DELTA as f32 || t == 0.0) && m > 0.0;
    let taus: Vec<f64> = (0..10).map(|k| 0.05 + k as f64 * 0.05).collect();
    let (mut union, mut inter, mut dists) = (0usize, 0usize, Vec::new());
    for i in 0..dt.len() {
        let g = visible(dg[i], dt[i]);
        let e = visible(de[i], dt[i]) || (g && de[i] > 0.0);
        union += usize::from(g || e);
        if g && e {
            inter += 1;
            dists.push((dg[i] - de[i]).abs() / DIAMETER);
        }
    }
    let errors: Vec<f64> = taus
        .iter()
        .map(|&tau| match union {
            0 => 1.0,
            _ => (dists.iter().filter(|&&d| d >= tau).count() + union - inter) as f64 / union as f64,
        })
        .collect();
    let recall = errors.iter().map(|&e| taus.iter().filter(|&&th| e < th).count()).sum::<usize>() as f64 / 100.0;
    (errors.iter().sum::<f64>() / 10.0, recall)
}

/// The box leaning on a wall 1150 mm away, the image its true rendering (depth to the nearest
/// mm) with the rig's holes: random estimates around the truth score the VSD the toolkit's
/// definition gives over the reference's renderings, alone and under the rig (renderings'
/// unmeasured pixels empty).
#[test]
fn vsd_equals_the_toolkits_definition_on_random_estimates() {
    let truth = at(-30.0, 20.0, 1000.0) * DMat4::from_rotation_y(0.5) * DMat4::from_rotation_x(-0.3);
    let render = |pose: DMat4| {
        let mut scene = common::scene(rig(75.0), ShadowMode::Exact, &[("builtin:box", pose)]);
        scene.objects[0].mesh =
            std::sync::Arc::new((*scene.objects[0].mesh).clone().scaled(100.0, &Default::default()).unwrap());
        rig_reference(&scene)
    };
    let image = render(truth);
    let depth_of = |r: &common::rig_reference::RigReference, shadowed: bool| -> Vec<f64> {
        (0..r.depth.len())
            .map(|i| if r.label[i] != 0 && (!shadowed || r.witness[i] == 0) { r.depth[i] } else { 0.0 })
            .collect()
    };
    let sensed: Vec<u16> = depth_of(&image, true).iter().map(|&d| d.round() as u16).collect();
    let root = dataset("random", &[(1, sensed.clone(), vec![truth])]);
    let test: Vec<f64> = sensed.iter().map(|&v| f64::from(v)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(38);
    let estimates: Vec<DMat4> = (0..3)
        .map(|_| {
            let shift = DVec3::new(rng.gen_range(-15.0..15.0), rng.gen_range(-15.0..15.0), rng.gen_range(-40.0..40.0));
            DMat4::from_translation(shift) * truth * DMat4::from_rotation_z(rng.gen_range(-0.2..0.2))
        })
        .collect();
    let rows: Vec<ResultRow> = estimates.iter().map(|&p| row(1, p)).collect();
    let scores = score(&root, 75.0, &rows, ShadowMode::Exact);
    let truth_image = render(truth);
    for (pose, s) in estimates.iter().zip(&scores) {
        let estimate = render(*pose);
        for (shadowed, ours) in [(false, s.vsd.unwrap()), (true, s.vsd_shadowed.unwrap())] {
            let expected = reference_vsd(&test, &depth_of(&estimate, shadowed), &depth_of(&truth_image, shadowed));
            assert!(
                (ours.0 - expected.0).abs() < 1e-12 && ours.1 == expected.1,
                "shadowed {shadowed}: {ours:?} against {expected:?}"
            );
        }
    }
}

fn bop_command(root: &Path, results: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let rig_file = root.join("rig.toml");
    let rig = "[sensor]\nkind = \"pinhole\"\nwidth = 1\nheight = 1\nfx = 1.0\nfy = 1.0\ncx = 0.0\ncy = 0.0\n\
               [[sensor.witness]]\nname = \"projector\"\nkind = \"pinhole\"\npose = [[1,0,0,0.075],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n\
               width = 1280\nheight = 480\nfx = 500.0\nfy = 500.0\ncx = 639.5\ncy = 239.5\n[[object]]\nmodel = \"builtin:box\"\n";
    std::fs::write(&rig_file, rig).unwrap();
    let mut command = rangesynth_command();
    command.args(["bop", root.to_str().unwrap(), "--results", results.to_str().unwrap(), "--rig"]);
    command.args([rig_file.to_str().unwrap(), "--out", out.to_str().unwrap()]).args(extra);
    command.output().unwrap()
}

/// From the command line, with the rig in metres (the default --rig-scale 1000): the scores file
/// repeats each input row's fields as written, in input order, then the eight score columns,
/// the same numbers the library gives; --targets leaves out the rows it does not list.
#[test]
fn the_command_repeats_the_results_rows_and_adds_the_scores() {
    let truth = at(0.0, 0.0, 1000.0);
    let root = dataset("cli", &[(1, square(295..=344, 215..=264, 1000), vec![truth]), (2, vec![0; 640 * 480], vec![])]);
    let rows = [row(1, at(0.0, 0.0, 1045.0)), row(2, truth), row(1, truth)];
    let results = root.join("results.csv");
    let body: Vec<String> = rows.iter().map(|r| r.fields.join(",")).collect();
    std::fs::write(&results, format!("scene_id,im_id,obj_id,score,R,t,time\n{}\n", body.join("\n"))).unwrap();
    let out = root.join("scores.csv");
    let run = bop_command(&root, &results, &out, &[]);
    assert!(run.status.success(), "{}{}", text(&run.stdout), text(&run.stderr));
    let written = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = written.lines().collect();
    assert_eq!(
        lines[0],
        "scene_id,im_id,obj_id,score,R,t,time,inlier,violation,explained_holes,depth_score,vsd,vsd_recall,vsd_shadowed,vsd_shadowed_recall"
    );
    assert_eq!(lines.len(), 4);
    let expected = score(&root, 75.0, &rows, ShadowMode::Exact);
    for ((line, row), scores) in lines[1..].iter().zip(&rows).zip(&expected) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells[..7], row.fields.iter().map(String::as_str).collect::<Vec<_>>()[..], "{line}");
        assert_eq!(cells[7..], scores.cells().iter().map(String::as_str).collect::<Vec<_>>()[..], "{line}");
    }
    // --shadow-mode label: the rows of image 1 drawn together on the GPU, as the library draws them.
    let run = bop_command(&root, &results, &out, &["--shadow-mode", "label", "--validation"]);
    assert!(run.status.success(), "{}{}", text(&run.stdout), text(&run.stderr));
    let written = std::fs::read_to_string(&out).unwrap();
    let expected = score(&root, 75.0, &rows, ShadowMode::Label);
    for (line, scores) in written.lines().skip(1).zip(&expected) {
        assert!(line.ends_with(&scores.cells().join(",")), "{line}: {:?}", scores.cells());
    }
    assert_eq!(written.lines().count(), 4);
    // Image 2 has no ground truth for the object: its VSD cells are empty.
    assert!(lines[2].ends_with(",,,,"), "{}", lines[2]);
    let targets = root.join("targets.json");
    std::fs::write(&targets, r#"[{"scene_id": 1, "im_id": 1, "obj_id": 1, "inst_count": 1}]"#).unwrap();
    let run = bop_command(&root, &results, &out, &["--targets", targets.to_str().unwrap()]);
    assert!(run.status.success(), "{}", text(&run.stderr));
    let written = std::fs::read_to_string(&out).unwrap();
    assert_eq!(written.lines().count(), 3, "{written}");
}

/// Each bad input is refused with the file, the scene and image, and the field named; the
/// previous scores file is left whole.
#[test]
fn bad_bop_input_is_refused_by_name() {
    let truth = at(0.0, 0.0, 1000.0);
    let root = dataset("bad", &[(1, square(295..=344, 215..=264, 1000), vec![truth])]);
    let results = root.join("results.csv");
    let out = root.join("scores.csv");
    std::fs::write(&out, "previous\n").unwrap();
    let refused = |rows: &str, expected: &[&str]| {
        std::fs::write(&results, format!("scene_id,im_id,obj_id,score,R,t,time\n{rows}\n")).unwrap();
        let run = bop_command(&root, &results, &out, &[]);
        let stderr = text(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{rows}: {stderr}");
        for e in expected {
            assert!(stderr.contains(e), "{rows}: expected {e:?} in {stderr}");
        }
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "previous\n");
    };
    let identity = "1 0 0 0 1 0 0 0 1";
    refused(&format!("1,9,1,0.5,{identity},0 0 1000,1"), &["scene_camera.json", "has no image 9 (scene 1)"]);
    refused(&format!("1,1,7,0.5,{identity},0 0 1000,1"), &["models_info.json", "lists no object 7"]);
    refused(
        "1,1,1,0.5,1 0 0 0 1 0 0 0 -1,0 0 1000,1",
        &["results.csv", "row 1 (scene 1, image 1, object 1)", "R is not a rotation"],
    );
    refused(&format!("2,1,1,0.5,{identity},0 0 1000,1"), &["000002", "scene_camera.json"]);
    let camera = root.join("test/000001/scene_camera.json");
    let good = std::fs::read_to_string(&camera).unwrap();
    std::fs::write(&camera, good.replace("\"depth_scale\": 1.0", "\"depth_scale\": 0.0")).unwrap();
    refused(&format!("1,1,1,0.5,{identity},0 0 1000,1"), &["scene 1, image 1: depth_scale = 0"]);
    std::fs::write(&camera, good.replace("0.0, 0.0, 1.0]", "0.0, 0.0]")).unwrap();
    refused(&format!("1,1,1,0.5,{identity},0 0 1000,1"), &["scene 1, image 1: cam_K must be 9 finite numbers"]);
    // An image given two cameras, as the same key or another spelling of its id.
    let twice = good.replacen('{', "{\"1\": {\"cam_K\": [1, 0, 0, 0, 1, 0, 0, 0, 1], \"depth_scale\": 1.0}, ", 1);
    std::fs::write(&camera, &twice).unwrap();
    refused(&format!("1,1,1,0.5,{identity},0 0 1000,1"), &["scene_camera.json", "image 1 is given twice (key \"1\")"]);
    std::fs::write(
        &camera,
        good.replacen('{', "{\"000001\": {\"cam_K\": [1, 0, 0, 0, 1, 0, 0, 0, 1], \"depth_scale\": 1.0}, ", 1),
    )
    .unwrap();
    refused(&format!("1,1,1,0.5,{identity},0 0 1000,1"), &["image 1 is given twice"]);
    std::fs::write(&camera, &good).unwrap();
    std::fs::remove_file(root.join("test/000001/depth/000001.png")).unwrap();
    refused(&format!("1,1,1,0.5,{identity},0 0 1000,1"), &["000001.png"]);
}

/// `bop` reads a scene's depth images, cameras, ground truth and models as it reaches them,
/// after its output is started: none of them may be its output, however late it was read,
/// and the scores file is not written.
#[test]
fn bop_never_writes_over_a_file_of_its_dataset() {
    let truth = at(0.0, 0.0, 1000.0);
    let root = dataset("protected", &[(1, square(295..=344, 215..=264, 1000), vec![truth])]);
    let results = root.join("results.csv");
    std::fs::write(&results, format!("scene_id,im_id,obj_id,score,R,t,time\n{}\n", row(1, truth).fields.join(",")))
        .unwrap();
    for target in [
        "test/000001/depth/000001.png",
        "test/000001/scene_camera.json",
        "test/000001/scene_gt.json",
        "models/obj_000001.ply",
        "models/models_info.json",
        "results.csv",
    ] {
        let path = root.join(target);
        let before = std::fs::read(&path).unwrap();
        let run = bop_command(&root, &results, &path, &[]);
        let stderr = text(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{target}: {stderr}");
        assert!(stderr.contains("this output is one of the run's inputs"), "{target}: {stderr}");
        assert_eq!(std::fs::read(&path).unwrap(), before, "{target} changed");
    }
}

/// The shadow mode the rig's images are made in is checked before any row: modes `depth` and
/// `label` without a device to draw on are refused by name.
#[test]
fn shadow_modes_the_scorer_cannot_make_are_refused_by_name() {
    let root = dataset("modes", &[(1, square(295..=344, 215..=264, 1000), vec![at(0.0, 0.0, 1000.0)])]);
    let ledger = Ledger::default();
    let dataset = Dataset::open(&root, "test", &ledger).unwrap();
    let refused = |rig: Sensor, mode: ShadowMode, renderer: Option<&rangesynth::Renderer>| {
        let settings = BopSettings { rig, delta: DELTA, shadow: ShadowSettings::of(mode) };
        BopScorer::new(&dataset, &settings, renderer, &ledger).err().map(|e| e.to_string()).unwrap_or_default()
    };
    for mode in [ShadowMode::Depth, ShadowMode::Label] {
        let e = refused(rig(75.0), mode, None);
        assert!(e.contains(&format!("shadow mode \"{}\"", mode.as_str())) && e.contains("needs a renderer"), "{e}");
    }
}
