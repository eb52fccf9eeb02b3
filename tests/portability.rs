//! The Vulkan 1.2 path (VK_KHR_dynamic_rendering and VK_KHR_synchronization2 instead of core
//! 1.3) renders and verifies exactly as the core path does, with validation clean. lavapipe
//! offers both, so capping the version at 1.2 exercises the extension path here.

mod common;

use ash::vk;
use common::*;
use glam::{DMat4, DVec3};
use rangesynth::io::RangeImage;
use rangesynth::shadow::{ShadowMode, ShadowSettings};
use rangesynth::verify::{Hypothesis, SensedImage, Verifier, VerifySettings};
use std::path::Path;

#[test]
fn the_vulkan_1_2_path_matches_the_core_path() {
    let extension_path = Verifier::new(test_renderer(Some(vk::API_VERSION_1_2))).expect("verifier");
    let ctx = extension_path.renderer().context();
    assert!(!ctx.core_vulkan_1_3(), "capped at 1.2, the extensions must be used");
    assert!(renderer().context().core_vulkan_1_3(), "lavapipe is a 1.3 device");

    let pose = DMat4::from_translation(DVec3::new(0.2, 0.1, 0.0)) * DMat4::from_rotation_z(0.4);
    for mode in [ShadowMode::Depth, ShadowMode::Label, ShadowMode::None] {
        let s = centred_sensor(96, 80, 0.05, [0.0, 0.0], 45.0);
        let sc = scene(s, mode, &[("builtin:step", pose), ("builtin:cylinder:20", DMat4::from_translation(DVec3::X))]);
        let core = render(&sc);
        let old = extension_path.renderer().render(&sc).expect("renders on the 1.2 path");
        assert_eq!(old.label, core.label, "{mode:?}");
        assert_eq!(old.label_unshadowed, core.label_unshadowed);
        assert_eq!(
            old.z.iter().map(|z| z.to_bits()).collect::<Vec<_>>(),
            core.z.iter().map(|z| z.to_bits()).collect::<Vec<_>>()
        );
        let names = |out: &rangesynth::RenderOutput| out.timings.iter().map(|t| t.name).collect::<Vec<_>>();
        assert_eq!(names(&old), names(&core));

        let sensed = SensedImage::new(&RangeImage::from(&core), &s.into()).unwrap();
        let settings = VerifySettings {
            sensor: s.into(),
            shadow: ShadowSettings::of(mode),
            effects: Default::default(),
            tolerance: 0.1,
            compare_shadow: true,
            chunk_size: 3,
        };
        let hypotheses = |v: &Verifier| -> Vec<Hypothesis> {
            (0..5)
                .map(|i| Hypothesis {
                    id: format!("h{i}"),
                    model: v.model("builtin:step", Path::new(".")).unwrap(),
                    pose: pose * DMat4::from_rotation_z(f64::from(i) * 0.05),
                    bindings: vec![(1, 1), (2, 2)],
                })
                .collect()
        };
        let a = VERIFIER.verify(&sensed, &settings, &hypotheses(&VERIFIER), &mut |_| {}).unwrap();
        let b = extension_path.verify(&sensed, &settings, &hypotheses(&extension_path), &mut |_| {}).unwrap();
        for (a, b) in common::paired(&a, &b) {
            assert_eq!(a.counts, b.counts, "{mode:?} {}", a.id);
            assert_eq!(a.scores.s.to_bits(), b.scores.s.to_bits());
        }
    }
    assert_no_validation_messages();
    let messages = ctx.take_validation_messages();
    assert!(messages.is_empty(), "validation on the 1.2 path:\n{}", messages.join("\n"));
}
