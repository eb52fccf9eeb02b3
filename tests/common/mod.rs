//! Shared test harness: one renderer per test binary with validation (synchronization
//! validation included) always on; any validation message fails the test that sees it.
//! There is no skipping: without a Vulkan device, `renderer()` panics and the test fails.
//! When `RANGESYNTH_EXPECT_DEVICE` is set (CI sets "llvmpipe"), the device must match it.
#![allow(dead_code)]

pub mod bop_dataset;
pub mod cli;
pub mod compare;
pub mod counting;
pub mod reference;
pub mod rig_reference;
pub mod scorer;
pub mod sliver_box;

use glam::DMat4;
pub use rangesynth::effects::Effects;
use rangesynth::gpu::ContextOptions;
use rangesynth::mesh::builtin_mesh;
use rangesynth::render::Raster;
use rangesynth::scene::SceneObject;
use rangesynth::sensor::{Scanner, Sensor};
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::Verifier;
use rangesynth::{RenderOutput, Renderer, Scene};
use std::sync::{Arc, LazyLock};

/// The test binary's one verifier; its renderer is the one every GPU test uses. It keeps as
/// many slots a batch, and chunks in flight, as `RANGESYNTH_TEST_SLOTS` and
/// `RANGESYNTH_TEST_CHUNKS_IN_FLIGHT` say (the device's defaults unless they are set:
/// tools/test.sh runs the verification suite again with a GPU's, 16 and 3).
pub static VERIFIER: LazyLock<Verifier> = LazyLock::new(|| {
    let count =
        |name: &str| std::env::var(name).ok().map(|n| n.parse().unwrap_or_else(|_| panic!("{name} is a count")));
    let mut verifier = Verifier::new(test_renderer(None)).expect("verifier");
    if let Some(n) = count("RANGESYNTH_TEST_SLOTS") {
        verifier = verifier.with_slots(n);
    }
    if let Some(n) = count("RANGESYNTH_TEST_CHUNKS_IN_FLIGHT") {
        verifier = verifier.with_chunks_in_flight(n);
    }
    verifier
});

/// A renderer for tests: validation on, on the expected device, at most the given Vulkan
/// version, with the rasterizer `RANGESYNTH_TEST_RASTER` names (`graphics` unless it is set:
/// tools/test.sh runs the conformance, stability, analytic and exact suites again with `compute`),
/// covering as many hypotheses a dispatch as `RANGESYNTH_TEST_HYPOTHESES_PER_DISPATCH` says
/// (the device's default unless it is set: tools/test.sh runs the verification suite again
/// with the compute rasterizer covering four). Panics (fails the test) without a device.
pub fn test_renderer(max_vulkan_version: Option<u32>) -> Renderer {
    // No persistent pipeline cache: what other runs left must not touch the suite's results
    // (tests/pipeline_cache.rs tests the cache, each test in a directory of its own).
    let options =
        ContextOptions { validation: true, max_vulkan_version, pipeline_cache_dir: None, ..ContextOptions::from_env() };
    let renderer = Renderer::new(&options)
        .unwrap_or_else(|e| panic!("GPU tests need a Vulkan device with validation layers: {e}"));
    let name = renderer.context().device_name().to_string();
    if let Ok(expected) = std::env::var("RANGESYNTH_EXPECT_DEVICE") {
        assert!(name.contains(&expected), "tests ran on {name:?}, expected a device named {expected:?}");
    }
    assert!(renderer.context().validation_enabled());
    let raster = std::env::var("RANGESYNTH_TEST_RASTER").map_or(Ok(Raster::Graphics), |name| name.parse());
    let renderer = renderer.with_raster(raster.expect("RANGESYNTH_TEST_RASTER names a rasterizer"));
    match std::env::var("RANGESYNTH_TEST_HYPOTHESES_PER_DISPATCH") {
        Ok(n) => renderer
            .with_hypotheses_per_dispatch(n.parse().expect("RANGESYNTH_TEST_HYPOTHESES_PER_DISPATCH is a count")),
        Err(_) => renderer,
    }
}

/// The pairs of two lists compared element by element, after asserting they are as long: a
/// truncated result must not pass as a match.
pub fn paired<'a, A, B>(a: &'a [A], b: &'a [B]) -> impl Iterator<Item = (&'a A, &'a B)> {
    assert_eq!(a.len(), b.len(), "the lists compared differ in length");
    a.iter().zip(b)
}

pub fn renderer() -> &'static Renderer {
    VERIFIER.renderer()
}

/// Fails the calling test if validation reported anything.
pub fn assert_no_validation_messages() {
    let messages = renderer().context().take_validation_messages();
    assert!(messages.is_empty(), "validation reported {} message(s):\n{}", messages.len(), messages.join("\n"));
}

/// The rasterizer the suite's renderer draws a view of one to four objects with, on the GPU:
/// the compute rasterizer in a run with it (RANGESYNTH_TEST_RASTER), else the graphics
/// pipeline.
#[allow(dead_code)]
pub fn gpu_raster() -> Raster {
    match renderer().raster() {
        Raster::Compute => Raster::Compute,
        _ => Raster::Graphics,
    }
}

pub fn render(scene: &Scene) -> RenderOutput {
    let out = renderer().render(scene).unwrap_or_else(|e| panic!("render failed: {e}"));
    assert_no_validation_messages();
    // A suite run with the compute rasterizer renders every view of one to four objects with it
    // (a rig's pinhole views too).
    let objects = (1..=rangesynth::render::COVERAGE_MEMBERS).contains(&scene.objects.len());
    let on_gpu = scene.shadow.mode != rangesynth::shadow::ShadowMode::Exact && out.raster.is_some();
    if renderer().raster() == Raster::Compute && objects && on_gpu {
        assert_eq!(out.raster, Some(Raster::Compute), "the compute rasterizer rendered the view");
    }
    out
}

pub fn sensor(width: u32, height: u32, pitch: f64, origin: [f64; 2], theta_deg: f64) -> Scanner {
    Scanner { width, height, pitch: [pitch, pitch], origin, theta_deg }
}

/// A sensor of `width`×`height` pixels centred on (cx, cy).
pub fn centred_sensor(width: u32, height: u32, pitch: f64, centre: [f64; 2], theta_deg: f64) -> Scanner {
    let origin =
        [centre[0] - (f64::from(width) - 1.0) / 2.0 * pitch, centre[1] + (f64::from(height) - 1.0) / 2.0 * pitch];
    sensor(width, height, pitch, origin, theta_deg)
}

pub fn scene(sensor: impl Into<Sensor>, mode: ShadowMode, objects: &[(&str, DMat4)]) -> Scene {
    Scene {
        sensor: sensor.into(),
        shadow: ShadowSettings::of(mode),
        effects: Effects::default(),
        objects: objects
            .iter()
            .map(|&(model, pose)| SceneObject {
                model_ref: model.to_string(),
                mesh: Arc::new(builtin_mesh(model).expect("built-in model")),
                pose,
                reflectivity: None,
            })
            .collect(),
    }
}
