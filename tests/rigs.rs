//! Rigs: pinhole reference views and witness sets (docs/sensors-and-rigs.md), against
//! geometry worked out by hand and the tests' own brute-force reference
//! (tests/common/rig_reference.rs).

mod common;

use common::rig_reference::rig_reference;
use common::scorer::{as_cpu, cpu_counts, cpu_scores, Images};
use common::{render, scene};
use glam::{DMat4, DVec3};
use rangesynth::effects::Reason;
use rangesynth::io::RangeImage;
use rangesynth::sensor::{Direction, Intrinsics, Pinhole, Sensor, View, Witness, WitnessGeometry};
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, VerifySettings};
use rangesynth::Scene;

/// A 640×480 camera, fx = fy = 500, whose pixel (320, 240) looks along its axis: on a plane
/// at depth Z, column c lies at X = Z·(c − 320)/500.
fn camera() -> Intrinsics {
    Intrinsics { width: 640, height: 480, fx: 500.0, fy: 500.0, cx: 320.0, cy: 240.0 }
}

fn reference() -> View {
    View::Pinhole(Pinhole { intrinsics: camera(), near: 0.0, far: f64::INFINITY })
}

/// A pinhole projector at `centre` (reference frame), looking along the camera's axis.
fn projector(name: &str, centre: DVec3, intrinsics: Intrinsics) -> Witness {
    Witness {
        name: name.into(),
        geometry: WitnessGeometry::Pinhole { pose: DMat4::from_translation(centre), intrinsics },
    }
}

/// Turns a model's +z (the built-in models' up) toward the camera, which looks down +z.
fn facing_camera(at: DVec3) -> DMat4 {
    DMat4::from_translation(at) * DMat4::from_rotation_x(std::f64::consts::PI)
}

/// A plane at depth 5 and the unit box standing on it, its near face at depth 4 and its
/// x from 0.2 to 1.2 (camera frame).
fn box_on_plane(witnesses: Vec<Witness>) -> Scene {
    let sensor = Sensor { reference: reference(), witnesses };
    scene(
        sensor,
        ShadowMode::Exact,
        &[
            ("builtin:plane:20", facing_camera(DVec3::new(0.0, 0.0, 5.0))),
            ("builtin:box", facing_camera(DVec3::new(0.7, 0.0, 5.0))),
        ],
    )
}

const PROJECTOR_BASELINE: f64 = 0.75;

/// The projector's image: 800 columns, wide enough that every point the camera sees on the
/// plane (X from −3.2 to 3.2 at depth 5) lies on it (u = 500·(X − 0.75)/5 + 400, from 5 to
/// 644).
fn projector_image() -> Intrinsics {
    Intrinsics { width: 800, cx: 400.0, ..camera() }
}

/// The projector's shadow of the box on the plane along row 240 (Y = 0). A plane point
/// (X, 0, D) is hidden from the projector at (b, 0, 0) when the segment to it passes through
/// the box, whose near face is at depth D − h and spans x ≥ x0: at that depth the segment's x
/// is X + (b − X)·h/D, which reaches x0 for X ≥ (x0·D − b·h)/(D − h) = (1 − 0.75)/4 = 0.0625:
/// columns 326.25 to 340 (X = 0.2, where the box stands). Columns 340 to 345 see the box's
/// left face (x = 0.2 is crossed at depths 5 to 4), which turns away from the projector
/// (b > x0); from column 345 the camera sees the near face, lit up to column 470 (x = 1.2 at
/// depth 4), and beyond it the plane again, lit (the projector's shadow on that side lies
/// under the box's far edge, which the camera does not see).
///
/// In every shadow mode: `exact` cast on the CPU, `depth` and `label` drawn on the GPU (whose
/// f32 depths and points are held to 4e-7 of the depth, a few f32 roundings, where the CPU's
/// are held to 1e-6 absolute).
#[test]
fn a_box_on_a_plane_casts_the_projectors_geometric_shadow() {
    for mode in [ShadowMode::Exact, ShadowMode::Depth, ShadowMode::Label] {
        let mut rig =
            box_on_plane(vec![projector("projector", DVec3::new(PROJECTOR_BASELINE, 0.0, 0.0), projector_image())]);
        rig.shadow.mode = mode;
        let on_gpu = mode != ShadowMode::Exact;
        let tolerance = if on_gpu { 4e-7 * 5.0 } else { 1e-6 };
        let out = render(&rig);
        assert_eq!(out.raster.is_some(), on_gpu, "{mode:?}: drawn on the GPU");
        let checked = box_shadow_row(&out, tolerance, &format!("{mode:?}"));
        assert_eq!(checked, 640 - 5, "{mode:?}");
    }
}

/// Checks row 240 of a render of the box on the plane against the worked shadow band, depths
/// and points within `tolerance`; returns how many columns it checked.
fn box_shadow_row(out: &rangesynth::RenderOutput, tolerance: f64, what: &str) -> usize {
    let plane = 1; // the plane's one surface; the box's are 2 to 7
    let row = 240;
    let mut checked = 0;
    for col in 0..640u32 {
        let i = (row * 640 + col) as usize;
        let x = f64::from(col as i32 - 320) / 100.0;
        let expected = match col {
            0..=325 | 472..=639 => Some((plane, Reason::Valid, 5.0)),
            327..=339 => Some((plane, Reason::Shadow, 5.0)),
            341..=344 => Some((0, Reason::Shadow, f64::NAN)),
            346..=469 => Some((0, Reason::Valid, 4.0)),
            _ => None, // within a pixel of an edge
        };
        let Some((label, reason, depth)) = expected else { continue };
        assert_eq!(out.reason[i], reason, "{what}: column {col} (X = {x})");
        assert_eq!(out.witness[i], u32::from(reason == Reason::Shadow), "{what}: column {col}");
        if label == plane {
            assert_eq!(out.label_unshadowed[i], plane, "{what}: column {col}");
        } else {
            assert_ne!(out.label_unshadowed[i], plane, "{what}: column {col}: the box");
        }
        if !depth.is_nan() {
            assert!((f64::from(out.z[i]) - depth).abs() < tolerance, "{what}: column {col}: Z = {}", out.z[i]);
            let [px, py, _] = out.point(i).unwrap_or([f32::NAN; 3]);
            if reason == Reason::Valid {
                let close = (f64::from(px) - depth * x / 5.0).abs() < tolerance && f64::from(py).abs() < tolerance;
                assert!(close, "{what}: column {col}: X = {px}, Y = {py}");
            }
        }
        checked += 1;
    }
    checked
}

/// Witness 0 a light straight along the camera's axis, which sees the whole plane beside
/// the box; witness 1 the projector. The projector's shadow band carries bit 1 alone.
#[test]
fn a_pixel_hidden_from_one_witness_carries_its_bit_alone() {
    let light =
        Witness { name: "light".into(), geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::NEG_Z)) };
    let rig =
        box_on_plane(vec![light, projector("projector", DVec3::new(PROJECTOR_BASELINE, 0.0, 0.0), projector_image())]);
    let out = render(&rig);
    let row = 240usize;
    for col in 327..=339 {
        assert_eq!(out.witness[row * 640 + col], 0b10, "column {col}");
    }
    for col in (0..=325).chain(346..=469) {
        assert_eq!(out.witness[row * 640 + col], 0, "column {col}");
    }
    // The box's left face is edge-on to the light along the axis, and turned from the
    // projector: lost by both.
    for col in 341..=344 {
        assert_eq!(out.witness[row * 640 + col], 0b11, "column {col}");
    }
    assert_eq!(out.pixels_lost_by_witness()[1], out.witness.iter().filter(|&&b| b & 2 != 0).count());
}

/// A witness at the camera's own centre with a 64×48 image (cx = 31.25, cy = 23.25): a plane
/// point of pixel (c, r) projects to (c − 320 + 31.25, r − 240 + 23.25), on its image for
/// columns 289 to 352 and rows 217 to 264 exactly; nothing else is lost by it.
#[test]
fn a_point_outside_a_witnesss_field_of_view_is_lost_by_that_witness() {
    let narrow = Intrinsics { width: 64, height: 48, fx: 500.0, fy: 500.0, cx: 31.25, cy: 23.25 };
    let sensor = Sensor { reference: reference(), witnesses: vec![projector("narrow", DVec3::ZERO, narrow)] };
    let out =
        render(&scene(sensor, ShadowMode::Exact, &[("builtin:plane:20", facing_camera(DVec3::new(0.0, 0.0, 5.0)))]));
    for row in 0..480 {
        for col in 0..640 {
            let seen = (289..=352).contains(&col) && (217..=264).contains(&row);
            let i = (row * 640 + col) as usize;
            assert_eq!(out.witness[i], u32::from(!seen), "pixel ({col}, {row})");
            assert_eq!(out.label[i] != 0, seen, "pixel ({col}, {row})");
        }
    }
}

/// The pixels whose label, depth (to `depth_tolerance` of it) or witness bits (where
/// `witnesses_tested`, else 0) differ from the reference's, and how many of them are interior: their four
/// neighbours in the reference all carry their label and bits, so that no surface edge or
/// shadow edge passes by.
fn differences(
    out: &rangesynth::RenderOutput,
    truth: &common::rig_reference::RigReference,
    witnesses_tested: bool,
    depth_tolerance: f64,
) -> (usize, usize) {
    let (w, h) = (i64::from(truth.width), i64::from(truth.height));
    let interior = |i: usize| {
        let (c, r) = (i as i64 % w, i as i64 / w);
        [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().all(|(dc, dr)| {
            let (c, r) = (c + dc, r + dr);
            let j = (r * w + c) as usize;
            c < 0
                || r < 0
                || c >= w
                || r >= h
                || (truth.label[j] == truth.label[i] && truth.witness[j] == truth.witness[i])
        })
    };
    let wrong: Vec<usize> = (0..truth.label.len())
        .filter(|&i| {
            let bits = if witnesses_tested { truth.witness[i] } else { 0 };
            out.label_unshadowed[i] != truth.label[i]
                || out.witness[i] != bits
                || (truth.label[i] != 0
                    && (f64::from(out.z[i]) - truth.depth[i]).abs() > depth_tolerance * truth.depth[i].abs().max(1.0))
        })
        .collect();
    let interior_wrong = wrong.iter().filter(|&&i| interior(i)).count();
    (wrong.len(), interior_wrong)
}

/// A sphere and a cluttered table under a camera, a projector 7.5 cm to its right and an IR
/// camera 2.5 cm to its left (a Kinect-like rig): labels, depths and witness bits in modes
/// `exact`, `depth`, `none` and `label` against the brute-force reference, with no interior
/// pixel wrong (a pixel whose neighbours in the reference all agree with it).
#[test]
fn a_sphere_and_a_cluttered_table_match_the_brute_force_reference() {
    let k = Intrinsics { width: 160, height: 120, fx: 150.0, fy: 150.0, cx: 79.5, cy: 59.5 };
    let witnesses = vec![
        projector("projector", DVec3::new(0.075, 0.0, 0.0), Intrinsics { width: 200, height: 160, ..k }),
        projector("ir", DVec3::new(-0.025, 0.002, 0.0), k),
    ];
    let sensor =
        Sensor { reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.1, far: f64::INFINITY }), witnesses };
    let tilt = |at: DVec3, angle: f64| facing_camera(at) * DMat4::from_rotation_z(angle);
    // (model, pose, scale into the scene's units).
    let objects = [
        ("builtin:plane:4", facing_camera(DVec3::new(0.0, 0.0, 1.5)), 1.0),
        ("builtin:sphere:24", facing_camera(DVec3::new(-0.25, 0.05, 1.3)), 0.15),
        ("builtin:box", tilt(DVec3::new(0.2, -0.1, 1.5), 0.4), 0.25),
        ("builtin:step", tilt(DVec3::new(0.05, 0.3, 1.5), -0.7), 0.25),
        ("builtin:cylinder:16", tilt(DVec3::new(0.45, 0.25, 1.5), 0.0), 0.2),
    ];
    let posed: Vec<(&str, DMat4)> = objects.iter().map(|&(model, pose, _)| (model, pose)).collect();
    for mode in [ShadowMode::Exact, ShadowMode::Depth, ShadowMode::None, ShadowMode::Label] {
        let mut rig = scene(sensor.clone(), mode, &posed);
        for (object, &(_, _, scale)) in rig.objects.iter_mut().zip(&objects) {
            object.mesh = std::sync::Arc::new((*object.mesh).clone().scaled(scale, &Default::default()).unwrap());
        }
        let out = render(&rig);
        let truth = rig_reference(&rig);
        let tested = mode != ShadowMode::None;
        assert!(out.shadow_pass == tested, "{mode:?}: the witnesses were tested");
        assert_eq!(out.raster.is_some(), mode != ShadowMode::Exact, "{mode:?}: drawn on the GPU");
        let (wrong, wrong_interior) = differences(&out, &truth, tested, 1e-6);
        let lost = if tested { truth.witness.iter().filter(|&&bits| bits != 0).count() } else { 0 };
        eprintln!("{mode:?}: {wrong} pixels differ from the reference, {wrong_interior} interior; {lost} lost");
        assert_eq!(wrong_interior, 0, "{mode:?}: {wrong} pixels differ, {wrong_interior} interior");
        if tested {
            assert!(lost > 200, "the rig loses pixels to its witnesses: {lost}");
        }
    }
}

/// Mode `depth` where its walk over the surfaces matters: a dense ball (9,800 triangles, about
/// two to a pixel of the camera and of the projector) before a plane, under a projector 0.5
/// to the camera's right and a lamp high to its left. Each witness sees the ball's self-shadow
/// (the band past its terminator) and its cast shadow on the plane; the triangles over a
/// point are mostly missing from the witness's image and are found by walking to them. Labels,
/// depths and witness bits against the brute-force reference, with no interior pixel wrong.
#[test]
fn depth_mode_walks_a_dense_ball_to_its_self_shadow_as_the_reference_casts_it() {
    let k = Intrinsics { width: 96, height: 72, fx: 160.0, fy: 160.0, cx: 47.5, cy: 35.5 };
    let lamp = DVec3::new(-0.6, -0.3, -0.74).normalize();
    let witnesses = vec![
        projector("projector", DVec3::new(0.5, 0.0, 0.0), Intrinsics { width: 320, cx: 159.5, ..k }),
        Witness { name: "lamp".into(), geometry: WitnessGeometry::Directional(Direction::Vector(lamp)) },
    ];
    let sensor =
        Sensor { reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY }), witnesses };
    let objects = [
        ("builtin:plane:4", facing_camera(DVec3::new(0.0, 0.0, 1.4)), 2.0),
        ("builtin:sphere:100", facing_camera(DVec3::new(0.02, 0.01, 1.0)), 0.3),
    ];
    let posed: Vec<(&str, DMat4)> = objects.iter().map(|&(model, pose, _)| (model, pose)).collect();
    let mut rig = scene(sensor, ShadowMode::Depth, &posed);
    for (object, &(_, _, scale)) in rig.objects.iter_mut().zip(&objects) {
        object.mesh = std::sync::Arc::new((*object.mesh).clone().scaled(scale, &Default::default()).unwrap());
    }
    let out = render(&rig);
    assert_eq!(out.raster, Some(common::gpu_raster()), "drawn on the GPU");
    let truth = rig_reference(&rig);
    let (wrong, wrong_interior) = differences(&out, &truth, true, 1e-6);
    eprintln!("{wrong} pixels differ from the reference, {wrong_interior} interior");
    assert_eq!(wrong_interior, 0, "{wrong} pixels differ, {wrong_interior} interior");
    // Each witness loses pixels of the ball alone (its self-shadow) and of the plane.
    let ball = |i: usize| truth.label[i] > 1;
    for (bit, what) in [(1, "the projector"), (2, "the lamp")] {
        let lost =
            |on_ball: bool| (0..truth.label.len()).filter(|&i| truth.witness[i] == bit && ball(i) == on_ball).count();
        let (on_ball, on_plane) = (lost(true), lost(false));
        assert!(
            on_ball > 50 && on_plane > 50,
            "{what} alone loses {on_ball} pixels of the ball, {on_plane} of the plane"
        );
    }
}

/// A box cut into aspect-10⁴ slivers, its top toward the camera, under a projector 40° to
/// the side and two lamps 70° from the camera's axis (so each sees side faces beside the top),
/// in mode `depth`: labels and witness bits against the box's geometry (a slab test, no
/// renderer: tests/common/sliver_box.rs), where a witness sees a point exactly when the point's
/// face turns toward it (the box alone, every point in the projector's view). No interior
/// pixel is wrong. Before the walk asked for a point to lie within a triangle's box as well as
/// within its edges' lines, a projector's sliver seen beside the top shadowed a point of it
/// (occluder_walk.glsl, `within_box`: rays from a centre).
#[test]
fn slivers_of_aspect_ten_thousand_are_seen_by_each_witness_as_their_faces_turn() {
    use common::sliver_box::{box_face_hit, sliver_box};
    let k = Intrinsics { width: 320, height: 240, fx: 250.0, fy: 250.0, cx: 160.0, cy: 120.0 };
    let projector_pose = DMat4::from_translation(DVec3::new(4.0, 0.3, 0.0)) * DMat4::from_rotation_y(-0.7);
    let lamps = [DVec3::new(-0.94, 0.05, -0.34).normalize(), DVec3::new(0.05, 0.94, -0.34).normalize()];
    let mut witnesses = vec![Witness {
        name: "projector".into(),
        geometry: WitnessGeometry::Pinhole {
            pose: projector_pose,
            intrinsics: Intrinsics { width: 800, height: 600, cx: 400.0, cy: 300.0, ..k },
        },
    }];
    for (i, &lamp) in lamps.iter().enumerate() {
        let geometry = WitnessGeometry::Directional(Direction::Vector(lamp));
        witnesses.push(Witness { name: format!("lamp {i}"), geometry });
    }
    let sensor =
        Sensor { reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY }), witnesses };
    let (mesh, normals) = sliver_box(10_000);
    let pose = facing_camera(DVec3::new(0.0, 0.0, 4.0)) * DMat4::from_rotation_z(0.05);
    let mut rig = scene(sensor, ShadowMode::Depth, &[]);
    rig.objects.push(rangesynth::scene::SceneObject {
        model_ref: "sliver box".into(),
        mesh: std::sync::Arc::new(mesh),
        pose,
        reflectivity: None,
    });
    let out = render(&rig);
    assert_eq!(out.raster, Some(common::gpu_raster()), "drawn on the GPU");
    let projector_centre = projector_pose.transform_point3(DVec3::ZERO);
    let (w, h) = (k.width as usize, k.height as usize);
    // (label, witness bits) at each pixel, by the geometry.
    let expected: Vec<(u32, u32)> = (0..w * h)
        .map(|i| {
            let ray = DVec3::new(((i % w) as f64 - k.cx) / k.fx, ((i / w) as f64 - k.cy) / k.fy, 1.0);
            let Some((face, t)) = box_face_hit(pose, DVec3::ZERO, ray) else { return (0, 0) };
            let (p, n) = (t * ray, pose.transform_vector3(normals[face]));
            let towards = [(projector_centre - p).normalize(), lamps[0], lamps[1]];
            let bits = (0..3).filter(|&b| n.dot(towards[b]) <= 0.0).fold(0, |bits, b| bits | 1 << b);
            (face as u32 + 1, bits)
        })
        .collect();
    let interior = |i: usize| {
        let (c, r) = ((i % w) as i64, (i / w) as i64);
        (-1..=1).all(|dr| {
            (-1..=1).all(|dc| {
                let (c, r) = (c + dc, r + dr);
                c < 0 || r < 0 || c >= w as i64 || r >= h as i64 || expected[r as usize * w + c as usize] == expected[i]
            })
        })
    };
    let wrong: Vec<usize> = (0..w * h).filter(|&i| (out.label_unshadowed[i], out.witness[i]) != expected[i]).collect();
    let wrong_interior = wrong.iter().filter(|&&i| interior(i)).count();
    eprintln!("{} pixels differ from the box's geometry, {wrong_interior} interior", wrong.len());
    assert_eq!(wrong_interior, 0, "{} pixels differ, {wrong_interior} interior", wrong.len());
    // The camera sees the top, which every witness lights; the false shadows fell on it.
    assert!(expected.iter().filter(|&&(label, _)| label == 1).count() > 5_000, "the top fills much of the view");
}

/// Mode `depth` against the brute-force reference on random rigs: a tilted table, one to four
/// models (boxes, steps, cylinders, balls of 2,208 and 25,280 triangles) of random size and
/// pose, one to three witnesses (pinhole ones of random pose and intrinsics, some behind the
/// camera, directional ones of random direction), in metres or millimetres. Labels and witness
/// bits have no interior pixel wrong, depths agree to 10⁻⁵ of Z (f32 depths on faces seen
/// nearly edge-on err by about 10⁻⁶). The seeds are those where walks over the balls' poles
/// and along their silhouettes once gave up and guessed a shadow.
#[test]
fn depth_mode_under_random_rigs_matches_the_brute_force_reference() {
    use rand::{Rng, SeedableRng};
    let models = ["builtin:box", "builtin:sphere:48", "builtin:cylinder:32", "builtin:step", "builtin:sphere:160"];
    for seed in [19u64, 20, 23] {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let unit = if seed % 2 == 0 { 1.0 } else { 1000.0 };
        let f = rng.gen_range(100.0..300.0);
        let k = Intrinsics { width: 128, height: 96, fx: f, fy: f * rng.gen_range(0.9..1.1), cx: 63.5, cy: 47.5 };
        let witnesses = (0..rng.gen_range(1..4))
            .map(|j| {
                let geometry = if rng.gen_bool(0.6) {
                    let centre =
                        DVec3::new(rng.gen_range(-0.4..0.4), rng.gen_range(-0.3..0.3), rng.gen_range(-0.2..0.3));
                    let turn = DMat4::from_rotation_y(rng.gen_range(-0.4..0.4))
                        * DMat4::from_rotation_x(rng.gen_range(-0.3..0.3));
                    let (width, height) = (rng.gen_range(100..300), rng.gen_range(80..250));
                    let (fx, fy) = (rng.gen_range(80.0..300.0), rng.gen_range(80.0..300.0));
                    let (cx, cy) = (f64::from(width) / 2.0 - 0.5, f64::from(height) / 2.0 - 0.5);
                    let intrinsics = Intrinsics { width, height, fx, fy, cx, cy };
                    WitnessGeometry::Pinhole { pose: DMat4::from_translation(centre * unit) * turn, intrinsics }
                } else {
                    let toward = DVec3::new(rng.gen_range(-0.9..0.9), rng.gen_range(-0.9..0.9), -1.0);
                    WitnessGeometry::Directional(Direction::Vector(toward.normalize()))
                };
                Witness { name: format!("witness {j}"), geometry }
            })
            .collect();
        let reference = View::Pinhole(Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY });
        let depth = rng.gen_range(0.6..1.5);
        let table = DMat4::from_translation(DVec3::new(0.0, 0.0, depth + 0.3) * unit)
            * DMat4::from_rotation_x(std::f64::consts::PI + rng.gen_range(-0.5..0.5));
        let mut objects = vec![("builtin:plane:4", table, 3.0 * unit)];
        for _ in 0..rng.gen_range(1..5) {
            let model = models[rng.gen_range(0..models.len())];
            let at = DVec3::new(rng.gen_range(-0.3..0.3), rng.gen_range(-0.25..0.25), depth + rng.gen_range(-0.2..0.2));
            let pose = DMat4::from_translation(at * unit)
                * DMat4::from_rotation_x(rng.gen_range(0.0..6.3))
                * DMat4::from_rotation_z(rng.gen_range(0.0..6.3));
            objects.push((model, pose, rng.gen_range(0.08..0.3) * unit));
        }
        let posed: Vec<(&str, DMat4)> = objects.iter().map(|&(model, pose, _)| (model, pose)).collect();
        let mut rig = scene(Sensor { reference, witnesses }, ShadowMode::Depth, &posed);
        for (object, &(_, _, scale)) in rig.objects.iter_mut().zip(&objects) {
            object.mesh = std::sync::Arc::new((*object.mesh).clone().scaled(scale, &Default::default()).unwrap());
        }
        let out = render(&rig);
        let truth = rig_reference(&rig);
        let (wrong, wrong_interior) = differences(&out, &truth, true, 1e-5);
        let lost = truth.witness.iter().filter(|&&bits| bits != 0).count();
        eprintln!("seed {seed}: {wrong} pixels differ from the reference, {wrong_interior} interior; {lost} lost");
        assert_eq!(wrong_interior, 0, "seed {seed}: {wrong} pixels differ, {wrong_interior} interior");
        assert!(lost > 100, "seed {seed}: the witnesses lose pixels: {lost}");
    }
}

/// The GPU draws a pinhole view between its `near` and `far` (depth along the optical axis)
/// as the brute-force reference casts it: a plane tilted 57° to the axis, crossing depths
/// from about 1.6 to 4.4 over the image, and a ball on it which the near plane cuts open, so
/// that its inside is seen; with near = 2.5 and far = 3.5 a band of rows is kept. No interior
/// pixel differs in label or depth (to 4e-7 of it). In mode `label`, a projector beside the
/// camera and above it: the plane's witness bits are the reference's too; the ball's inside is not tested,
/// as the label test cannot see a surface shadow itself (the projector sees the ball's outside,
/// of the same label, in front of its inside).
#[test]
fn a_pinhole_view_draws_what_lies_between_its_near_and_far() {
    let k = Intrinsics { width: 64, height: 48, fx: 40.0, fy: 40.0, cx: 31.5, cy: 23.5 };
    let witnesses = vec![projector("projector", DVec3::new(0.6, 0.6, 0.0), Intrinsics { width: 96, cx: 47.5, ..k })];
    let sensor = Sensor { reference: View::Pinhole(Pinhole { intrinsics: k, near: 2.5, far: 3.5 }), witnesses };
    let tilted = facing_camera(DVec3::new(0.0, 0.0, 3.0)) * DMat4::from_rotation_x(1.0);
    for mode in [ShadowMode::None, ShadowMode::Label] {
        let rig = scene(sensor.clone(), mode, &[("builtin:plane:20", tilted), ("builtin:sphere:24", tilted)]);
        let out = render(&rig);
        let truth = rig_reference(&rig);
        // Labels and depths alone here: the witness bits are checked below.
        let mut unbitten = out.clone();
        unbitten.witness.fill(0);
        let (wrong, interior) = differences(&unbitten, &truth, false, 4e-7);
        let drawn = truth.label.iter().filter(|&&l| l != 0).count();
        assert!(drawn > 500 && drawn < 64 * 40, "{mode:?}: the band is cut by near and far: {drawn} pixels");
        assert!(truth.label.iter().filter(|&&l| l == 2).count() > 100, "the ball's inside is seen");
        assert_eq!(interior, 0, "{mode:?}: {wrong} pixels differ, {interior} interior");
        if mode == ShadowMode::Label {
            let plane = |i: usize| truth.label[i] == 1;
            let lost = (0..truth.label.len()).filter(|&i| plane(i) && truth.witness[i] != 0).count();
            assert!(lost > 10, "the ball shadows the plane: {lost} pixels");
            let bits_wrong: Vec<usize> = (0..truth.label.len())
                .filter(|&i| plane(i) && out.witness[i] != truth.witness[i])
                .filter(|&i| {
                    let (c, r) = (i % 64, i / 64);
                    let near = |j: usize| truth.label[j] != 1 || truth.witness[j] != truth.witness[i];
                    !(c == 0
                        || r == 0
                        || c == 63
                        || r == 47
                        || near(i - 1)
                        || near(i + 1)
                        || near(i - 64)
                        || near(i + 64))
                })
                .collect();
            assert!(bits_wrong.is_empty(), "interior plane pixels with other witness bits: {bits_wrong:?}");
        }
    }
}

/// Coincident faces of two objects go to the lower label in a pinhole view too: a plane, and
/// the same plane turned about its normal (other triangles, other roundings), drawn in either
/// order, show label 1 at every pixel, as the reference's tie rule has it.
#[test]
fn coincident_faces_in_a_pinhole_view_go_to_the_lower_label() {
    let plane = facing_camera(DVec3::new(0.1, -0.2, 5.0));
    let turned = plane * DMat4::from_rotation_z(0.3);
    for objects in [[plane, turned], [turned, plane]] {
        let rig = scene(
            Sensor { reference: reference(), witnesses: vec![] },
            ShadowMode::None,
            &[("builtin:plane:20", objects[0]), ("builtin:plane:20", objects[1])],
        );
        let out = render(&rig);
        let truth = rig_reference(&rig);
        // (f64 rays that meet a plane on its triangles' shared diagonal can miss it.)
        let first = truth.label.iter().filter(|&&l| l == 1).count();
        assert!(first > truth.label.len() * 999 / 1000, "the reference sees the first plane: {first} pixels");
        let higher = out.label_unshadowed.iter().filter(|&&l| l != 1).count();
        assert_eq!(higher, 0, "{higher} pixels show another label than the lower");
    }
}

/// Every bad rig is refused by a message that names the key.
#[test]
fn bad_rigs_are_refused_with_the_key_named() {
    let pinhole = "[sensor]\nkind = \"pinhole\"\nwidth = 64\nheight = 48\nfx = 50\nfy = 50\ncx = 31.5\ncy = 23.5\n";
    let witness = |body: &str| format!("{pinhole}[[sensor.witness]]\nname = \"projector\"\n{body}");
    let camera = "width = 64\nheight = 48\nfx = 50\nfy = 50\ncx = 31.5\ncy = 23.5\n";
    let pose = |rows: &str| format!("kind = \"pinhole\"\npose = {rows}\n{camera}");
    let object = "[[object]]\nmodel = \"builtin:box\"\n";
    let cases = [
        (pinhole.replace("fx = 50", "fx = 0"), "[sensor]: fx = 0"),
        (pinhole.replace("fy = 50", "fy = -2"), "[sensor]: fy = -2"),
        (pinhole.replace("cx = 31.5", "cx = nan"), "[sensor]: cx = NaN"),
        (format!("{pinhole}far = 0.5\nnear = 1\n"), "far = 0.5"),
        (
            witness(&pose("[[1, 0.1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]")),
            "[[sensor.witness]] 1 (\"projector\"): pose",
        ),
        (witness(&pose("[[1, 0, 0, inf], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]")), "non-finite"),
        (witness(&pose("[[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, 1]]")), "cannot contain any point"),
        (
            witness(&pose("[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]").replace("fx = 50", "fx = 0")),
            "[[sensor.witness]] 1 (\"projector\"): fx = 0",
        ),
        (
            witness("kind = \"directional\"\ndirection = [0, 0, 2]\n"),
            "direction = [0, 0, 2] must be a finite unit vector",
        ),
        (witness("kind = \"directional\"\n"), "kind = \"directional\" needs direction"),
        (
            format!(
                "{pinhole}{}",
                (0..33)
                    .map(|i| format!(
                        "[[sensor.witness]]\nname = \"l{i}\"\nkind = \"directional\"\ndirection = [0, 0, -1]\n"
                    ))
                    .collect::<String>()
            ),
            "33 witnesses",
        ),
    ];
    for (text, expected) in cases {
        let e = Scene::from_toml(&format!("{text}{object}"), std::path::Path::new("."), &Default::default())
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains(expected), "expected {expected:?}:\n{text}\n→ {e}");
    }
}

/// Mode `label` reads the witnesses' label images at a pinhole reference view's points: an
/// orthographic reference view other than the scanner's is refused by name.
#[test]
fn what_the_label_test_cannot_read_is_refused_by_name() {
    let light =
        Witness { name: "light".into(), geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::NEG_Z)) };
    let mut rig = box_on_plane(vec![]);
    rig.shadow.mode = ShadowMode::Label;
    let view = rangesynth::sensor::Orthographic { width: 64, height: 48, pitch: [0.05, 0.05], origin: [-1.575, 1.175] };
    rig.sensor = Sensor { reference: View::Orthographic(view), witnesses: vec![light] };
    let e = common::renderer().render(&rig).err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("[shadow] mode = \"label\"") && e.contains("orthographic reference view"), "{e}");
}

/// Every example rig in rigs/ renders from the command line, and its range image records the
/// whole rig in its header and one bit per witness in its `witness` channel, set exactly where
/// `reason` says shadow.
#[test]
fn every_example_rig_renders_and_records_its_witnesses() {
    let rigs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs");
    let mut names: Vec<_> = std::fs::read_dir(&rigs).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    assert_eq!(names.len(), 5, "{names:?}");
    for rig in names {
        let name = rig.file_stem().unwrap().to_string_lossy().into_owned();
        let out_dir = common::cli::fresh_dir("rigs", &name).join("out");
        let out =
            common::cli::rangesynth_command().arg("render").arg(&rig).arg("--out").arg(&out_dir).output().unwrap();
        assert!(out.status.success(), "{name}: {}", common::cli::text(&out.stderr));
        let image = rangesynth::io::read_range_image(&out_dir.join("range.exr"), &Default::default()).unwrap();
        let scene = Scene::from_file(&rig, &Default::default()).unwrap();
        assert_eq!(image.sensor.as_ref(), Some(&scene.sensor), "{name}");
        let (witness, reason) = (image.witness.unwrap(), image.reason.unwrap());
        let shadow = Reason::Shadow.code();
        assert!(witness.iter().zip(&reason).all(|(&bits, &r)| (bits != 0) == (r == shadow)), "{name}");
        assert!(witness.iter().any(|&bits| bits != 0), "{name}: some pixel is lost to a witness");
        let all = (1u64 << scene.sensor.witnesses.len()) - 1;
        assert!(witness.iter().all(|&bits| u64::from(bits) & !all == 0), "{name}: bits of its witnesses only");
    }
}

/// A pinhole range image holds X, Y, Z of the point on each valid pixel's ray: on the plane
/// at depth 5 beside the box, pixel (c, 240) holds (5·(c − 320)/500, 0, 5).
#[test]
fn a_pinhole_range_image_holds_the_point_on_each_pixels_ray() {
    let rig = box_on_plane(vec![projector("projector", DVec3::new(PROJECTOR_BASELINE, 0.0, 0.0), projector_image())]);
    let out = render(&rig);
    let image = rangesynth::io::RangeImage::from(&out);
    for col in [0u32, 100, 300, 500, 639] {
        let i = (240 * 640 + col) as usize;
        let x = 5.0 * (f64::from(col) - 320.0) / 500.0;
        let close = |a: f32, b: f64| (f64::from(a) - b).abs() < 1e-6;
        assert!(close(image.x[i], x) && close(image.y[i], 0.0) && close(image.z[i], 5.0), "column {col}");
    }
    // Row 0, column 0: Y = 5·(0 − 240)/500 = −2.4.
    assert!((f64::from(image.y[0]) + 2.4).abs() < 1e-6, "{}", image.y[0]);
    assert!(image.x[240 * 640 + 330].is_nan(), "a shadowed pixel has no point");
}

/// A fronto-parallel plane filling the image of a Kinect-like camera (f = 580 px, 64×48) at
/// depth `z`, with `effects`.
fn plane_at(z: f64, effects: &str) -> Scene {
    let k = Intrinsics { width: 64, height: 48, fx: 580.0, fy: 580.0, cx: 31.5, cy: 23.5 };
    let sensor = Sensor {
        reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY }),
        witnesses: vec![],
    };
    let mut rig = scene(sensor, ShadowMode::None, &[("builtin:plane:20", facing_camera(DVec3::new(0.0, 0.0, z)))]);
    rig.effects = toml::from_str(effects).unwrap();
    rig
}

/// A Kinect v1's disparity (f = 580 px, b = 7.5 cm, 1/8 pixel): at depth Z the disparity
/// f·b/Z is rounded to eighths, so Z = 1.9 is measured as 43.5/(183/8) = 1.90164 m (183 = the
/// nearest integer to 8·43.5/1.9 = 183.16), Z = 1 as 43.5/43.5 = 1 and Z = 3.7 as
/// 43.5/(94/8) = 3.70213; with a search of 15 to 40 pixels the nearest (43.5 px) and the
/// farthest (11.76 px) are lost as out of range.
#[test]
fn disparity_measures_depth_in_eighths_of_a_pixel_within_its_search() {
    let kinect = "[disparity]\nbaseline = 0.075\nfocal_px = 580\nsubpixel = 8\n";
    for (z, measured) in [(1.0, 1.0), (1.9, 43.5 / (183.0 / 8.0)), (3.7, 43.5 / (94.0 / 8.0))] {
        let out = render(&plane_at(z, kinect));
        assert!(out.reason.iter().all(|&r| r == Reason::Valid), "Z = {z}");
        for &zi in &out.z {
            assert!((f64::from(zi) - measured).abs() < 1e-5 * measured, "Z = {z}: {zi}, expected {measured}");
        }
    }
    let searched = format!("{kinect}min_px = 15\nmax_px = 40\n");
    for (z, kept) in [(1.0, false), (1.9, true), (3.7, false)] {
        let out = render(&plane_at(z, &searched));
        let expected = if kept { Reason::Valid } else { Reason::OutOfRange };
        assert!(out.reason.iter().all(|&r| r == expected), "Z = {z}: {:?}", out.reason[0]);
    }
}

/// Noise on the disparity: σ_z ≈ Z²·σ_d/(f·b) = 4·0.1/43.5 = 0.0092 at Z = 2 (1/256 pixel
/// steps, 0.36 mm there, leave it alone), measured over 3072 pixels to within 8%; the same
/// seed draws the same image.
#[test]
fn disparity_noise_grows_with_the_square_of_depth() {
    let noisy = "[disparity]\nbaseline = 0.075\nfocal_px = 580\nsubpixel = 256\nnoise_px = 0.1\nseed = 7\n";
    let stats = |z: f64| {
        let out = render(&plane_at(z, noisy));
        let n = out.z.len() as f64;
        let mean = out.z.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let var = out.z.iter().map(|&v| (f64::from(v) - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, var.sqrt(), out.z)
    };
    for z in [1.0, 2.0] {
        let (mean, sigma, _) = stats(z);
        let expected = z * z * 0.1 / 43.5;
        assert!((sigma / expected - 1.0).abs() < 0.08, "Z = {z}: σ = {sigma}, expected {expected}");
        assert!((mean - z).abs() < 3.0 * expected / (3072f64).sqrt() + 1e-4, "Z = {z}: mean {mean}");
    }
    assert_eq!(stats(2.0).2, stats(2.0).2);
}

/// The box's left face runs along the camera's rays' plane (its normal (−1, 0, 0) has no z):
/// the cast image gives its pixels no NaN gradient (−n.y/n.z would be 0/0), and they keep a
/// finite z through the noise effect.
#[test]
fn a_face_along_the_rays_keeps_a_finite_depth_through_the_effects() {
    let cast = rangesynth::exact::render_scene_exact(&box_on_plane(vec![])).unwrap();
    let nan = cast.gradient.iter().flatten().filter(|g| g.is_nan()).count();
    assert_eq!(nan, 0, "NaN gradients");
    let mut rig = box_on_plane(vec![]);
    rig.shadow.mode = ShadowMode::None;
    rig.effects = toml::from_str("[noise]\nsigma = 0.001\n").unwrap();
    let out = render(&rig);
    let side = (341..=344).map(|col| 240 * 640 + col);
    for i in side {
        assert!(out.reason[i] == Reason::Valid && out.label[i] != 1 && out.z[i].is_finite(), "pixel {i}: {}", out.z[i]);
    }
    assert!(out.z.iter().zip(&out.label).all(|(z, &l)| l == 0 || z.is_finite()));
}

/// Effects under a rig: the working volume is in depth along the optical axis; disparity is
/// refused on an orthographic sensor, by name.
#[test]
fn effects_under_a_rig_measure_depth_and_refuse_disparity_without_a_pinhole_view() {
    let near = render(&plane_at(1.9, "[range]\nmax_z = 1.8\n"));
    assert!(near.reason.iter().all(|&r| r == Reason::OutOfRange));
    let kept = render(&plane_at(1.9, "[range]\nmax_z = 2.0\n"));
    assert!(kept.reason.iter().all(|&r| r == Reason::Valid));
    let refused = |rig: &Scene| common::renderer().render(rig).err().map(|e| e.to_string()).unwrap_or_default();
    let mut scanner =
        scene(common::sensor(8, 8, 0.1, [0.0, 0.0], 30.0), ShadowMode::Label, &[("builtin:box", DMat4::IDENTITY)]);
    scanner.effects = toml::from_str("[disparity]\nbaseline = 0.075\nfocal_px = 580\nsubpixel = 8\n").unwrap();
    let e = refused(&scanner);
    assert!(e.contains("effects.disparity") && e.contains("orthographic"), "{e}");
}

/// `render --depth-png SCALE` writes BOP's depth image for a pinhole sensor: the plane at
/// depth 1.9 (metres) at a scale of 0.1 mm is 19000 everywhere it is valid, 0 in the
/// projector's shadow; an orthographic sensor, a bad scale and a depth beyond 65535 × the
/// scale are refused before anything is written.
#[test]
fn render_writes_a_bop_depth_png_for_a_pinhole_sensor() {
    let d = common::cli::fresh_dir("rigs", "depth_png");
    let rig = "[sensor]\nkind = \"pinhole\"\nwidth = 64\nheight = 48\nfx = 50\nfy = 50\ncx = 31.5\ncy = 23.5\n\
               [[sensor.witness]]\nname = \"projector\"\nkind = \"pinhole\"\n\
               pose = [[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n\
               width = 64\nheight = 48\nfx = 50\nfy = 50\ncx = 31.5\ncy = 23.5\n[shadow]\nmode = \"exact\"\n\
               [[object]]\nmodel = \"builtin:plane:20\"\n\
               pose = [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 1.9], [0, 0, 0, 1]]\n\
               [[object]]\nmodel = \"builtin:box\"\nscale = 0.2\n\
               pose = [[1, 0, 0, 0], [0, -1, 0, 0], [0, 0, -1, 1.9], [0, 0, 0, 1]]\n";
    std::fs::write(d.join("rig.toml"), rig).unwrap();
    let render = |scene: &str, scale: &str, out: &str| {
        common::cli::rangesynth_command()
            .args(["render", scene, "--out", out, "--depth-png", scale])
            .current_dir(&d)
            .output()
            .unwrap()
    };
    let out = render("rig.toml", "0.0001", "out");
    assert!(out.status.success(), "{}", common::cli::text(&out.stderr));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(d.join("out/depth.png")).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buffer = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buffer).unwrap();
    assert_eq!((info.width, info.height, info.bit_depth), (64, 48, png::BitDepth::Sixteen));
    let values: Vec<u16> = buffer.chunks(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
    let image = rangesynth::io::read_range_image(&d.join("out/range.exr"), &Default::default()).unwrap();
    let plane = image.label.iter().position(|&l| l == 1).unwrap();
    assert_eq!(values[plane], 19000);
    for (i, (&value, &label)) in values.iter().zip(&image.label).enumerate() {
        let expected = if label == 0 { 0 } else { (f64::from(image.z[i]) / 1e-4).round() as u16 };
        assert_eq!(value, expected, "pixel {i}");
    }
    assert!(values.contains(&0) && image.reason.unwrap().contains(&Reason::Shadow.code()));
    std::fs::write(d.join("scanner.toml"), "[sensor]\nkind = \"orthographic\"\nwidth = 8\nheight = 8\npitch = [0.1, 0.1]\norigin = [0, 0]\ntheta_deg = 0\n").unwrap();
    for (scene, scale, expected) in
        [("scanner.toml", "0.001", "orthographic"), ("rig.toml", "0.00001", "outside a depth PNG's 1 to 65535")]
    {
        let out = render(scene, scale, "refused");
        common::cli::refused(&out, scene, expected);
        assert!(!d.join("refused").exists(), "{scene} {scale}: nothing written");
    }
    // A scale that is no positive number is a usage error, as any option's bad value is.
    for scale in ["0", "NaN", "inf", "deep"] {
        let out = render("rig.toml", scale, "refused");
        let stderr = common::cli::text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{scale}: {stderr}");
        assert!(stderr.contains("--depth-png") && !stderr.contains("panicked"), "{scale}: {stderr}");
        assert!(!d.join("refused").exists(), "{scale}: nothing written");
    }
}

/// The disparity's depth levels: on a plane tilted 30° across the depths around 1, 2 and 4 m,
/// every measured depth is f·b·s/k for an integer k, and the levels next to the depth are
/// apart by f·b·s/(k(k + 1)) ≈ z²/(f·b·s): 2.9 mm at 1 m, 11.5 mm at 2 m, 46 mm at 4 m for a
/// Kinect v1 (f = 580 px, b = 7.5 cm, s = 8). Left out, f and b come from the rig: its fx and
/// the distance to its first witness, here the projector 7.5 cm to the camera's right.
#[test]
fn disparity_steps_grow_with_the_square_of_depth_and_take_the_rigs_geometry() {
    let fbs = 580.0 * 0.075 * 8.0;
    let image = Intrinsics { width: 64, height: 48, fx: 580.0, fy: 580.0, cx: 31.5, cy: 23.5 };
    for (z, step) in [(1.0, 0.0029), (2.0, 0.0115), (4.0, 0.046)] {
        let mut rig = plane_at(z, "[disparity]\nsubpixel = 8\n");
        rig.sensor.witnesses = vec![projector("projector", DVec3::new(0.075, 0.0, 0.0), image)];
        rig.objects[0].pose = facing_camera(DVec3::new(0.0, 0.0, z)) * DMat4::from_rotation_x(30f64.to_radians());
        let out = render(&rig);
        let mut levels: Vec<f64> =
            out.z.iter().zip(&out.label).filter(|p| *p.1 != 0).map(|p| f64::from(*p.0)).collect();
        levels.sort_by(f64::total_cmp);
        levels.dedup();
        assert!(levels.len() > 3, "Z = {z}: {} levels", levels.len());
        for &level in &levels {
            let k = (fbs / level).round();
            assert!((level - fbs / k).abs() < 1e-5 * level, "Z = {z}: {level} is no f·b·s/k");
        }
        let above = levels.iter().position(|&l| l >= z).unwrap();
        let measured = levels[above] - levels[above - 1];
        assert!((measured / step - 1.0).abs() < 0.03, "Z = {z}: step {measured}, expected {step}");
    }
    let e = common::renderer().render(&plane_at(2.0, "[disparity]\nsubpixel = 8\n")).err().unwrap().to_string();
    assert!(e.contains("effects.disparity.baseline is left out"), "{e}");
}

/// An orthographic reference view with witnesses other than the scanner's camera: a pinhole
/// projector 3 above the table, looking down, and a distant light from (0.6, 0, 0.8); a box
/// and a cylinder on a plane. Labels, z and witness bits in mode `exact` against the
/// brute-force reference, no interior pixel wrong.
#[test]
fn an_orthographic_view_with_pinhole_and_directional_witnesses_matches_the_reference() {
    let view = rangesynth::sensor::Orthographic { width: 96, height: 64, pitch: [0.05, 0.05], origin: [-2.375, 1.575] };
    let looking_down =
        DMat4::from_translation(DVec3::new(1.0, 0.3, 3.0)) * DMat4::from_rotation_x(std::f64::consts::PI);
    let witnesses = vec![
        Witness {
            name: "projector".into(),
            geometry: WitnessGeometry::Pinhole {
                pose: looking_down,
                intrinsics: Intrinsics { width: 200, height: 200, fx: 60.0, fy: 60.0, cx: 99.5, cy: 99.5 },
            },
        },
        Witness {
            name: "light".into(),
            geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::new(0.6, 0.0, 0.8))),
        },
    ];
    let sensor = Sensor { reference: View::Orthographic(view), witnesses };
    let rig = scene(
        sensor,
        ShadowMode::Exact,
        &[
            ("builtin:plane:6", DMat4::IDENTITY),
            ("builtin:box", DMat4::from_translation(DVec3::new(-0.8, 0.2, 0.0)) * DMat4::from_rotation_z(0.5)),
            ("builtin:cylinder:24", DMat4::from_translation(DVec3::new(0.9, -0.4, 0.0))),
        ],
    );
    let out = render(&rig);
    let truth = rig_reference(&rig);
    let (wrong, interior_wrong) = differences(&out, &truth, true, 1e-6);
    assert_eq!(interior_wrong, 0, "{wrong} pixels differ, {interior_wrong} interior");
    let lost_by = |bit: u32| truth.witness.iter().filter(|&&b| b & bit != 0).count();
    assert!(lost_by(1) > 50 && lost_by(2) > 50, "both witnesses lose pixels: {} and {}", lost_by(1), lost_by(2));
}

/// A box turned to show three faces to the camera, 4 to 5 units deep, under the camera and
/// the projector at its baseline.
fn turned_box_pose() -> DMat4 {
    facing_camera(DVec3::new(0.3, -0.1, 5.0)) * DMat4::from_rotation_y(0.5) * DMat4::from_rotation_x(0.4)
}

fn projector_rig() -> Sensor {
    let witnesses = vec![projector("projector", DVec3::new(PROJECTOR_BASELINE, 0.0, 0.0), projector_image())];
    Sensor { reference: reference(), witnesses }
}

fn rig_hypothesis(id: &str, model: &str, pose: DMat4, bindings: &[(u32, u32)]) -> Hypothesis {
    let model = common::VERIFIER.model(model, std::path::Path::new(".")).unwrap();
    Hypothesis { id: id.into(), model, pose, bindings: bindings.to_vec() }
}

fn rig_settings(mode: ShadowMode) -> VerifySettings {
    VerifySettings {
        sensor: projector_rig(),
        shadow: ShadowSettings::of(mode),
        effects: Default::default(),
        tolerance: 0.01,
        compare_shadow: true,
        chunk_size: 1024,
    }
}

/// `verify` under a pinhole camera and projector: against the sensed image of the turned
/// box, the true pose scores exactly 1 (no effects: the same image), the pose moved by two
/// pixels' width at the box's depth (2 · 4.5 / 500) scores less, and every count and score of
/// every hypothesis equals the independent CPU scorer's on the rendered images (areas from
/// the pixels' points along their rays, in units of a pixel at the farthest sensed depth;
/// a hypothesis nearer than the sensed surface counts in N1−), in shadow modes exact, depth,
/// none and label (the last two drawn on the GPU; label also with a lamp above the camera, a
/// directional witness whose image each hypothesis plans over its own model), shadowed and
/// unshadowed.
#[test]
fn verify_under_a_pinhole_rig_scores_the_true_pose_one_and_matches_the_cpu_scorer() {
    let bindings: Vec<(u32, u32)> = (1..=6).map(|l| (l, l)).collect();
    let mut with_lamp = projector_rig();
    let lamp = DVec3::new(0.1, -0.7, -0.7).normalize();
    with_lamp
        .witnesses
        .push(Witness { name: "lamp".into(), geometry: WitnessGeometry::Directional(Direction::Vector(lamp)) });
    let modes =
        [ShadowMode::Exact, ShadowMode::Depth, ShadowMode::None, ShadowMode::Label].map(|m| (m, projector_rig()));
    for (mode, rig) in modes.into_iter().chain([(ShadowMode::Label, with_lamp)]) {
        let sensed_scene = scene(rig.clone(), mode, &[("builtin:box", turned_box_pose())]);
        let image = RangeImage::from(&render(&sensed_scene));
        let sensed = SensedImage::new(&image, &rig).expect("a pinhole sensed image");
        let lamp_alone = image.witness.iter().flatten().filter(|&&bits| bits == 2).count();
        assert!(rig.witnesses.len() == 1 || lamp_alone > 20, "the lamp alone loses pixels: {lamp_alone}");
        let moved = DMat4::from_translation(DVec3::new(2.0 * 4.5 / 500.0, 0.0, 0.0)) * turned_box_pose();
        let nearer = DMat4::from_translation(DVec3::new(0.0, 0.0, -0.05)) * turned_box_pose();
        let hypotheses = [
            rig_hypothesis("true", "builtin:box", turned_box_pose(), &bindings),
            rig_hypothesis("moved", "builtin:box", moved, &bindings),
            rig_hypothesis("nearer", "builtin:box", nearer, &bindings),
            rig_hypothesis("sphere", "builtin:sphere:24", facing_camera(DVec3::new(0.6, 0.2, 4.2)), &[(1, 1)]),
            // Over the image's bottom-right corner: the score pass's last column and row.
            rig_hypothesis("corner", "builtin:box", facing_camera(DVec3::new(3.2, 2.4, 5.0)), &[(1, 1)]),
            // Around the camera's centre, its bottom face through it: no footprint to cut, and
            // every pixel sees the box's inside at a depth Z > 0 (never the face at Z = 0).
            rig_hypothesis("around", "builtin:box", DMat4::IDENTITY, &[(1, 1)]),
            // Behind the camera: nothing in view.
            rig_hypothesis("behind", "builtin:box", DMat4::from_translation(DVec3::new(0.0, 0.0, -3.0)), &[(1, 1)]),
        ];
        let settings = VerifySettings { sensor: rig.clone(), ..rig_settings(mode) };
        let results = common::VERIFIER.verify(&sensed, &settings, &hypotheses, &mut |_| {}).expect("verifies");
        common::assert_no_validation_messages();
        for (h, v) in common::paired(&hypotheses, &results) {
            let name = format!("{} ({mode:?}, {} witnesses)", h.id, rig.witnesses.len());
            let synthetic = render(&scene(rig.clone(), mode, &[(h.model.mesh.name.as_str(), h.pose)]));
            let shadowed = Images::of(&image, &synthetic);
            let unshadowed = Images { synthetic_label: &synthetic.label_unshadowed, ..Images::of(&image, &synthetic) };
            let (unshadowed_counts, unshadowed_scores) = v.unshadowed.as_ref().expect("compare_shadow");
            for (which, images, counts, scores) in [
                ("", &shadowed, &v.counts, &v.scores),
                (" unshadowed", &unshadowed, unshadowed_counts, unshadowed_scores),
            ] {
                let cpu = cpu_counts(images, settings.tolerance as f32);
                assert_eq!(as_cpu(counts, &sensed, sensed.valid), cpu, "{name}{which}: counts");
                let expected = cpu_scores(&cpu, &h.bindings);
                let s = scores;
                for (k, (ours, cpu)) in [s.s1, s.s2, s.s3, s.s4, s.s5, s.s6, s.s].iter().zip(expected).enumerate() {
                    let scale = ours.abs().max(cpu.abs()).max(f64::MIN_POSITIVE);
                    assert!((ours - cpu).abs() <= 1e-12 * scale, "{name}{which} score {k}: {ours} vs CPU {cpu}");
                }
            }
            // Modes `none`, `label` and `depth` are drawn on the GPU, `exact` cast on the CPU;
            // a hypothesis out of view is drawn by neither.
            let drawn = mode != ShadowMode::Exact && h.id != "behind";
            assert_eq!(v.raster, drawn.then_some(common::gpu_raster()), "{name}");
        }
        let score = |id: &str| results.iter().find(|v| v.id == id).map(|v| v.scores.s).unwrap();
        assert_eq!(score("true"), 1.0, "{mode:?}");
        assert!(score("moved") < 0.95, "{mode:?}: moved scores {}", score("moved"));
        let nearer = &results[2].counts;
        assert!(nearer.n1_minus > 0 && nearer.n1_plus == 0, "{mode:?}: nearer {nearer:?}");
        assert!(results[4].counts.synthetic_valid() > 0, "{mode:?}: the corner box is in view");
        if mode == ShadowMode::None {
            assert_eq!(results[5].counts.synthetic_valid(), 640 * 480, "{mode:?}: inside the box");
        }
        assert_eq!(results[6].counts.synthetic_valid(), 0, "{mode:?}: behind the camera");
    }
}

/// A pinhole sensed image refuses what cannot be: a sensor of other intrinsics or another
/// kind of view, and a labelled pixel at depth Z ≤ 0.
#[test]
fn verify_under_a_rig_refuses_mismatched_sensors_and_impossible_depths() {
    let sensed_scene = scene(projector_rig(), ShadowMode::None, &[("builtin:box", turned_box_pose())]);
    let image = RangeImage::from(&render(&sensed_scene));
    let sensed = SensedImage::new(&image, &projector_rig()).unwrap();
    let hypotheses = [rig_hypothesis("true", "builtin:box", turned_box_pose(), &[(1, 1)])];
    let refused = |settings: &VerifySettings| {
        common::VERIFIER.verify(&sensed, settings, &hypotheses, &mut |_| {}).err().map(|e| e.to_string())
    };
    let mut other = rig_settings(ShadowMode::None);
    other.sensor.reference =
        View::Pinhole(Pinhole { intrinsics: Intrinsics { fx: 510.0, ..camera() }, near: 0.0, far: f64::INFINITY });
    assert!(refused(&other).is_some_and(|e| e.contains("intrinsics")), "{:?}", refused(&other));
    let scanner =
        rangesynth::sensor::Scanner { width: 640, height: 480, pitch: [0.01; 2], origin: [0.0; 2], theta_deg: 0.0 };
    let ortho = VerifySettings { sensor: scanner.into(), ..rig_settings(ShadowMode::None) };
    let e = refused(&ortho).unwrap_or_default();
    assert!(e.contains("a view of kind pinhole but the sensor's reference view is orthographic"), "{e}");
    let mut behind = image.clone();
    let i = behind.label.iter().position(|&l| l != 0).unwrap();
    behind.z[i] = -1.0;
    let e = SensedImage::new(&behind, &projector_rig()).unwrap_err().to_string();
    assert!(e.contains("Z = -1") && e.contains("behind its pinhole view"), "{e}");
}

/// `verify` under an orthographic view that is not the paper's scanner (its one witness a
/// light from a direction, not `theta_deg`): the images are cast on the CPU, and the counts and scores are the independent CPU scorer's (orthographic areas and
/// N1− looking down z), the true pose scoring 1.
#[test]
fn verify_under_an_orthographic_rig_matches_the_cpu_scorer() {
    let view = rangesynth::sensor::Orthographic { width: 64, height: 48, pitch: [0.05, 0.05], origin: [-1.575, 1.175] };
    let light = Witness {
        name: "light".into(),
        geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::new(0.4, 0.0, 1.0).normalize())),
    };
    let sensor = Sensor { reference: View::Orthographic(view), witnesses: vec![light] };
    assert!(sensor.scanner().is_none());
    let pose = DMat4::from_rotation_z(0.3) * DMat4::from_rotation_y(0.2);
    let sensed_scene = scene(sensor.clone(), ShadowMode::Exact, &[("builtin:step", pose)]);
    let image = RangeImage::from(&render(&sensed_scene));
    let sensed = SensedImage::new(&image, &sensor).unwrap();
    let bindings: Vec<(u32, u32)> = (1..=8).map(|l| (l, l)).collect();
    let moved = DMat4::from_translation(DVec3::new(0.1, 0.0, 0.05)) * pose;
    let hypotheses = [
        rig_hypothesis("true", "builtin:step", pose, &bindings),
        rig_hypothesis("moved", "builtin:step", moved, &bindings),
    ];
    let settings = VerifySettings { sensor: sensor.clone(), ..rig_settings(ShadowMode::Exact) };
    let results = common::VERIFIER.verify(&sensed, &settings, &hypotheses, &mut |_| {}).expect("verifies");
    common::assert_no_validation_messages();
    for (h, v) in common::paired(&hypotheses, &results) {
        let synthetic = render(&scene(sensor.clone(), ShadowMode::Exact, &[(h.model.mesh.name.as_str(), h.pose)]));
        let cpu = cpu_counts(&Images::of(&image, &synthetic), settings.tolerance as f32);
        assert_eq!(as_cpu(&v.counts, &sensed, sensed.valid), cpu, "{}: counts", h.id);
        let expected = cpu_scores(&cpu, &h.bindings);
        assert_eq!(v.scores.s, expected[6], "{}", h.id);
    }
    assert_eq!(results[0].scores.s, 1.0);
    assert!(results[1].scores.s < 0.9, "{}", results[1].scores.s);
}

/// The pinhole score pass corrects a device's square root as the orthographic one does
/// (tests/verify.rs): stood in for on lavapipe by putting the root 2 ulp low and 3 high before
/// the correction, every count of a pinhole rig's verification, the areas included, stays the
/// exact root's.
#[test]
fn pinhole_areas_are_the_hosts_bits_where_the_devices_square_root_errs() {
    let sensed_scene = scene(projector_rig(), ShadowMode::None, &[("builtin:box", turned_box_pose())]);
    let image = RangeImage::from(&render(&sensed_scene));
    let sensed = SensedImage::new(&image, &projector_rig()).unwrap();
    let bindings: Vec<(u32, u32)> = (1..=6).map(|l| (l, l)).collect();
    let settings = rig_settings(ShadowMode::None);
    let hypothesis = rig_hypothesis("true", "builtin:box", turned_box_pose(), &bindings);
    let exact = common::VERIFIER.verify(&sensed, &settings, std::slice::from_ref(&hypothesis), &mut |_| {}).unwrap();
    assert!(exact[0].counts.surface_area_units.iter().any(|&a| a > 0), "areas counted");
    for ulps in [0, -2, 3] {
        let verifier = rangesynth::verify::Verifier::new(common::test_renderer(None))
            .and_then(|v| v.with_sqrt_error_for_tests(ulps))
            .expect("verifier");
        let model = verifier.model("builtin:box", std::path::Path::new(".")).expect("model");
        let h = Hypothesis { model, ..hypothesis.clone() };
        let out = verifier.verify(&sensed, &settings, &[h], &mut |_| {}).expect("verification runs");
        assert_eq!(out[0].counts, exact[0].counts, "the root {ulps} ulp off");
        let messages = verifier.renderer().context().take_validation_messages();
        assert!(messages.is_empty(), "validation reported:\n{}", messages.join("\n"));
    }
}

/// What lies wholly beyond `far` is not drawn: the plane at depth 5 under a camera whose far is
/// 4 leaves the image empty, on the GPU (modes `none` and `label`) as in the reference.
#[test]
fn a_pinhole_view_draws_nothing_beyond_its_far() {
    let witnesses = vec![projector("projector", DVec3::new(PROJECTOR_BASELINE, 0.0, 0.0), projector_image())];
    let sensor = Sensor { reference: View::Pinhole(Pinhole { intrinsics: camera(), near: 0.0, far: 4.0 }), witnesses };
    for mode in [ShadowMode::None, ShadowMode::Label] {
        let rig = scene(sensor.clone(), mode, &[("builtin:plane:20", facing_camera(DVec3::new(0.0, 0.0, 5.0)))]);
        let out = render(&rig);
        assert!(rig_reference(&rig).label.iter().all(|&l| l == 0), "the reference sees nothing");
        let seen = out.label_unshadowed.iter().filter(|&&l| l != 0).count();
        assert_eq!(seen, 0, "{mode:?}: {seen} pixels beyond far drawn");
    }
}

/// A floor exactly level with the camera's axis (its normal the camera's −y, so the plane's
/// gradient in the camera's frame is indeterminate in x and infinite in y) faces the camera and
/// a projector beside it: in mode `label` on the GPU no interior floor pixel is lost, as in the
/// reference.
#[test]
fn a_floor_level_with_the_axis_faces_its_witnesses() {
    // Model +z (the plane's normal) to camera −y, exactly; the floor 1 below the axis.
    let level = DMat4::from_cols(
        glam::DVec4::new(1.0, 0.0, 0.0, 0.0),
        glam::DVec4::new(0.0, 0.0, 1.0, 0.0),
        glam::DVec4::new(0.0, -1.0, 0.0, 0.0),
        glam::DVec4::new(0.0, 1.0, 5.0, 1.0),
    );
    let rig = scene(
        Sensor { reference: reference(), witnesses: vec![projector("projector", DVec3::new(0.3, 0.0, 0.0), camera())] },
        ShadowMode::Label,
        &[("builtin:plane:20", level)],
    );
    let out = render(&rig);
    let truth = rig_reference(&rig);
    let floor = truth.label.iter().filter(|&&l| l != 0).count();
    assert!(floor > 10_000, "the floor is seen: {floor} pixels");
    let (wrong, interior) = differences(&out, &truth, true, 1e-6);
    assert_eq!(interior, 0, "{wrong} pixels differ, {interior} interior");
}

/// A 64×48 camera of fx = fy = 50 (about ±32° across) and a plane through (0, 0, 2) turned
/// 45° about y, its unit normal (−√½, 0, −√½) facing the camera: pixel (c, r)'s ray
/// d = ((c − 31.5)/50, (r − 23.5)/50, 1) meets it at p = 2·d/(1 + d.x), from depth 1.23 on the
/// right to 5.4 on the left, seen from 77° to 13° off its normal.
fn tilted_plane(witnesses: Vec<Witness>, mode: ShadowMode, effects: &str) -> Scene {
    let k = Intrinsics { width: 64, height: 48, fx: 50.0, fy: 50.0, cx: 31.5, cy: 23.5 };
    let sensor =
        Sensor { reference: View::Pinhole(Pinhole { intrinsics: k, near: 0.0, far: f64::INFINITY }), witnesses };
    let pose = DMat4::from_translation(DVec3::new(0.0, 0.0, 2.0))
        * DMat4::from_rotation_y(std::f64::consts::FRAC_PI_4)
        * DMat4::from_rotation_x(std::f64::consts::PI);
    let mut rig = scene(sensor, mode, &[("builtin:plane:20", pose)]);
    rig.effects = toml::from_str(effects).unwrap();
    rig
}

/// The tilted plane's point and facing unit normal at pixel `i` (f64, worked out by hand).
fn tilted_plane_point(i: usize) -> (DVec3, DVec3) {
    let (c, r) = ((i % 64) as f64, (i / 64) as f64);
    let ray = DVec3::new((c - 31.5) / 50.0, (r - 23.5) / 50.0, 1.0);
    (2.0 * ray / (1.0 + ray.x), DVec3::new(-1.0, 0.0, -1.0).normalize())
}

/// Grazing under a rig is measured toward the camera (back along each pixel's ray) and toward
/// each witness: a projector 0.5 to the camera's right. With a limit of 70°, the camera loses
/// the plane's far left, the projector a band of columns the camera still sees well, the
/// expectation worked out per pixel in f64; in shadow modes none and label (drawn on the GPU)
/// and exact (cast on the CPU), whose effects are the same passes. Pixels within 1e-3 of the
/// limit's cosine are not compared (f32 normals).
#[test]
fn grazing_under_a_rig_is_measured_toward_the_camera_and_each_witness() {
    let limit = 70f64.to_radians().cos();
    let projector_at = DVec3::new(0.5, 0.0, 0.0);
    let wide = Intrinsics { width: 400, height: 300, fx: 50.0, fy: 50.0, cx: 199.5, cy: 149.5 };
    let (mut by_camera, mut by_projector_alone, mut kept) = (0, 0, 0);
    let expected: Vec<Option<bool>> = (0..64 * 48)
        .map(|i| {
            let (p, n) = tilted_plane_point(i);
            let camera = n.dot(-p) / p.length();
            let projector = n.dot(projector_at - p) / (projector_at - p).length();
            assert!(camera > 0.05 && projector > 0.05, "every point faces both");
            let lost = camera.min(projector) < limit;
            by_camera += usize::from(camera < limit);
            by_projector_alone += usize::from(camera >= limit && projector < limit);
            kept += usize::from(!lost);
            ((camera - limit).abs() > 1e-3 && (projector - limit).abs() > 1e-3).then_some(lost)
        })
        .collect();
    assert!(by_camera > 200 && by_projector_alone > 200 && kept > 200, "{by_camera} {by_projector_alone} {kept}");
    for mode in [ShadowMode::None, ShadowMode::Label, ShadowMode::Exact] {
        let rig =
            tilted_plane(vec![projector("projector", projector_at, wide)], mode, "[grazing]\nmax_incidence_deg = 70\n");
        let out = render(&rig);
        for (i, lost) in expected.iter().enumerate() {
            let Some(lost) = *lost else { continue };
            let want = if lost { Reason::Grazing } else { Reason::Valid };
            assert_eq!(out.reason[i], want, "{mode:?}: pixel ({}, {})", i % 64, i / 64);
        }
    }
}

/// A directional witness's grazing: a light 75° off the normal of a plane facing the view
/// loses every pixel at a 70° limit, a light 65° off it none; under a pinhole view (light from
/// the camera's side, the plane facing back along z) and an orthographic one (the plane's
/// normal +z), cast in mode exact and drawn in mode none.
#[test]
fn grazing_toward_a_directional_witness_under_either_view() {
    let light = |degrees: f64, toward: DVec3| Witness {
        name: "light".into(),
        geometry: WitnessGeometry::Directional(Direction::Vector(
            DVec3::new(degrees.to_radians().sin(), 0.0, 0.0) + degrees.to_radians().cos() * toward,
        )),
    };
    let grazing = "[grazing]\nmax_incidence_deg = 70\n";
    for (degrees, want) in [(75.0, Reason::Grazing), (65.0, Reason::Valid)] {
        let mut pinhole = plane_at(1.9, grazing);
        pinhole.sensor.witnesses = vec![light(degrees, DVec3::NEG_Z)];
        let view = rangesynth::sensor::Orthographic { width: 32, height: 24, pitch: [0.1, 0.1], origin: [-1.55, 1.15] };
        let ortho_sensor = Sensor { reference: View::Orthographic(view), witnesses: vec![light(degrees, DVec3::Z)] };
        for mode in [ShadowMode::None, ShadowMode::Exact] {
            let mut orthographic = scene(ortho_sensor.clone(), mode, &[("builtin:plane:20", DMat4::IDENTITY)]);
            orthographic.effects = toml::from_str(grazing).unwrap();
            pinhole.shadow.mode = mode;
            for (what, rig) in [("pinhole", &pinhole), ("orthographic", &orthographic)] {
                let out = render(rig);
                let wrong = out.reason.iter().filter(|&&r| r != want).count();
                assert_eq!(wrong, 0, "{what}, {mode:?}, light {degrees}° off: {wrong} pixels not {want:?}");
            }
        }
    }
}

/// The noise's incidence term under a pinhole view measures α back along each pixel's ray:
/// on the tilted plane α runs from 13° to 77°, so σ = 0.001·α²/(π/2 − α)² grows from 1e-4 to
/// 0.027 across the image. The noise divided by each pixel's σ (worked out in f64) has a
/// standard deviation of 1 within 10% on the plane's nearer-facing half and on its more
/// oblique half alike, and a mean near 0.
#[test]
fn noise_incidence_under_a_rig_is_measured_back_along_each_ray() {
    let clean = render(&tilted_plane(vec![], ShadowMode::None, ""));
    let noisy = render(&tilted_plane(
        vec![],
        ShadowMode::None,
        "[noise]\nsigma = 0\nincidence_coefficient = 0.001\nseed = 3\n",
    ));
    let mut halves = [Vec::new(), Vec::new()];
    for i in 0..64 * 48 {
        let (p, n) = tilted_plane_point(i);
        let alpha = (n.dot(-p) / p.length()).acos();
        let sigma = 0.001 * (alpha / (std::f64::consts::FRAC_PI_2 - alpha)).powi(2);
        let noise = f64::from(noisy.z[i]) - f64::from(clean.z[i]);
        halves[usize::from(alpha > std::f64::consts::FRAC_PI_4)].push(noise / sigma);
    }
    for (half, standardised) in halves.iter().enumerate() {
        let n = standardised.len() as f64;
        let mean = standardised.iter().sum::<f64>() / n;
        let sd = (standardised.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!(n > 500.0 && (sd - 1.0).abs() < 0.1 && mean.abs() < 0.15, "half {half}: n {n}, mean {mean}, sd {sd}");
    }
}

/// Directional witnesses in modes `label` and `depth`: two lamps, high to the left and low to
/// the right, over a box, a step and a plank on a table (flat faces, none grazed by a lamp),
/// under a camera with a projector beside it, and under the camera and the lamps alone
/// (photometric stereo: no pinhole witness). The lamps' images are drawn orthographically along
/// their directions over what the camera can see (at `[shadow] columns = 2`); labels, depths and
/// witness bits against the brute-force reference, with no interior pixel wrong, as in mode
/// `exact`, each lamp losing pixels alone. Under the lamps alone, once more with the step alone,
/// stored 40 units from its model frame's origin (the mesh keeps an origin of its own) and
/// posed back: the same.
#[test]
fn directional_witnesses_in_modes_label_and_depth_match_the_brute_force_reference() {
    let k = Intrinsics { width: 160, height: 120, fx: 150.0, fy: 150.0, cx: 79.5, cy: 59.5 };
    let lamp = |name: &str, toward: DVec3| Witness {
        name: name.into(),
        geometry: WitnessGeometry::Directional(Direction::Vector(toward.normalize())),
    };
    let lamps = vec![lamp("high left", DVec3::new(-0.5, -0.6, -0.62)), lamp("low right", DVec3::new(0.7, 0.2, -0.68))];
    let with_projector = [
        vec![projector("projector", DVec3::new(0.075, 0.0, 0.0), Intrinsics { width: 200, height: 160, ..k })],
        lamps.clone(),
    ]
    .concat();
    let tilt = |at: DVec3, angle: f64| facing_camera(at) * DMat4::from_rotation_z(angle);
    let objects = [
        ("builtin:plane:4", facing_camera(DVec3::new(0.0, 0.0, 1.5)), 1.0),
        ("builtin:box", tilt(DVec3::new(0.2, -0.1, 1.5), 0.4), 0.25),
        ("builtin:step", tilt(DVec3::new(-0.25, 0.2, 1.5), -0.7), 0.25),
        ("builtin:box", tilt(DVec3::new(-0.3, -0.25, 1.5), 1.1), 0.15),
    ];
    let posed: Vec<(&str, DMat4)> = objects.iter().map(|&(model, pose, _)| (model, pose)).collect();
    let modes = [ShadowMode::Exact, ShadowMode::Label, ShadowMode::Depth];
    let runs = modes.iter().flat_map(|&mode| {
        [(&with_projector, mode, false), (&lamps, mode, false)]
            .into_iter()
            .chain((mode != ShadowMode::Exact).then_some((&lamps, mode, true)))
    });
    for (witnesses, mode, stored_away) in runs {
        let reference = View::Pinhole(Pinhole { intrinsics: k, near: 0.1, far: f64::INFINITY });
        let sensor = Sensor { reference, witnesses: witnesses.clone() };
        let mut rig = scene(sensor, mode, &posed);
        // Each lamp's image at twice the pixels: at one, a pixel two from an object's edge
        // went to the label test's rim.
        rig.shadow.columns = 2;
        for (object, &(_, _, scale)) in rig.objects.iter_mut().zip(&objects) {
            object.mesh = std::sync::Arc::new((*object.mesh).clone().scaled(scale, &Default::default()).unwrap());
        }
        if stored_away {
            let step = &mut rig.objects[2];
            let away = DVec3::new(40.0, 0.0, 0.0);
            let m = &*step.mesh;
            let positions = (0..m.positions.len() as u32).map(|i| (m.vertex(i) + away).to_array()).collect();
            let moved = rangesynth::mesh::Mesh::new(
                "the step stored away",
                positions,
                m.triangles.clone(),
                m.triangle_surfaces.clone(),
                m.surface_names.clone(),
            )
            .unwrap();
            assert_ne!(moved.origin, DVec3::ZERO, "the mesh keeps an origin of its own");
            step.mesh = std::sync::Arc::new(moved);
            step.pose *= DMat4::from_translation(-away);
            // Alone, so that its lamps' images are planned over it alone.
            rig.objects = vec![rig.objects[2].clone()];
        }
        let what =
            format!("{mode:?}, {} witnesses{}", witnesses.len(), if stored_away { ", step stored away" } else { "" });
        let out = render(&rig);
        let truth = rig_reference(&rig);
        let (wrong, wrong_interior) = differences(&out, &truth, true, 1e-6);
        eprintln!("{what}: {wrong} pixels differ from the reference, {wrong_interior} interior");
        assert_eq!(wrong_interior, 0, "{what}: {wrong} pixels differ, {wrong_interior} interior");
        let first_lamp = 1 << (witnesses.len() - 2);
        let lamps_alone =
            if stored_away { vec![] } else { vec![(first_lamp, "high left"), (first_lamp << 1, "low right")] };
        for (bit, lamp) in lamps_alone {
            let alone = |bits: &[u32]| bits.iter().filter(|&&b| b == bit).count();
            let (ours, reference) = (alone(&out.witness), alone(&truth.witness));
            assert!(ours > 100 && reference > 100, "{what}: the {lamp} lamp alone loses {ours} pixels ({reference})");
        }
    }
}

/// What BOP's scoring draws (`Renderer::draw_alone`: each model alone within its footprint,
/// eight a submission) is what `render` draws of each model alone, under a camera with a
/// projector and a lamp in modes `label` and `depth`: labels, shadowed labels and depth bits,
/// for ten models in two submissions (each job with its own table for the lamp's grid, and in
/// mode `depth` its witnesses' draw tables).
#[test]
fn models_drawn_alone_under_a_lamp_are_what_render_draws_in_modes_label_and_depth() {
    let lamp = Witness {
        name: "lamp".into(),
        geometry: WitnessGeometry::Directional(Direction::Vector(DVec3::new(0.3, -0.5, -0.8).normalize())),
    };
    let mut sensor = projector_rig();
    sensor.witnesses.push(lamp);
    let models: Vec<(std::sync::Arc<rangesynth::mesh::Mesh>, DMat4)> = (0..10)
        .map(|i| {
            let name = if i % 2 == 0 { "builtin:box" } else { "builtin:step" };
            let at = DVec3::new(-1.5 + 0.35 * f64::from(i), 0.4 * f64::from(i % 3) - 0.4, 4.5 + 0.1 * f64::from(i));
            let pose = facing_camera(at) * DMat4::from_rotation_z(0.3 * f64::from(i)) * DMat4::from_rotation_x(0.2);
            (std::sync::Arc::new(rangesynth::mesh::builtin_mesh(name).unwrap()), pose)
        })
        .collect();
    for mode in [ShadowMode::Label, ShadowMode::Depth] {
        let shadow = ShadowSettings::of(mode);
        let drawn = common::renderer().draw_alone(&sensor, &shadow, &models, &|i| format!("model {i}")).unwrap();
        common::assert_no_validation_messages();
        let mut lost_by_lamp = 0;
        for (i, ((mesh, pose), alone)) in models.iter().zip(&drawn).enumerate() {
            let out = render(&scene(sensor.clone(), mode, &[(mesh.name.as_str(), *pose)]));
            assert!(alone.label.iter().any(|&l| l != 0), "{mode:?}, model {i} is in view");
            assert_eq!(alone.label, out.label_unshadowed, "{mode:?}, model {i}: labels");
            assert_eq!(alone.shadowed, out.label, "{mode:?}, model {i}: shadowed labels");
            lost_by_lamp += out.witness.iter().filter(|&&bits| bits == 2).count();
            let seen = alone.label.iter().map(|&l| l != 0);
            for (p, ((a, b), seen)) in alone.z.iter().zip(&out.z).zip(seen).enumerate() {
                assert!(!seen || a.to_bits() == b.to_bits(), "{mode:?}, model {i}, pixel {p}: z {a} vs {b}");
            }
        }
        assert!(lost_by_lamp > 100, "{mode:?}: the lamp alone loses pixels: {lost_by_lamp}");
    }
}
