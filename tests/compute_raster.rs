//! The compute rasterizer (src/render/raster/compute/) against the graphics pipeline: the
//! same coverage rule (top-left), the same sub-pixel precision (1/256) and the same plane z
//! should give the same images. The allowance is stated here: none on lavapipe, where every
//! label, shadowed label and z bit is identical on every case below; on a GPU, a boundary
//! between two surfaces may move by a fraction of a pixel (`assert_same_images`). (Both skip a
//! solid's triangles facing away, the graphics pipeline judging by the snapped corners, the
//! compute rasterizer by the normal: they could disagree only on a triangle seen almost
//! edge-on. And the graphics pipeline clips a triangle reaching past its viewport, 8,192
//! pixels from the view's centre on lavapipe, and snaps the clipper's corners anew, which the
//! compute rasterizer does not: see `triangles_crossing_the_views_edge_…`.) The other
//! comparisons (effects, spikes, a solid wound inward) stay exact on every device: they passed
//! so on NVIDIA's H100 and H200.

mod common;

use common::compare::near_label_change;
use common::*;
use glam::{DMat4, DVec3};
use rangesynth::effects::{Effects, Reason};
use rangesynth::mesh::{builtin_mesh, Mesh, Solidity};
use rangesynth::render::{Raster, MAX_REACH_PIXELS, MAX_SEEN_REACH_PIXELS};
use rangesynth::scene::{Scene, SceneObject};
use rangesynth::sensor::MAX_IMAGE_SIDE;
use rangesynth::shadow::{Neighbourhood, ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, Verifier, VerifySettings};
use rangesynth::RenderOutput;
use std::path::Path;
use std::sync::{Arc, LazyLock};

/// A second renderer, with the compute rasterizer, beside the tests' graphics one.
static COMPUTE: LazyLock<Verifier> = LazyLock::new(|| {
    let renderer = test_renderer(None);
    assert!(renderer.supports_compute_raster(), "lavapipe has 64-bit buffer atomics");
    Verifier::new(renderer.with_raster(Raster::Compute)).expect("verifier")
});

/// A third, choosing per view (the library's and the command line's default).
static AUTO: LazyLock<Verifier> =
    LazyLock::new(|| Verifier::new(test_renderer(None).with_raster(Raster::Auto)).expect("verifier"));

/// Both, covering four hypotheses a coverage dispatch, as a GPU does by default (on lavapipe
/// the default is one).
static GROUPED: LazyLock<[Verifier; 2]> = LazyLock::new(|| {
    [Raster::Compute, Raster::Auto].map(|raster| {
        let renderer = test_renderer(None).with_raster(raster).with_hypotheses_per_dispatch(4);
        assert_eq!(renderer.hypotheses_per_dispatch(), 4);
        Verifier::new(renderer).expect("verifier")
    })
});

fn render_with(verifier: &Verifier, scene: &Scene) -> RenderOutput {
    let out = verifier.renderer().render(scene).unwrap_or_else(|e| panic!("render failed: {e}"));
    let messages = verifier.renderer().context().take_validation_messages();
    assert!(messages.is_empty(), "validation: {}", messages.join("\n"));
    out
}

fn render_compute(scene: &Scene) -> RenderOutput {
    render_with(&COMPUTE, scene)
}

fn turned() -> DMat4 {
    DMat4::from_translation(DVec3::new(0.2, -0.1, 0.3))
        * DMat4::from_rotation_z(0.7)
        * DMat4::from_rotation_x(0.4)
        * DMat4::from_rotation_y(-0.3)
}

#[test]
fn both_rasterizers_render_identical_images_of_one_object() {
    // Triangles of every size: sphere:16's fill boxes of up to 8 rows (raster.comp's small
    // boxes keep the covered pixels of rows 4–7 apart), sphere:320's cover a pixel or none. A
    // flat plane has no hull faces (`GpuMesh::hull_faces`): its depth test walks from every face.
    let models = [
        "builtin:plane:6",
        "builtin:box",
        "builtin:step",
        "builtin:cylinder:48",
        "builtin:sphere:16",
        "builtin:sphere:64",
        "builtin:sphere:320",
    ];
    for model in models {
        let settings = [
            (45.0, ShadowMode::Depth, Neighbourhood::Nearest),
            (-30.0, ShadowMode::Label, Neighbourhood::Nearest),
            (-30.0, ShadowMode::Label, Neighbourhood::Square2),
            (20.0, ShadowMode::None, Neighbourhood::Nearest),
        ];
        for (theta, mode, neighbourhood) in settings {
            for (pose_name, pose) in [("identity", DMat4::IDENTITY), ("turned", turned())] {
                let s = centred_sensor(96, 80, 0.035, [0.1, 0.0], theta);
                let mut sc = scene(s, mode, &[(model, pose)]);
                sc.shadow.neighbourhood = neighbourhood;
                let graphics = render(&sc);
                let compute = render_compute(&sc);
                let name = format!("{model} {pose_name} θ = {theta} {:?}", sc.shadow);
                assert_eq!(graphics.raster, Some(Raster::Graphics));
                assert_eq!(compute.raster, Some(Raster::Compute), "{name}");
                assert!(graphics.label_unshadowed.iter().any(|&l| l != 0), "{name}: in view");
                assert_same_images(&name, &graphics, &compute);
            }
        }
    }
}

/// The effects read the range view's attachments, gradients included, which the shadow mask
/// writes where the compute rasterizer rendered the views: grazing incidence and noise turn
/// on them, and must drop and perturb the same pixels by the same bits.
#[test]
fn effects_see_the_same_range_view_from_either_rasterizer() {
    let effects: Effects =
        toml::from_str("[grazing]\nmax_incidence_deg = 55\n[noise]\nsigma = 0.002\nseed = 7").expect("effects");
    for (model, mode) in [("builtin:sphere:64", ShadowMode::Depth), ("builtin:cylinder:48", ShadowMode::Label)] {
        let s = centred_sensor(96, 80, 0.035, [0.1, 0.0], 35.0);
        let mut sc = scene(s, mode, &[(model, turned())]);
        sc.effects = effects;
        let (graphics, compute) = (render(&sc), render_compute(&sc));
        assert_eq!(compute.raster, Some(Raster::Compute), "{model}");
        assert!(graphics.pixels_lost_to(Reason::Grazing) > 0, "{model}: grazing drops pixels");
        assert_eq!(compute.reason, graphics.reason, "{model}: reasons");
        assert_eq!(compute.label, graphics.label, "{model}: labels");
        let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&compute.z), bits(&graphics.z), "{model}: z");
    }
}

#[test]
fn the_compute_rasterizer_renders_both_views_in_one_pass() {
    let s = centred_sensor(96, 80, 0.035, [0.1, 0.0], 45.0);
    let names = |mode| {
        let out = render_compute(&scene(s, mode, &[("builtin:sphere:64", DMat4::IDENTITY)]));
        assert_eq!(out.raster, Some(Raster::Compute));
        out.timings.iter().map(|t| t.name).collect::<Vec<_>>()
    };
    assert_eq!(names(ShadowMode::Depth), ["range and shadow", "shadow mask", "shadow mask: walks"]);
    assert_eq!(names(ShadowMode::Label), ["range and shadow", "shadow mask"]);
    assert_eq!(names(ShadowMode::None), ["range"]);
}

/// A rig's views of several objects on the compute rasterizer, in the depth test, with every
/// effect: the most passes a job records (four of coverage, the resolves, the mask's two, and
/// eight effects), every one of them timed in the render's summary.
#[test]
fn a_job_of_every_pass_times_every_pass() {
    use rangesynth::sensor::{Intrinsics, Pinhole, Sensor, View, Witness, WitnessGeometry};
    let camera = Intrinsics { width: 96, height: 80, fx: 80.0, fy: 80.0, cx: 47.5, cy: 39.5 };
    let projector = Witness {
        name: "projector".into(),
        geometry: WitnessGeometry::Pinhole {
            pose: DMat4::from_translation(DVec3::new(0.5, 0.0, 0.0)),
            intrinsics: camera,
        },
    };
    let sensor = Sensor {
        reference: View::Pinhole(Pinhole { intrinsics: camera, near: 0.0, far: f64::INFINITY }),
        witnesses: vec![projector],
    };
    let facing =
        |z: f64| DMat4::from_translation(DVec3::new(0.0, 0.0, z)) * DMat4::from_rotation_x(std::f64::consts::PI);
    let mut sc = scene(sensor, ShadowMode::Depth, &[("builtin:plane:20", facing(5.0)), ("builtin:box", facing(4.5))]);
    sc.effects = toml::from_str(
        "[quantize]\nz_step = 0.01\n[noise]\nsigma = 0.001\n[dropout]\nprobability = 0.1\n\
         [edges]\njump = 0.2\n[reflectivity]\nthreshold = 0.1\n[range]\nmax_z = 9\n\
         [grazing]\nmax_incidence_deg = 80\n[disparity]\nbaseline = 0.075\nfocal_px = 80\nsubpixel = 8\n",
    )
    .expect("effects");
    let out = render_compute(&sc);
    assert_eq!(out.raster, Some(Raster::Compute));
    let names: Vec<&str> = out.timings.iter().map(|t| t.name).collect();
    let passes = [
        "coverage: set-up",
        "coverage",
        "coverage: large triangles",
        "coverage: ties",
        "range",
        "shadow mask",
        "shadow mask: walks",
    ];
    // Every effect after them, in their order (tests/effects.rs holds the order).
    let effects = rangesynth::effects::EFFECT_ORDER.map(|effect| effect.pass_name());
    assert_eq!(names, [passes.as_slice(), effects.as_slice()].concat());
}

#[test]
fn views_too_large_for_their_visibility_words_stay_on_the_graphics_path() {
    let range = COMPUTE.renderer().context().max_storage_buffer_range();
    // The smallest square range view whose 8-byte words exceed what the device binds as one
    // buffer: 4,097² on lavapipe (128 MiB).
    let side = ((range / 8) as f64).sqrt().floor() as u32 + 1;
    let s = centred_sensor(side, side, 1.2 / f64::from(side), [0.0, 0.0], 45.0);
    let sc = scene(s, ShadowMode::Label, &[("builtin:sphere:64", DMat4::IDENTITY)]);
    if side > MAX_IMAGE_SIDE {
        // A device binding 4 GiB (NVIDIA's: 23,171²): no image the renderer accepts is so
        // large, and the refusal says so before any rasterizer is chosen. The graphics path
        // this test names is then never needed there.
        let e = COMPUTE.renderer().render(&sc).expect_err("beyond the largest image").to_string();
        assert!(e.contains(&format!("sides are limited to {MAX_IMAGE_SIDE}")), "{e}");
        return;
    }
    let out = render_compute(&sc);
    assert_eq!(out.raster, Some(Raster::Graphics));
    assert!(out.label.iter().any(|&l| l != 0), "in view");
}

/// A rig's depth test lists the pixels it leaves to walk from in a buffer of 4 bytes a pixel,
/// as large as the shadowed labels, which the device binds for any image the renderer accepts
/// (`check_pixel_buffers`): a rig whose reference view's 8-byte words do not fit one buffer
/// (4,097² on lavapipe) still renders, on the graphics pipeline.
#[test]
fn a_rig_too_large_for_its_visibility_words_tests_its_depth_all_the_same() {
    use rangesynth::sensor::{Intrinsics, Pinhole, Sensor, View, Witness, WitnessGeometry};
    let range = COMPUTE.renderer().context().max_storage_buffer_range();
    let side = ((range / 8) as f64).sqrt().floor() as u32 + 1;
    if side > MAX_IMAGE_SIDE {
        // A device binding more (NVIDIA's 4 GiB): no accepted image comes near its limit.
        return;
    }
    let half = f64::from(side) / 2.0 - 0.5;
    let camera = Intrinsics { width: side, height: side, fx: f64::from(side), fy: f64::from(side), cx: half, cy: half };
    let projector = Witness {
        name: "projector".into(),
        geometry: WitnessGeometry::Pinhole {
            pose: DMat4::from_translation(DVec3::new(0.5, 0.0, 0.0)),
            intrinsics: Intrinsics { width: 256, height: 256, fx: 256.0, fy: 256.0, cx: 127.5, cy: 127.5 },
        },
    };
    let sensor = Sensor {
        reference: View::Pinhole(Pinhole { intrinsics: camera, near: 0.0, far: f64::INFINITY }),
        witnesses: vec![projector],
    };
    let pose = DMat4::from_translation(DVec3::new(0.0, 0.0, 6.0)) * DMat4::from_rotation_x(std::f64::consts::PI);
    let out = render_compute(&scene(sensor, ShadowMode::Depth, &[("builtin:box", pose)]));
    assert_eq!(out.raster, Some(Raster::Graphics));
    assert!(out.label.iter().any(|&l| l != 0), "in view");
}

/// Views of two to four objects: their draws share the view's words, and the ties between
/// them go to the lower label as the graphics path's ties pass decides them (draw.rs), among
/// them coincident faces (two boxes whose tops overlap in one plane, listed either way), an
/// object inside another, and a dense sphere behind a plane. Five objects stay on the
/// graphics path.
#[test]
fn both_rasterizers_render_identical_images_of_several_objects() {
    let lean = DMat4::from_rotation_x(0.5) * DMat4::from_rotation_y(-0.35);
    let shifted = lean * DMat4::from_translation(DVec3::new(0.45, 0.3, 0.0)) * DMat4::from_rotation_z(0.3);
    let back = DMat4::from_translation(DVec3::new(0.0, 0.0, -0.9));
    let scenes: [&[(&str, DMat4)]; 5] = [
        &[("builtin:box", lean), ("builtin:box", shifted)],
        &[("builtin:box", shifted), ("builtin:box", lean)],
        &[("builtin:sphere:64", turned()), ("builtin:box", DMat4::from_translation(DVec3::new(0.3, 0.0, 0.1)))],
        &[("builtin:plane:6", DMat4::IDENTITY), ("builtin:sphere:320", back), ("builtin:cylinder:48", shifted)],
        &[
            ("builtin:step", turned()),
            ("builtin:box", shifted),
            ("builtin:sphere:16", DMat4::from_translation(DVec3::new(-0.8, 0.8, -0.2))),
            ("builtin:box", lean * DMat4::from_rotation_z(0.8)),
        ],
    ];
    for (k, objects) in scenes.into_iter().enumerate() {
        for (theta, mode) in [(30.0, ShadowMode::Depth), (-30.0, ShadowMode::Label), (20.0, ShadowMode::None)] {
            let sc = scene(centred_sensor(96, 96, 0.03, [0.1, 0.1], theta), mode, objects);
            let name = format!("scene {k} θ = {theta} {mode:?}");
            let (graphics, compute) = (render(&sc), render_compute(&sc));
            assert_eq!(compute.raster, Some(Raster::Compute), "{name}");
            // Every object in view: a label of each object's surfaces (its base + 1 to its count).
            let bases = sc.label_bases().expect("labels");
            for (object, base) in sc.objects.iter().zip(bases) {
                let own = base + 1..=base + object.mesh.surface_count();
                let seen = graphics.label_unshadowed.iter().any(|label| own.contains(label));
                assert!(seen, "{name}: {} in view", object.model_ref);
            }
            assert_same_images(&name, &graphics, &compute);
        }
    }
    let five = [("builtin:box", DMat4::IDENTITY); 5];
    let sc = scene(centred_sensor(64, 64, 0.06, [0.0, 0.0], 45.0), ShadowMode::Depth, &five);
    let out = render_compute(&sc);
    assert_eq!(out.raster, Some(Raster::Graphics));
    assert_eq!(out.label, render(&sc).label);
}

#[test]
fn auto_takes_the_rasterizer_its_devices_crossover_picks() {
    assert_eq!(Raster::default(), Raster::Auto);
    let s = centred_sensor(96, 80, 0.035, [0.1, 0.0], 45.0);
    let wide = centred_sensor(160, 160, 0.05, [0.0, 0.0], 45.0);
    // Footprints with their 2-pixel margins (bounding spheres of radius 0.5, the box's 0.87):
    // in `s` a sphere's about 33² pixels, so 3,968 triangles are 3.6 a pixel and 224 are 0.2;
    // in `wide` the box's about 40² pixels, so 12 triangles are 0.0075 a pixel, and the plane's
    // 2 triangles fill the image, 0.00008 a pixel. A CPU device takes compute from 0.0001 a
    // pixel; a GPU from 1,500 triangles, or under 0.004 a pixel (Crossover). A view of up to
    // four objects counts all their triangles over all their footprints.
    let cpu = AUTO.renderer().context().is_cpu();
    let either = |on_cpu: Raster, on_gpu: Raster| if cpu { on_cpu } else { on_gpu };
    let (compute, graphics) = (Raster::Compute, Raster::Graphics);
    for (sensor, objects, expected) in [
        (s, vec![("builtin:sphere:64", DMat4::IDENTITY)], compute),
        (s, vec![("builtin:sphere:16", DMat4::IDENTITY)], either(compute, graphics)),
        (wide, vec![("builtin:box", turned())], either(compute, graphics)),
        (wide, vec![("builtin:plane:10", DMat4::IDENTITY)], either(graphics, compute)),
        (s, vec![("builtin:sphere:64", DMat4::IDENTITY), ("builtin:plane:6", DMat4::IDENTITY)], compute),
        // More draws than a coverage dispatch's members.
        (s, vec![("builtin:sphere:64", DMat4::IDENTITY); 5], graphics),
    ] {
        let sc = scene(sensor, ShadowMode::Depth, &objects);
        let auto = render_with(&AUTO, &sc);
        assert_eq!(auto.raster, Some(expected), "{objects:?}");
        assert!(auto.label == render(&sc).label, "{objects:?}: the same image as the graphics pipeline's");
    }
}

#[test]
fn verification_counts_are_the_same_bits_with_either_rasterizer() {
    let s = centred_sensor(160, 160, 0.045, [0.0, 0.0], 45.0);
    let step = DMat4::from_translation(DVec3::new(0.3, -0.2, 0.0)) * DMat4::from_rotation_z(0.44);
    let sensed_image =
        rangesynth::io::RangeImage::from(&render(&scene(s, ShadowMode::Depth, &[("builtin:step", step)])));
    let sensed = SensedImage::new(&sensed_image, &s.into()).unwrap();
    let hypotheses = |verifier: &Verifier| -> Vec<Hypothesis> {
        // The plane fills the image: 2 triangles over 25,600 pixels, below a CPU device's
        // crossover; the box, 12 triangles over about 44² pixels, is in a GPU's graphics band.
        ["builtin:step", "builtin:sphere:100", "builtin:box", "builtin:plane:8"]
            .iter()
            .enumerate()
            .flat_map(|(m, model)| {
                let model = verifier.model(model, Path::new(".")).unwrap();
                let bindings = if model.mesh.surface_count() > 1 { vec![(1, 1), (2, 1)] } else { vec![(1, 1)] };
                (0..4).map(move |k| {
                    // One sphere far outside the image: its footprint misses it, so it records
                    // no passes, and the hypotheses after it take the next slots.
                    let away = if (m, k) == (1, 2) { DVec3::new(50.0, 0.0, 0.0) } else { DVec3::ZERO };
                    Hypothesis {
                        id: format!("{m}-{k}"),
                        model: model.clone(),
                        pose: DMat4::from_translation(away) * step * DMat4::from_rotation_z(0.05 * f64::from(k)),
                        bindings: bindings.clone(),
                    }
                })
            })
            .collect()
    };
    // Chunks of 5 hypotheses of four models, the first four of a chunk in one coverage
    // dispatch where it is grouped, the fifth alone; the shadow mask resolves each one's range view,
    // or without shadows the resolve pass does. Scoring the unshadowed labels as well reads
    // the range view's labels, and so do effects (the grazing angle its gradient, the edges
    // its labels); without either, the mask writes only its z (MaskVariant).
    let effects: Effects = toml::from_str("[grazing]\nmax_incidence_deg = 70\n[edges]\njump = 0.2").unwrap();
    let plain = || [true, false].map(|compare_shadow| (compare_shadow, Effects::default()));
    let cases = [ShadowMode::Depth, ShadowMode::Label, ShadowMode::None]
        .into_iter()
        .flat_map(|mode| plain().map(|case| (mode, case)))
        .chain([(ShadowMode::Depth, (false, effects))]);
    for (mode, (compare_shadow, effects)) in cases {
        let settings = VerifySettings {
            sensor: s.into(),
            shadow: ShadowSettings::of(mode),
            effects,
            tolerance: 0.05,
            compare_shadow,
            chunk_size: 5,
        };
        let counts = |verifier: &Verifier| {
            let out = verifier.verify(&sensed, &settings, &hypotheses(verifier), &mut |_| {}).unwrap();
            let messages = verifier.renderer().context().take_validation_messages();
            assert!(messages.is_empty(), "validation: {}", messages.join("\n"));
            out.into_iter().map(|v| (v.counts, v.unshadowed.map(|(c, _)| c))).collect::<Vec<_>>()
        };
        let graphics = counts(&VERIFIER);
        let far = &graphics[6].0;
        assert_eq!((far.n1_plus, far.n1_minus, far.n0), (0, 0, 0), "the sphere far outside the image renders nothing");
        assert_eq!(counts(&COMPUTE), graphics, "{mode:?}, compare_shadow {compare_shadow}, {:?}", settings.effects);
        // Auto mixes both in one batch: the plane by graphics on a CPU device, the box on a GPU,
        // the others by compute.
        assert_eq!(counts(&AUTO), graphics, "{mode:?}, compare_shadow {compare_shadow}, {:?}", settings.effects);
        // Hypotheses of different models in one coverage dispatch; with auto, some of a
        // dispatch's members by graphics.
        for grouped in GROUPED.iter() {
            let raster = grouped.renderer().raster();
            assert_eq!(counts(grouped), graphics, "{mode:?}, compare_shadow {compare_shadow}, {raster:?}, grouped");
        }
    }
}

#[test]
fn an_open_mesh_shows_its_inside_to_the_compute_rasterizer() {
    // A unit box without its top, seen from above: the floor's normal points down, away from
    // the camera, yet the camera sees it through the opening. Only a solid's triangles facing
    // away may be skipped (src/mesh/solid.rs); this mesh is open, so none are.
    let positions =
        (0..8).map(|i| [(i & 1) as f64 - 0.5, ((i >> 1) & 1) as f64 - 0.5, ((i >> 2) & 1) as f64]).collect();
    let (floor, walls) = ([[0, 2, 3, 1]], [[0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]);
    let quads = floor.iter().map(|q| (1, q)).chain(walls.iter().map(|q| (2, q)));
    let (mut triangles, mut surfaces) = (Vec::new(), Vec::new());
    for (surface, &[a, b, c, d]) in quads {
        triangles.extend([[a, b, c], [a, c, d]]);
        surfaces.extend([surface; 2]);
    }
    let mesh = Mesh::new("open box", positions, triangles, surfaces, vec!["floor".into(), "walls".into()]).unwrap();
    assert_eq!(mesh.solidity(), Solidity::Open);
    let mut sc = scene(centred_sensor(48, 48, 0.05, [0.0, 0.0], 0.0), ShadowMode::None, &[]);
    sc.objects.push(SceneObject {
        model_ref: "open box".into(),
        mesh: Arc::new(mesh),
        pose: DMat4::from_translation(DVec3::new(0.0, 0.0, 0.25)),
        reflectivity: None,
    });
    let out = render_compute(&sc);
    assert_eq!(out.raster, Some(Raster::Compute));
    let s = sc.sensor.scanner().unwrap();
    let mut inside = 0;
    for row in 0..s.height {
        for col in 0..s.width {
            let (x, y) = s.pixel_centre(col, row);
            if x.abs() < 0.45 && y.abs() < 0.45 {
                let i = (row * s.width + col) as usize;
                assert_eq!((out.label[i], out.z[i]), (1, 0.25), "pixel ({col}, {row}) sees the floor at z = 0.25");
                inside += 1;
            }
        }
    }
    assert!(inside > 300, "{inside} pixels inside the walls");
    assert_eq!(out.label, render(&sc).label, "the graphics pipeline's image");
}

/// `count` spikes entering a 64² view from outside it: each has one corner at x = `tip`, left
/// of the view, and two inside, so its box within the view is small while a corner lies far
/// from it, which the small triangles' pass leaves to the queue of large triangles
/// (shaders/raster/raster.comp). Spike i lies nearer than spike i − 1 where both are, by far more
/// than rounding. Returns the scene, without a shadow view (a far tip makes the scene too deep
/// for one), and what the graphics pipeline renders.
fn spikes(count: u32, tip: f32) -> (Scene, RenderOutput) {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for i in 0..count {
        // Bases spread over the view by a low-discrepancy sequence.
        let (u, v) = ((i as f32 * 0.618_034).fract(), (i as f32 * 0.754_877_7).fract());
        let (x, y, z) = (-0.9 + 1.4 * u, -0.9 + 1.8 * v, 0.001 * i as f32);
        let corners: [[f32; 3]; 3] = [[tip, 3.0 * y, z], [x, y - 0.03, z], [x, y + 0.03, z]];
        positions.extend(corners.map(|c| c.map(f64::from)));
        triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let surfaces = vec![1; triangles.len()];
    let mesh = Mesh::new("spikes", positions, triangles, surfaces, vec!["spikes".into()]).unwrap();
    let mut sc = scene(centred_sensor(64, 64, 0.035, [0.0, 0.0], 0.0), ShadowMode::None, &[]);
    sc.objects.push(SceneObject {
        model_ref: "spikes".into(),
        mesh: Arc::new(mesh),
        pose: DMat4::IDENTITY,
        reflectivity: None,
    });
    let graphics = render(&sc);
    assert!(graphics.label_unshadowed.iter().filter(|&&l| l != 0).count() > 300, "in view");
    (sc, graphics)
}

fn assert_renders_as(compute: &RenderOutput, graphics: &RenderOutput) {
    assert_eq!(compute.raster, Some(Raster::Compute));
    assert!(compute.label_unshadowed == graphics.label_unshadowed, "labels");
    assert!(compute.label == graphics.label, "shadowed labels");
    let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert!(bits(&compute.z) == bits(&graphics.z), "z");
}

/// Tips 2,000,000 pixels away, just within the compute rasterizer's reach
/// (`render::MAX_REACH_PIXELS`, 2^21): the large triangles' 64-bit edge functions stay exact.
#[test]
fn spikes_from_the_edge_of_the_compute_rasterizers_reach_render_as_the_graphics_pipeline_renders_them() {
    let (sc, graphics) = spikes(12, -70_000.0);
    assert_renders_as(&render_compute(&sc), &graphics);
}

/// A plane reaching 7 million pixels past a 64² view in every direction: beyond the compute
/// rasterizer's reach its edge functions overflowed (at 25 million pixels it rendered
/// nothing, every pixel empty); such a draw is left to the graphics pipeline, which renders
/// the plane everywhere. (A model reaching farther than MAX_SEEN_REACH_PIXELS from a view it
/// shows in is refused: tests/f32_boundaries.rs.)
#[test]
fn a_model_reaching_beyond_the_compute_rasterizers_reach_stays_on_the_graphics_path() {
    let s = centred_sensor(64, 64, 0.02, [0.0, 0.0], 0.0);
    let sc = scene(s, ShadowMode::None, &[("builtin:plane:200000", DMat4::from_rotation_z(0.14))]);
    let (centre, radius) = sc.objects[0].mesh.bounding_sphere();
    let reach = (centre.x.abs() + radius) / 0.02;
    assert!(reach > 3.0 * MAX_REACH_PIXELS && reach < MAX_SEEN_REACH_PIXELS, "7 million pixels: {reach}");
    let out = render_compute(&sc);
    assert!(out.label.iter().all(|&l| l == 1), "the plane everywhere");
    assert_eq!(out.label, render(&sc).label);
    assert_eq!(out.raster, Some(Raster::Graphics));
}

/// More queued triangles than one indirect dispatch has workgroups (65,535): the large
/// triangles' workgroups stride over the rest of the queue. Tips 54 pixels left of the view.
#[test]
fn a_queue_longer_than_a_dispatch_is_covered_whole() {
    let (sc, graphics) = spikes(70_000, -3.0);
    assert_renders_as(&render_compute(&sc), &graphics);
}

/// Triangles crossing the view's edge. The graphics pipeline clips a triangle that crosses its
/// viewport's edge (lavapipe has no guard band with a depth attachment bound) and snaps the
/// corners the clipper makes anew, which moves the kept part's edges by up to a snapping step;
/// the compute rasterizer covers the whole triangle. When the viewport was the view itself,
/// these differed: the step's shadow view, where the centre of pixel (96, 94) lies 0.0012
/// pixel inside the edge of a triangle that crosses the view's right edge (one shadowed label);
/// 5,000 spikes from 57,000 pixels left of the view (edge functions past 32 bits in their
/// boxes), their depths 0.001 apart (3 of 2,477 pixels kept another spike: z differs); and
/// 5,000 from about 250 pixels (1 pixel). The viewport is now 16,384 pixels a side on
/// lavapipe (src/render/raster/draw.rs, `ViewportFrame`): a spike from 57,000 pixels away is still
/// clipped, 8,192 pixels from the view's centre, where moving its corner by a snapping step
/// moves its edge in the view by a hundredth of that or less. The viewport's centre is the
/// view's rounded down to a whole pixel, so a view of an odd number of pixels a side is
/// rendered too.
#[test]
fn triangles_crossing_the_views_edge_render_as_the_graphics_pipeline_renders_them() {
    let lean = DMat4::from_rotation_x(0.5) * DMat4::from_rotation_y(-0.35);
    for (width, height) in [(96, 96), (95, 97)] {
        let sensor = centred_sensor(width, height, 0.03, [0.1, 0.1], -30.0);
        let step = scene(sensor, ShadowMode::Label, &[("builtin:step", lean)]);
        let (compute, graphics) = (render_compute(&step), render(&step));
        assert!(graphics.label.iter().filter(|&&l| l != 0).count() > 1000, "the step in view");
        assert_renders_as(&compute, &graphics);
    }
    for tip in [-2000.0, -10.0] {
        let (sc, graphics) = spikes(5_000, tip);
        assert_renders_as(&render_compute(&sc), &graphics);
    }
}

#[test]
fn a_solid_wound_inward_renders_as_the_graphics_pipeline_renders_it() {
    // The built-in box with every triangle turned over: still a solid, its normals pointing in,
    // so the compute rasterizer skips the triangles whose normals face the camera.
    let mut mesh = builtin_mesh("builtin:box").unwrap();
    for triangle in &mut mesh.triangles {
        triangle.swap(1, 2);
    }
    assert_eq!(mesh.solidity(), Solidity::Inward);
    let mut sc = scene(centred_sensor(96, 80, 0.035, [0.1, 0.0], 45.0), ShadowMode::Depth, &[]);
    sc.objects.push(SceneObject {
        model_ref: "box, inside out".into(),
        mesh: Arc::new(mesh),
        pose: turned(),
        reflectivity: None,
    });
    let (compute, graphics) = (render_compute(&sc), render(&sc));
    assert_eq!(compute.raster, Some(Raster::Compute));
    assert!(graphics.label_unshadowed.iter().filter(|&&l| l != 0).count() > 500, "in view");
    assert!(compute.label_unshadowed == graphics.label_unshadowed, "labels");
    assert!(compute.label == graphics.label, "shadowed labels");
    let bits = |z: &[f32]| z.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert!(bits(&compute.z) == bits(&graphics.z), "z");
}

/// Asserts that the graphics pipeline's and the compute rasterizer's renders of one scene are
/// the same images. On lavapipe, every label, shadowed label and z bit. A GPU's rasterizer may
/// work a triangle's depth out from its snapped corners (NVIDIA's does), where the compute
/// rasterizer takes the unsnapped plane: where two surfaces lie within those roundings of each
/// other in depth (up to the depth change over 1/256 pixel), each may keep another. So on a GPU
/// a label or shadowed label may differ within one pixel of a change of label in either render
/// (a boundary moved by a fraction of a pixel), at most one pixel in 1,000 of the view, and z
/// only where the label differs. (On an NVIDIA H200, 2026-11-26: one pixel, in all this suite's
/// renders.)
fn assert_same_images(name: &str, graphics: &RenderOutput, compute: &RenderOutput) {
    describe_differences(name, graphics, compute);
    let (w, h) = (graphics.width() as usize, graphics.height() as usize);
    let exact = COMPUTE.renderer().context().is_cpu();
    let differ = |a: &[u32], b: &[u32]| (0..w * h).filter(|&i| a[i] != b[i]).collect::<Vec<_>>();
    for (what, g, c) in [
        ("labels", &graphics.label_unshadowed, &compute.label_unshadowed),
        ("shadowed labels", &graphics.label, &compute.label),
    ] {
        let at = differ(g, c);
        if exact {
            assert_eq!(at.len(), 0, "{name}: {what}");
            continue;
        }
        let (near_g, near_c) = (near_label_change(g, w, h), near_label_change(c, w, h));
        assert!(at.iter().all(|&i| near_g[i] || near_c[i]), "{name}: {what} differ away from a change of label");
        assert!(at.len() * 1000 <= w * h, "{name}: {what}: {} pixels differ", at.len());
    }
    let z_differs_alone = (0..w * h).any(|i| {
        graphics.z[i].to_bits() != compute.z[i].to_bits() && graphics.label_unshadowed[i] == compute.label_unshadowed[i]
    });
    assert!(!z_differs_alone, "{name}: z differs where the labels do not");
}

/// Prints where two renders of one scene differ (at most 12 pixels): the graphics pipeline's
/// label, shadowed label and z, then the compute rasterizer's, so that a failure on another
/// device says where to look.
fn describe_differences(name: &str, graphics: &RenderOutput, compute: &RenderOutput) {
    let width = graphics.width() as usize;
    let differs = |i: &usize| {
        graphics.label_unshadowed[*i] != compute.label_unshadowed[*i]
            || graphics.label[*i] != compute.label[*i]
            || graphics.z[*i].to_bits() != compute.z[*i].to_bits()
    };
    let at: Vec<usize> = (0..graphics.label.len()).filter(differs).collect();
    if at.is_empty() {
        return;
    }
    eprintln!("{name}: {} pixels differ (col, row: label, shadowed, z graphics | compute):", at.len());
    for &i in at.iter().take(12) {
        let one = |out: &RenderOutput| format!("{} {} {:e}", out.label_unshadowed[i], out.label[i], out.z[i]);
        eprintln!("  {}, {}: {} | {}", i % width, i / width, one(graphics), one(compute));
    }
}

/// A rig's pinhole views (src/render/raster/compute/rig.rs): the reference view and every
/// witness's band, pinhole and directional, in modes `none`, `label` and `depth`, draw the same
/// labels, shadowed labels, z bits and witness bits with either rasterizer (on lavapipe; a GPU
/// as `assert_same_images` allows). The example rigs' scenes (a floor the near plane cuts, four
/// objects sharing the views' words, lamps), the Kinect rig without a near limit (its floor
/// reaching behind the camera and the projector: the compute rasterizer clips it to the
/// viewport as the graphics pipeline does) and with its near plane through a face, and a
/// camera inside a box.
#[test]
fn both_rasterizers_draw_identical_rigs() {
    let rigs = Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs");
    let example = |name: &str| Scene::from_file(&rigs.join(format!("{name}.toml")), &Default::default()).unwrap();
    let mut scenes: Vec<(String, Scene)> =
        ["kinect-v1", "kinect-v1-registered", "photometric-stereo", "realsense-d435"]
            .into_iter()
            .map(|name| (name.to_string(), example(name)))
            .collect();
    let mut unlimited = example("kinect-v1");
    if let rangesynth::sensor::View::Pinhole(p) = &mut unlimited.sensor.reference {
        p.near = 0.0;
    }
    scenes.push(("kinect-v1 without a near limit".into(), unlimited.clone()));
    // Its near plane through the cylinder's cap (at 0.9), a far plane beyond: a face lying in
    // the near plane is kept or cut as the clipper keeps or cuts it.
    let mut capped = unlimited.clone();
    if let rangesynth::sensor::View::Pinhole(p) = &mut capped.sensor.reference {
        (p.near, p.far) = (0.9, 1.5);
    }
    scenes.push(("kinect-v1, its near plane through the cylinder's cap".into(), capped));
    let mut inside = unlimited;
    let around = builtin_mesh("builtin:box").unwrap().scaled(3.0, &Default::default()).unwrap();
    inside.objects.truncate(3);
    inside.objects.push(SceneObject { mesh: Arc::new(around), ..inside.objects[0].clone() });
    inside.objects.last_mut().unwrap().pose = DMat4::from_translation(DVec3::new(0.1, 0.05, 0.4));
    scenes.push(("the Kinect rig inside a box".into(), inside));
    // Each model alone: views of one draw, where the compute rasterizer's depth test skips its
    // walks from the model's hull faces (src/mesh/hull_faces.rs) and the graphics pipeline's
    // does not. The cylinder's side lies along the camera's rays, its gradient clamped.
    for rig in ["kinect-v1", "photometric-stereo"] {
        let whole = example(rig);
        for (i, object) in whole.objects.iter().enumerate().skip(1) {
            let alone = Scene { objects: vec![object.clone()], ..whole.clone() };
            scenes.push((format!("{rig}, its object {i} alone"), alone));
        }
    }
    for (name, scene) in scenes {
        for mode in [ShadowMode::None, ShadowMode::Label, ShadowMode::Depth] {
            let mut scene = scene.clone();
            scene.shadow.mode = mode;
            let graphics = render(&scene);
            let compute = render_compute(&scene);
            let name = format!("{name}, mode {mode:?}");
            assert_eq!(graphics.raster, Some(Raster::Graphics), "{name}");
            assert_eq!(compute.raster, Some(Raster::Compute), "{name}");
            assert!(graphics.label.iter().any(|&l| l != 0), "{name}: in view");
            assert_same_images(&name, &graphics, &compute);
            if COMPUTE.renderer().context().is_cpu() {
                let differ = (0..graphics.witness.len()).filter(|&i| graphics.witness[i] != compute.witness[i]).count();
                assert_eq!(differ, 0, "{name}: witness bits");
            }
        }
    }
}

/// Coincident faces of two objects that the near plane cuts, in a pinhole view, go to the lower
/// label alike on both rasterizers: a floor under the Kinect rig without a near limit, reaching
/// behind the camera (so that the clipper cuts its triangles there), and the same floor turned
/// about its normal (other triangles, other roundings). The compute rasterizer queues the
/// triangles the clipper cuts apart from the others (raster.comp, `LargeArgs`), and its ties
/// pass takes them too.
#[test]
fn coincident_floors_the_near_plane_cuts_tie_alike_on_both_rasterizers() {
    let rigs = Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs");
    let mut floors = Scene::from_file(&rigs.join("kinect-v1.toml"), &Default::default()).unwrap();
    if let rangesynth::sensor::View::Pinhole(p) = &mut floors.sensor.reference {
        p.near = 0.0;
    }
    floors.shadow.mode = ShadowMode::None;
    // A floor 0.3 below the camera (y down), 10 units a side, centred on the camera's plane.
    let wide = builtin_mesh("builtin:plane:20").unwrap().scaled(10.0, &Default::default()).unwrap();
    let under =
        DMat4::from_translation(DVec3::new(0.0, 0.3, 0.0)) * DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2);
    let floor = SceneObject { mesh: Arc::new(wide), pose: under, ..floors.objects[0].clone() };
    let turned = SceneObject { pose: floor.pose * DMat4::from_rotation_z(0.3), ..floor.clone() };
    for (name, objects) in [("the floor first", [floor.clone(), turned.clone()]), ("turned first", [turned, floor])] {
        floors.objects = objects.to_vec();
        let graphics = render(&floors);
        let compute = render_compute(&floors);
        assert_eq!(compute.raster, Some(Raster::Compute), "{name}");
        let seen = graphics.label_unshadowed.iter().filter(|&&l| l != 0).count();
        assert!(seen > graphics.label_unshadowed.len() / 4, "{name}: the floor is seen ({seen} pixels)");
        // Toward the horizon, where the floor's faces lie nearly along the rays, a few pixels'
        // depths part by more than the tie tolerance (137 of 152,457 in one order, on both).
        let higher = compute.label_unshadowed.iter().filter(|&&l| l > 1).count();
        assert!(higher * 1000 <= seen, "{name}: {higher} of {seen} pixels show the higher label");
        assert_same_images(name, &graphics, &compute);
    }
}

/// `auto` under a rig follows the rigs' crossover (`Renderer::rig_crossover`): on a CPU device,
/// in the label test, the graphics pipeline for the Kinect rig's box alone (12 triangles over
/// some 14,000 pixels, which the scanner's rule would give the compute rasterizer) and the
/// compute rasterizer for a dense ball; in the depth test, the compute rasterizer for the box
/// alone too, as the scanner's rule gives it (a GPU takes its own rule, compute for all); the
/// images the same either way.
#[test]
fn auto_under_a_rig_follows_the_rigs_crossover() {
    let rigs = Path::new(env!("CARGO_MANIFEST_DIR")).join("rigs");
    let mut boxed = Scene::from_file(&rigs.join("kinect-v1.toml"), &Default::default()).unwrap();
    boxed.shadow.mode = ShadowMode::Label;
    boxed.objects = vec![boxed.objects[1].clone()];
    let mut ball = boxed.clone();
    let dense = builtin_mesh("builtin:sphere:100").unwrap().scaled(0.1, &Default::default()).unwrap();
    ball.objects[0].mesh = Arc::new(dense);
    ball.objects[0].pose = DMat4::from_translation(DVec3::new(0.0, 0.0, 0.8));
    let mut boxed_depth = boxed.clone();
    boxed_depth.shadow.mode = ShadowMode::Depth;
    let cpu = AUTO.renderer().context().is_cpu();
    let cases = [
        ("the box", &boxed, Raster::Graphics),
        ("a ball", &ball, Raster::Compute),
        ("the box in the depth test", &boxed_depth, Raster::Compute),
    ];
    for (name, scene, on_cpu) in cases {
        let auto = render_with(&AUTO, scene);
        let expected = if cpu { on_cpu } else { Raster::Compute };
        assert_eq!(auto.raster, Some(expected), "{name}");
        assert_same_images(name, &render(scene), &auto);
    }
}
