//! A BOP-format dataset the tests write (tests/bop.rs, tests/bop_memory.rs): a 100 mm box
//! (its near face at the pose's depth, centred on its x and y) under a 640×480 camera of
//! fx = fy = 500, (cx, cy) = (319.5, 239.5), with a projector beside it.

use super::cli::fresh_dir;
use glam::{DMat3, DMat4, DVec3};
use rangesynth::bop::ResultRow;
use rangesynth::io::write_depth_png;
use rangesynth::sensor::{Intrinsics, Pinhole, Sensor, View, Witness, WitnessGeometry};
use std::path::PathBuf;

pub const K: [f64; 9] = [500.0, 0.0, 319.5, 0.0, 500.0, 239.5, 0.0, 0.0, 1.0];
pub const DIAMETER: f64 = 200.0;
pub const DELTA: f64 = 15.0;

pub fn camera() -> Intrinsics {
    Intrinsics { width: 640, height: 480, fx: 500.0, fy: 500.0, cx: 319.5, cy: 239.5 }
}

/// The camera, and a projector `baseline` mm to its right with a wide image.
pub fn rig(baseline: f64) -> Sensor {
    let projector = Witness {
        name: "projector".into(),
        geometry: WitnessGeometry::Pinhole {
            pose: DMat4::from_translation(DVec3::new(baseline, 0.0, 0.0)),
            intrinsics: Intrinsics { width: 1280, cx: 639.5, ..camera() },
        },
    };
    Sensor {
        reference: View::Pinhole(Pinhole { intrinsics: camera(), near: 0.0, far: f64::INFINITY }),
        witnesses: vec![projector],
    }
}

/// The box: x and y from −50 to 50 mm, z from 0 to 100 (its near face at z = 0), as ASCII PLY.
pub fn box_ply() -> String {
    let corner =
        |i: usize| [(i & 1) as f64 * 100.0 - 50.0, ((i >> 1) & 1) as f64 * 100.0 - 50.0, ((i >> 2) & 1) as f64 * 100.0];
    let faces = [
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
    ];
    let mut ply = "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
                   element face 12\nproperty list uchar int vertex_indices\nend_header\n"
        .to_string();
    for i in 0..8 {
        let [x, y, z] = corner(i);
        ply += &format!("{x} {y} {z}\n");
    }
    for [a, b, c] in faces {
        ply += &format!("3 {a} {b} {c}\n");
    }
    ply
}

pub fn pose_text(pose: &DMat4) -> (String, String) {
    let r = DMat3::from_mat4(*pose).transpose().to_cols_array(); // row-major
    let t = pose.w_axis.truncate();
    (r.map(|v| v.to_string()).join(" "), format!("{} {} {}", t.x, t.y, t.z))
}

pub fn json_pose(pose: &DMat4) -> String {
    let r = DMat3::from_mat4(*pose).transpose().to_cols_array();
    let t = pose.w_axis.truncate();
    format!("\"cam_R_m2c\": {:?}, \"cam_t_m2c\": [{}, {}, {}]", r, t.x, t.y, t.z)
}

pub fn at(x: f64, y: f64, z: f64) -> DMat4 {
    DMat4::from_translation(DVec3::new(x, y, z))
}

/// A dataset of one scene: per image, its depth (mm, depth_scale 1) and ground-truth poses of
/// object 1, and the camera K for every image.
pub fn dataset(name: &str, images: &[(u32, Vec<u16>, Vec<DMat4>)]) -> PathBuf {
    let root = fresh_dir("bop", name);
    let models = root.join("models");
    std::fs::create_dir_all(&models).unwrap();
    std::fs::write(models.join("models_info.json"), format!("{{\"1\": {{\"diameter\": {DIAMETER}, \"min_x\": -50}}}}"))
        .unwrap();
    std::fs::write(models.join("obj_000001.ply"), box_ply()).unwrap();
    let scene = root.join("test").join("000001");
    std::fs::create_dir_all(scene.join("depth")).unwrap();
    let cameras: Vec<String> = images
        .iter()
        .map(|(im, ..)| format!("\"{im}\": {{\"cam_K\": {K:?}, \"depth_scale\": 1.0, \"elev\": 45}}"))
        .collect();
    std::fs::write(scene.join("scene_camera.json"), format!("{{{}}}", cameras.join(", "))).unwrap();
    let gts: Vec<String> = images
        .iter()
        .map(|(im, _, poses)| {
            let objects: Vec<String> = poses.iter().map(|p| format!("{{{}, \"obj_id\": 1}}", json_pose(p))).collect();
            format!("\"{im}\": [{}]", objects.join(", "))
        })
        .collect();
    std::fs::write(scene.join("scene_gt.json"), format!("{{{}}}", gts.join(", "))).unwrap();
    for (im, depth, _) in images {
        write_depth_png(&scene.join("depth").join(format!("{im:06}.png")), 640, 480, depth).unwrap();
    }
    root
}

/// Depth `value` over columns `cols` and rows `rows`, 0 elsewhere.
pub fn square(cols: std::ops::RangeInclusive<usize>, rows: std::ops::RangeInclusive<usize>, value: u16) -> Vec<u16> {
    let mut depth = vec![0u16; 640 * 480];
    for r in rows {
        for c in cols.clone() {
            depth[r * 640 + c] = value;
        }
    }
    depth
}

pub fn row(im_id: u32, pose: DMat4) -> ResultRow {
    let (r, t) = pose_text(&pose);
    let fields = ["1".to_string(), im_id.to_string(), "1".into(), "0.5".into(), r, t, "0.1".into()].to_vec();
    ResultRow { scene_id: 1, im_id, obj_id: 1, pose, fields }
}
