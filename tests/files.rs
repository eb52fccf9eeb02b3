//! What is written reads back bit-identical: EXR points (NaN included), u32 labels above 2^24,
//! the sensor settings in the header, and labels.json; and the same image is written as the
//! same bytes.

mod common;

use common::*;
use glam::DMat4;
use rangesynth::io::{read_label_image, read_range_image, write_label_image, write_range_image, RangeImage};
use rangesynth::limits::Ledger;
use rangesynth::render_set::write_render_directory;
use rangesynth::shadow::{ShadowMode, ShadowSettings};

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn range_image_round_trips_bit_identically_with_large_labels() {
    let (w, h) = (7u32, 5u32);
    let n = (w * h) as usize;
    // Labels that a float channel would corrupt: 2^24 + 1 is not representable in f32.
    let labels: Vec<u32> = (0..n as u32)
        .map(|i| match i % 5 {
            0 => 0,
            1 => (1 << 24) + 1,
            2 => u32::MAX,
            3 => (1 << 31) + 12345,
            _ => i,
        })
        .collect();
    let coordinate = |k: u32| -> Vec<f32> {
        (0..n as u32)
            .map(|i| if labels[i as usize] == 0 { f32::NAN } else { (i * 7 + k) as f32 * 0.123_456_7 - 1.0 })
            .collect()
    };
    let image = RangeImage {
        width: w,
        height: h,
        x: coordinate(1),
        y: coordinate(2),
        z: coordinate(3),
        label: labels.clone(),
        sensor: Some(sensor(w, h, 0.25, [-1.0, 2.0], 37.5).into()),
        reason: Some((0..n as u32).map(|i| if labels[i as usize] == 0 { 1 } else { 0 }).collect()),
        witness: None,
        shadow: Some(ShadowSettings::of(ShadowMode::Depth)),
        effects: Some(toml::from_str("[noise]\nsigma = 0.25\nseed = 9\n[edges]\njump = 0.5\n").unwrap()),
    };
    let dir = temp_dir("files_round_trip");
    let path = dir.join("range.exr");
    write_range_image(&path, &image).unwrap();
    let back = read_range_image(&path, &Ledger::default()).unwrap();
    let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&back.x), bits(&image.x));
    assert_eq!(bits(&back.y), bits(&image.y));
    assert_eq!(bits(&back.z), bits(&image.z));
    assert_eq!(back.label, labels);
    assert_eq!(back.sensor, image.sensor);
    assert_eq!(back.shadow, image.shadow);
    assert_eq!(back.reason, image.reason);
    assert_eq!(back.effects, image.effects);

    let label_path = dir.join("label.exr");
    write_label_image(&label_path, w, h, &labels).unwrap();
    assert_eq!(read_label_image(&label_path, &Ledger::default()).unwrap(), (w, h, labels));

    // The same image gives the same bytes, whatever order the exr crate's HashMap of
    // attributes iterates in this time (each map is seeded afresh).
    let first = std::fs::read(&path).unwrap();
    for i in 0..8 {
        let again = dir.join(format!("again{i}.exr"));
        write_range_image(&again, &image).unwrap();
        assert!(std::fs::read(&again).unwrap() == first, "write {i} differs from the first");
    }
}

#[test]
fn a_rendered_directory_reads_back_what_was_rendered() {
    let s = centred_sensor(48, 40, 0.05, [-0.5, 0.0], 45.0);
    let sc = scene(s, ShadowMode::Depth, &[("builtin:step", DMat4::IDENTITY), ("builtin:plane:4", DMat4::IDENTITY)]);
    let out = render(&sc);
    let dir = temp_dir("files_render_dir");
    let written = write_render_directory(&dir, &sc, &out).unwrap();
    assert_eq!(written.len(), 6);
    let back = read_range_image(&dir.join("range.exr"), &Ledger::default()).unwrap();
    assert_eq!(back.label, out.label);
    for i in 0..out.label.len() {
        match out.point(i) {
            Some([x, y, z]) => {
                assert_eq!([back.x[i], back.y[i], back.z[i]].map(f32::to_bits), [x, y, z].map(f32::to_bits))
            }
            None => assert!(back.x[i].is_nan() && back.y[i].is_nan() && back.z[i].is_nan(), "pixel {i} has no data"),
        }
    }
    assert_eq!(back.sensor, Some(s.into()));
    let (_, _, unshadowed) = read_label_image(&dir.join("label_unshadowed.exr"), &Ledger::default()).unwrap();
    assert_eq!(unshadowed, out.label_unshadowed);
    let map: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("labels.json")).unwrap()).unwrap();
    let labels = map["labels"].as_array().unwrap();
    assert_eq!(labels.len(), 9, "8 step surfaces and the plane");
    assert_eq!(labels[8]["label"], 9);
    assert_eq!(labels[8]["object"], 1);
    assert_eq!(labels[8]["surface_name"], "plane");
    assert_eq!(labels[1]["surface_name"], "high_top");
    for png in ["range.png", "label.png", "label_unshadowed.png"] {
        let decoder = png::Decoder::new(std::fs::File::open(dir.join(png)).unwrap());
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (48, 40), "{png}");
    }
}
