//! Shadow mode `exact` (src/exact/) and the knobs that refine the GPU modes (`[shadow]
//! columns`, `neighbourhood`): exact mode against the tests' independent CPU reference
//! (tests/common/reference.rs) and against geometric oracles; its images through the GPU's
//! effect passes; and the knobs against exact shadowing.

// Per-pixel arrays are read side by side by pixel index.
#![allow(clippy::needless_range_loop)]

mod common;

use common::reference::reference_render;
use common::*;
use glam::{DMat4, DQuat, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rangesynth::effects::{Grazing, Reason};
use rangesynth::exact::render_scene_exact;
use rangesynth::mesh::builtin_mesh;
use rangesynth::shadow::{Neighbourhood, ShadowMode, ShadowSettings};
use rangesynth::Scene;

const SIZE: u32 = 96;
/// Where the single models sit: off the pixel lattice, so that no edge of a symmetric model
/// runs exactly along a row of pixel centres (an exact tie, decided by rule, not geometry).
const OFF_GRID: DVec3 = DVec3::new(0.0123, 0.0071, 0.0);

fn about_centre(model: &str, rotation: DQuat, at: DVec3) -> DMat4 {
    let (centre, _) = builtin_mesh(model).expect("built-in").bounding_sphere();
    DMat4::from_translation(at) * DMat4::from_quat(rotation) * DMat4::from_translation(-centre)
}

fn random_rotation(rng: &mut ChaCha8Rng) -> DQuat {
    DQuat::from_euler(glam::EulerRot::XYZ, rng.gen_range(-3.2..3.2), rng.gen_range(-1.6..1.6), rng.gen_range(-3.2..3.2))
}

/// The conformance scenes: single built-ins and a cluttered table, each under the identity
/// and two seeded random rotations (the table stays flat).
fn conformance_scenes(theta: f64, mode: ShadowMode) -> Vec<(String, Scene)> {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut scenes = Vec::new();
    for (model, extent) in
        [("builtin:step", 3.0), ("builtin:box", 2.5), ("builtin:cylinder:24", 2.5), ("builtin:sphere:16", 2.5)]
    {
        for k in 0..3 {
            let rotation = if k == 0 { DQuat::IDENTITY } else { random_rotation(&mut rng) };
            let s = centred_sensor(SIZE, SIZE, extent / f64::from(SIZE), [0.0, 0.0], theta);
            scenes.push((
                format!("{model} pose {k}"),
                scene(s, mode, &[(model, about_centre(model, rotation, OFF_GRID))]),
            ));
        }
    }
    let s = centred_sensor(SIZE, SIZE, 5.0 / f64::from(SIZE), [0.0, 0.0], theta);
    let table = [
        ("builtin:step", DMat4::from_translation(DVec3::new(0.6, 0.8, 0.0)) * DMat4::from_rotation_z(0.35)),
        ("builtin:cylinder:24", DMat4::from_translation(DVec3::new(-1.0, -1.2, 0.0))),
        ("builtin:box", DMat4::from_translation(DVec3::new(-1.1, 1.0, 0.0)) * DMat4::from_rotation_z(-0.5)),
        ("builtin:plane:5", DMat4::IDENTITY),
    ];
    scenes.push(("cluttered table".into(), scene(s, mode, &table)));
    scenes
}

#[test]
fn exact_mode_agrees_with_the_independent_reference() {
    let mut ties = 0;
    for theta in [45.0, -30.0] {
        for (name, scene) in conformance_scenes(theta, ShadowMode::Exact) {
            let exact = render_scene_exact(&scene).expect("exact render");
            let reference = reference_render(&scene);
            let case = format!("{name}, θ = {theta}");
            assert!(exact.label.iter().any(|&l| l != 0), "{case}: the model is in view");
            let mut worst_z = 0.0f64;
            for i in 0..exact.label.len() {
                assert_eq!(exact.label[i], reference.label[i], "{case}: label at pixel {i}");
                if exact.label[i] != 0 {
                    worst_z = worst_z.max((exact.z[i] - reference.z[i]).abs() / reference.z[i].abs().max(1.0));
                }
            }
            assert!(worst_z <= 1e-9, "{case}: z differs from the reference by {worst_z:e}");
            eprintln!("{case}: z within {worst_z:e} of the reference");
            let expected = reference.label_shadowed();
            // A pixel centre on an edge takes one of the planes meeting there, by rule: whether
            // it faces the camera may differ with the plane.
            let differing: Vec<usize> =
                (0..expected.len()).filter(|&i| exact.shadowed[i] != expected[i] && !reference.tied[i]).collect();
            assert!(differing.is_empty(), "{case}: shadowed labels differ away from ties at pixels {differing:?}");
            ties += reference.tied.iter().filter(|&&t| t).count();
        }
    }
    eprintln!("{ties} pixel centres on edges or vertices, where the plane is a matter of rule");
}

/// A scene's objects as exact mode casts them.
fn exact_objects(scene: &Scene) -> Vec<rangesynth::exact::ExactObject<'_>> {
    let bases = scene.label_bases().unwrap();
    let objects = scene.objects.iter().zip(bases);
    objects
        .map(|(o, label_base)| rangesynth::exact::ExactObject {
            mesh: &o.mesh,
            pose: o.pose,
            label_base,
            solidity: o.mesh.solidity(),
        })
        .collect()
}

/// Exact mode leaves a solid's triangles facing away from a caster's rays out of it
/// (src/exact/mod.rs, `posed_triangles`): the images are those of the same meshes cast whole
/// (but for a ray within the tie distance of a silhouette edge, which these scenes' pixel
/// centres avoid), bit for bit (labels, shadowed labels, z, gradients, witness bits), on the conformance
/// scenes at three θ, on a box wound inside out (its normals pointing in), under a rig of a
/// camera looking down and two lamps (directional witnesses, whose casters cull too), and
/// under pinhole rigs whose views must keep a solid whole: a near limit cutting it open, a
/// projector inside it.
#[test]
fn culling_a_solids_back_faces_changes_no_bit_of_exact_mode() {
    use rangesynth::exact::{render_exact, ExactImage, ExactObject};
    use rangesynth::mesh::{Mesh, Solidity};
    use rangesynth::sensor::{Direction, Intrinsics, Pinhole, Sensor, View, Witness, WitnessGeometry};
    let inside_out = {
        let cube = builtin_mesh("builtin:box").unwrap();
        let positions = (0..cube.positions.len() as u32).map(|v| cube.vertex(v).to_array()).collect();
        let triangles = cube.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
        Mesh::new(
            "inside-out box".to_string(),
            positions,
            triangles,
            cube.triangle_surfaces.clone(),
            cube.surface_names.clone(),
        )
        .unwrap()
    };
    assert_eq!(inside_out.solidity(), Solidity::Inward);
    let both = |case: &str, sensor: &Sensor, objects: Vec<ExactObject>| {
        let bits = |image: &ExactImage| {
            let z: Vec<u64> = image.z.iter().map(|z| z.to_bits()).collect();
            let gradient: Vec<[u64; 2]> = image.gradient.iter().map(|g| g.map(f64::to_bits)).collect();
            (image.label.clone(), image.shadowed.clone(), z, gradient, image.witness.clone())
        };
        let culled = render_exact(sensor, &objects).unwrap();
        let whole: Vec<ExactObject> = objects.iter().map(|&o| ExactObject { solidity: Solidity::Open, ..o }).collect();
        assert!(culled.label.iter().any(|&l| l != 0), "{case}: in view");
        assert!(bits(&culled) == bits(&render_exact(sensor, &whole).unwrap()), "{case}: culled differs from whole");
    };
    let mut solids = 0;
    for theta in [45.0, -30.0, 80.0] {
        for (name, scene) in conformance_scenes(theta, ShadowMode::Exact) {
            let objects = exact_objects(&scene);
            solids += objects.iter().filter(|o| o.solidity != Solidity::Open).count();
            both(&format!("{name}, θ = {theta}"), &scene.sensor, objects);
        }
    }
    assert!(solids > 20, "the scenes hold solids: {solids}");
    let pose = DMat4::from_rotation_x(0.3) * DMat4::from_rotation_z(0.5);
    let s = centred_sensor(SIZE, SIZE, 2.5 / f64::from(SIZE), [0.0, 0.0], 45.0);
    both(
        "inside-out box",
        &s.into(),
        vec![ExactObject { mesh: &inside_out, pose, label_base: 0, solidity: Solidity::Inward }],
    );
    let lamps = [DVec3::new(0.6, 0.2, 0.77), DVec3::new(-0.3, -0.7, 0.65)].map(|d| Direction::Vector(d.normalize()));
    let mut rig: Sensor = centred_sensor(SIZE, SIZE, 5.0 / f64::from(SIZE), [0.0, 0.0], 0.0).into();
    rig.witnesses = lamps
        .iter()
        .enumerate()
        .map(|(i, &d)| Witness { name: format!("lamp {i}"), geometry: WitnessGeometry::Directional(d) })
        .collect();
    let (_, table) = conformance_scenes(0.0, ShadowMode::Exact).pop().unwrap();
    both("cluttered table under two lamps", &rig, exact_objects(&table));
    // A pinhole camera 6 units above the table, looking down at it, and a pinhole projector:
    // beside it; with the camera's near limit cutting the models (whose insides it then sees);
    // inside the box (which it sees from within).
    let flip = DMat4::from_translation(DVec3::new(0.0, 0.0, 6.0)) * DMat4::from_rotation_x(std::f64::consts::PI);
    let on_table: Vec<ExactObject> =
        exact_objects(&table).into_iter().map(|o| ExactObject { pose: flip * o.pose, ..o }).collect();
    let inside_box = flip.transform_point3(DVec3::new(-1.1, 1.0, 0.5));
    let k = Intrinsics { width: 96, height: 72, fx: 60.0, fy: 60.0, cx: 47.5, cy: 35.5 };
    for (case, near, projector) in [
        ("a camera and a projector beside it", 0.0, DVec3::new(0.4, 0.1, 0.0)),
        ("a near limit through the models", 5.5, DVec3::new(0.4, 0.1, 0.0)),
        ("a projector inside the box", 0.0, inside_box),
    ] {
        let geometry = WitnessGeometry::Pinhole {
            pose: DMat4::from_translation(projector),
            intrinsics: Intrinsics { width: 400, height: 400, cx: 199.5, cy: 199.5, ..k },
        };
        let sensor = Sensor {
            reference: View::Pinhole(Pinhole { intrinsics: k, near, far: f64::INFINITY }),
            witnesses: vec![Witness { name: "projector".into(), geometry }],
        };
        both(case, &sensor, on_table.clone());
    }
}

#[test]
fn on_a_convex_body_exactly_the_facets_facing_the_camera_are_lit() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for model in ["builtin:box", "builtin:sphere:8", "builtin:sphere:24", "builtin:sphere:64", "builtin:cylinder:12"] {
        for theta in [45.0, 20.0, -60.0] {
            let pose = about_centre(model, random_rotation(&mut rng), DVec3::ZERO);
            let s = centred_sensor(SIZE, SIZE, 2.5 / f64::from(SIZE), [0.0, 0.0], theta);
            let scene = scene(s, ShadowMode::Exact, &[(model, pose)]);
            let exact = render_scene_exact(&scene).expect("exact render");
            let reference = reference_render(&scene);
            let d_cam = s.camera_direction();
            let (mut lit, mut shadowed) = (0, 0);
            for i in 0..exact.label.len() {
                // Where a centre lies on an edge, which facet's plane holds is a matter of rule.
                if reference.label[i] == 0 || reference.tied[i] {
                    continue;
                }
                assert_eq!(exact.label[i], reference.label[i], "{model} θ = {theta}: pixel {i} hits the facet");
                // The facet's normal, from its corners here in f64, against the camera.
                let facing = reference.lit_normal[i].dot(d_cam);
                if facing.abs() < 1e-6 {
                    continue;
                }
                let is_lit = exact.shadowed[i] != 0;
                assert_eq!(is_lit, facing > 0.0, "{model} θ = {theta}: pixel {i} facing {facing}");
                if is_lit {
                    lit += 1
                } else {
                    shadowed += 1
                }
            }
            assert!(lit > 0, "{model} θ = {theta}: some facets face the camera");
            assert!(shadowed > 0 || model == "builtin:box", "{model} θ = {theta}: {shadowed} turned away");
        }
    }
}

#[test]
fn exact_images_go_through_the_gpu_effects_as_cast() {
    let s = centred_sensor(SIZE, SIZE, 5.0 / f64::from(SIZE), [0.0, 0.0], 45.0);
    let objects = [
        ("builtin:sphere:24", DMat4::from_translation(DVec3::new(-0.8, 0.3, 0.6))),
        ("builtin:step", DMat4::from_translation(DVec3::new(0.6, -0.4, 0.0)) * DMat4::from_rotation_z(0.35)),
        ("builtin:plane:5", DMat4::IDENTITY),
    ];
    let scene = scene(s, ShadowMode::Exact, &objects);
    let exact = render_scene_exact(&scene).expect("exact render");
    let out = render(&scene);
    assert!(out.label_unshadowed == exact.label, "labels as cast");
    assert!(out.label == exact.shadowed, "shadowed labels as cast");
    for i in 0..exact.label.len() {
        if exact.label[i] != 0 {
            let error = (f64::from(out.z[i]) - exact.z[i]).abs();
            assert!(error <= 1e-6 * exact.z[i].abs().max(1.0), "pixel {i}: z {} vs {}", out.z[i], exact.z[i]);
        }
        let expected = match (exact.label[i], exact.shadowed[i]) {
            (0, _) => Reason::NoSurface,
            (_, 0) => Reason::Shadow,
            _ => Reason::Valid,
        };
        assert_eq!(out.reason[i], expected, "pixel {i}");
    }
    assert!(out.timings.iter().any(|t| t.on_cpu), "the CPU's ray casting is timed");

    // Grazing losses read the cast planes: a lit pixel whose facet's normal (from its corners,
    // in the independent reference) makes more than 50° with the projector or the camera is
    // lost to grazing, and no other.
    let effects = Effects { grazing: Some(Grazing { max_incidence_deg: 50.0 }), ..Effects::default() };
    let grazed = render(&Scene { effects, ..scene.clone() });
    let reference = reference_render(&scene);
    let limit = 50f64.to_radians().cos();
    let d_cam = s.camera_direction();
    let mut lost = 0;
    for i in 0..exact.label.len() {
        let n = reference.lit_normal[i];
        let incidence = n.z.min(n.dot(d_cam));
        let on_the_facet = exact.label[i] == reference.label[i] && !reference.tied[i];
        if exact.shadowed[i] != 0 && on_the_facet && (incidence - limit).abs() > 1e-4 {
            let expected = if incidence < limit { Reason::Grazing } else { Reason::Valid };
            assert_eq!(grazed.reason[i], expected, "pixel {i}: incidence cosine {incidence}");
            lost += usize::from(incidence < limit);
        }
    }
    assert!(lost > 0, "the sphere's lit rim grazes");
}

/// Pixels whose validity or label differs from exact shadowing, among those counted.
fn wrong_pixels(scene: &Scene, expected: &[u32], counted: &[bool]) -> usize {
    let out = render(scene);
    (0..expected.len()).filter(|&i| counted[i] && out.label[i] != expected[i]).count()
}

/// Against exact shadowing, as computed by the independent reference. The label test cannot see
/// a surface shadow itself (src/shadow.rs), whatever the resolution: for it, pixels shadowed
/// only by their own surface are not counted (there, being right is luck).
#[test]
fn a_finer_shadow_buffer_is_never_worse() {
    for mode in [ShadowMode::Depth, ShadowMode::Label] {
        for (name, scene) in conformance_scenes(45.0, mode) {
            let reference = reference_render(&scene);
            let expected = reference.label_shadowed();
            let paper = reference.label_paper_shadowed();
            let counted: Vec<bool> =
                (0..expected.len()).map(|i| mode == ShadowMode::Depth || paper[i] == expected[i]).collect();
            let wrong = |columns| {
                let shadow = ShadowSettings { columns, ..ShadowSettings::of(mode) };
                wrong_pixels(&Scene { shadow, ..scene.clone() }, &expected, &counted)
            };
            let one = wrong(1);
            for k in [2, 4] {
                let finer = wrong(k);
                eprintln!("{name} {}: wrong pixels {one} at k = 1, {finer} at k = {k}", mode.as_str());
                assert!(finer <= one, "{name} {}: {finer} wrong pixels at k = {k}, {one} at k = 1", mode.as_str());
            }
        }
    }
}

#[test]
fn the_2x2_label_test_keeps_every_pixel_the_nearest_keeps() {
    let mut kept_more = 0;
    for (name, scene) in conformance_scenes(45.0, ShadowMode::Label) {
        let nearest = render(&scene);
        let square = ShadowSettings { neighbourhood: Neighbourhood::Square2, ..ShadowSettings::of(ShadowMode::Label) };
        let wide = render(&Scene { shadow: square, ..scene.clone() });
        assert_eq!(wide.label_unshadowed, nearest.label_unshadowed);
        for i in 0..nearest.label.len() {
            // The nearest shadow pixel is one of the four, so a pixel lit by it stays lit.
            assert!(nearest.label[i] == 0 || wide.label[i] == nearest.label[i], "{name}: pixel {i}");
            kept_more += usize::from(nearest.label[i] == 0 && wide.label[i] != 0);
        }
    }
    assert!(kept_more > 0, "the 2×2 test keeps some of the nearest test's rim");
}

#[test]
fn shadow_knobs_out_of_range_are_refused() {
    let (_, base) = conformance_scenes(45.0, ShadowMode::Depth).swap_remove(0);
    for (shadow, expected) in [
        (ShadowSettings { columns: 0, ..ShadowSettings::of(ShadowMode::Depth) }, "columns = 0"),
        (ShadowSettings { columns: 9, ..ShadowSettings::of(ShadowMode::Depth) }, "columns = 9"),
        (
            ShadowSettings { neighbourhood: Neighbourhood::Square2, ..ShadowSettings::of(ShadowMode::Depth) },
            "neighbourhood",
        ),
    ] {
        let err = renderer().render(&Scene { shadow, ..base.clone() }).expect_err("refused").to_string();
        assert!(err.contains(expected), "{err}");
    }
}
