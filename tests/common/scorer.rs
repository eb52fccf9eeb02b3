//! Independent CPU scorer: counts and scores straight from the sensed and synthetic images,
//! written from docs/design.md "Verification scores" without the library's verify module. Area
//! units follow the arithmetic docs/design.md and src/verify/area.rs specify (f32, fixed order),
//! re-typed here, so the counts can be compared exactly.
#![allow(clippy::needless_range_loop)]

use std::collections::BTreeMap;

/// Where an image's pixels' rays run: the scores' areas and which way is nearer.
#[derive(Clone, Copy)]
pub enum Rays {
    /// Parallel over a grid of this pitch; z grows toward the sensor.
    Orthographic([f64; 2]),
    /// Through the centre of a pinhole view of these intrinsics; depth grows away from it.
    Pinhole { fx: f64, fy: f64, cx: f64, cy: f64 },
}

pub struct Images<'a> {
    pub width: usize,
    pub height: usize,
    pub rays: Rays,
    pub sensed_label: &'a [u32],
    pub sensed_z: &'a [f32],
    pub synthetic_label: &'a [u32],
    pub synthetic_z: &'a [f32],
}

impl<'a> Images<'a> {
    /// A sensed range image against a render's synthetic image of the same size.
    pub fn of(sensed: &'a rangesynth::io::RangeImage, synthetic: &'a rangesynth::RenderOutput) -> Self {
        Images {
            width: sensed.width as usize,
            height: sensed.height as usize,
            rays: match synthetic.sensor.reference {
                rangesynth::sensor::View::Orthographic(o) => Rays::Orthographic(o.pitch),
                rangesynth::sensor::View::Pinhole(p) => {
                    let k = p.intrinsics;
                    Rays::Pinhole { fx: k.fx, fy: k.fy, cx: k.cx, cy: k.cy }
                }
                _ => panic!("the scorer knows no such view"),
            },
            sensed_label: &sensed.label,
            sensed_z: &sensed.z,
            synthetic_label: &synthetic.label,
            synthetic_z: &synthetic.z,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct CpuCounts {
    pub n1_plus: u64,
    pub n1_minus: u64,
    pub n0: u64,
    pub n1: u64,
    pub n_i: u64,
    pub n_s: u64,
    /// (scene label, model surface) → t
    pub overlap: BTreeMap<(u32, u32), u64>,
    pub scene_population: BTreeMap<u32, u64>,
    pub model_population: BTreeMap<u32, u64>,
    pub scene_area_units: BTreeMap<u32, u64>,
    pub model_area_units: BTreeMap<u32, u64>,
}

fn triangle_units(p: f32, q: f32, level: f32, scale: f32) -> u64 {
    let sum = p * p + q * q + level;
    u64::from((sum.sqrt() * scale).min(4_294_967_040.0) as u32)
}

/// A pinhole block's two triangles' units: the points z·((c − cx)/fx, (r − cy)/fy, 1) of its
/// four pixels (1/fx and 1/fy rounded to f32, then multiplied), each triangle's doubled area
/// the length of the cross product of two of its edges from the top-left point, x, y, z
/// components summed in that order.
fn pinhole_units(c: usize, r: usize, z: [f32; 4], (ifx, ify, cx, cy): (f32, f32, f32, f32), scale: f32) -> u64 {
    let point = |c: usize, r: usize, z: f32| [z * ((c as f32 - cx) * ifx), z * ((r as f32 - cy) * ify), z];
    let p = point(c, r, z[0]);
    let edge = |q: [f32; 3]| [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let (e1, e2, e3) = (edge(point(c + 1, r, z[1])), edge(point(c + 1, r + 1, z[3])), edge(point(c, r + 1, z[2])));
    let units = |a: [f32; 3], b: [f32; 3]| {
        let x = a[1] * b[2] - a[2] * b[1];
        let y = a[2] * b[0] - a[0] * b[2];
        let z = a[0] * b[1] - a[1] * b[0];
        triangle_units(0.0, 0.0, x * x + y * y + z * z, scale)
    };
    units(e1, e2) + units(e2, e3)
}

/// Each label's area units over the blocks whose four pixels carry it. A pinhole view's unit
/// is a pixel's footprint at `unit_depth`.
fn areas(label: &[u32], z: &[f32], w: usize, h: usize, rays: Rays, unit_depth: f64) -> BTreeMap<u32, u64> {
    let (dx, dy) = match rays {
        Rays::Orthographic([dx, dy]) => (dx as f32, dy as f32),
        Rays::Pinhole { fx, fy, .. } => ((unit_depth / fx) as f32, (unit_depth / fy) as f32),
    };
    let scale = 0.5 * 65536.0 / (dx * dy);
    let mut out = BTreeMap::new();
    for r in 0..h.saturating_sub(1) {
        for c in 0..w.saturating_sub(1) {
            let i = r * w + c;
            let l = label[i];
            if l == 0 || label[i + 1] != l || label[i + w] != l || label[i + w + 1] != l {
                continue;
            }
            let units = match rays {
                Rays::Orthographic(_) => {
                    let (a, b, e) = (z[i + 1] - z[i], z[i + w + 1] - z[i], z[i + w] - z[i]);
                    let level = (dx * dy) * (dx * dy);
                    triangle_units(dy * a, dx * (a - b), level, scale)
                        + triangle_units(dy * (b - e), dx * e, level, scale)
                }
                Rays::Pinhole { fx, fy, cx, cy } => {
                    let k = ((1.0 / fx) as f32, (1.0 / fy) as f32, cx as f32, cy as f32);
                    pinhole_units(c, r, [z[i], z[i + 1], z[i + w], z[i + w + 1]], k, scale)
                }
            };
            *out.entry(l).or_insert(0) += units;
        }
    }
    out
}

pub fn cpu_counts(im: &Images, tolerance: f32) -> CpuCounts {
    let mut c = CpuCounts::default();
    for i in 0..im.width * im.height {
        let (s, m) = (im.sensed_label[i], im.synthetic_label[i]);
        if s != 0 {
            c.n_i += 1;
            *c.scene_population.entry(s).or_insert(0) += 1;
        }
        if m != 0 {
            c.n_s += 1;
            *c.model_population.entry(m).or_insert(0) += 1;
        }
        match (s != 0, m != 0) {
            (false, true) => c.n0 += 1,
            (true, false) => c.n1 += 1,
            (true, true) => {
                *c.overlap.entry((s, m)).or_insert(0) += 1;
                // Positive where the synthetic surface lies nearer the sensor.
                let d = match im.rays {
                    Rays::Orthographic(_) => im.synthetic_z[i] - im.sensed_z[i],
                    Rays::Pinhole { .. } => im.sensed_z[i] - im.synthetic_z[i],
                };
                if d.abs() <= tolerance {
                    c.n1_plus += 1;
                } else if d > tolerance {
                    c.n1_minus += 1;
                }
            }
            (false, false) => {}
        }
    }
    // A pinhole view's area unit is a pixel's footprint at the farthest sensed depth.
    let labelled = im.sensed_label.iter().zip(im.sensed_z).filter(|(&l, _)| l != 0);
    let farthest = labelled.map(|(_, &z)| f64::from(z)).fold(0.0, f64::max);
    let unit_depth = if farthest > 0.0 { farthest } else { 1.0 };
    c.scene_area_units = areas(im.sensed_label, im.sensed_z, im.width, im.height, im.rays, unit_depth);
    c.model_area_units = areas(im.synthetic_label, im.synthetic_z, im.width, im.height, im.rays, unit_depth);
    c
}

/// [s1, s2, s3, s4, s5, s6, s]; s is 0 when s4 or s5 rejects.
pub fn cpu_scores(c: &CpuCounts, bindings: &[(u32, u32)]) -> [f64; 7] {
    let mut bound: Vec<(u32, u32)> = bindings.to_vec();
    bound.sort_unstable();
    bound.dedup();
    let pop_s = |s: u32| *c.scene_population.get(&s).unwrap_or(&0) as f64;
    let pop_m = |m: u32| *c.model_population.get(&m).unwrap_or(&0) as f64;
    let present: Vec<(u32, u32)> = bound.iter().copied().filter(|&(s, m)| pop_s(s) > 0.0 && pop_m(m) > 0.0).collect();
    let t = |s: u32, m: u32| *c.overlap.get(&(s, m)).unwrap_or(&0) as f64;

    let s1 = if c.n1_plus + c.n1_minus == 0 { 0.0 } else { c.n1_plus as f64 / (c.n1_plus + c.n1_minus) as f64 };
    let mut log_s2 = 0.0;
    for (&(s, m), &n) in &c.overlap {
        let x = (n as f64).powi(2) / (pop_s(s) * pop_m(m));
        log_s2 += if bound.contains(&(s, m)) { 0.0 } else { (1.0 - x).ln() };
    }
    for &(s, m) in &present {
        log_s2 += (t(s, m).powi(2) / (pop_s(s) * pop_m(m))).ln();
    }
    let s2 = log_s2.exp();
    let total: f64 = c.overlap.values().map(|&n| n as f64).sum();
    let s3 = if total == 0.0 { 0.0 } else { bound.iter().map(|&(s, m)| t(s, m)).sum::<f64>() / total };
    let mut s4 = 1.0;
    let mut rejected = false;
    for &(s, m) in &present {
        let a_s = *c.scene_area_units.get(&s).unwrap_or(&0) as f64;
        let a_m = *c.model_area_units.get(&m).unwrap_or(&0) as f64;
        if a_s == 0.0 && a_m == 0.0 {
            continue;
        }
        let r = a_s / a_m;
        if r <= 1.0 {
            s4 *= r;
        } else if r <= 2.0 {
            s4 /= r;
        } else {
            s4 = 0.0;
            rejected = true;
        }
    }
    let (ni, ns) = (c.n_i as f64, c.n_s as f64);
    let s5 = if ns == 0.0 {
        rejected = true;
        0.0
    } else if ni < ns {
        ni / ns
    } else if ni / ns <= 2.0 {
        ns / ni
    } else {
        rejected = true;
        0.0
    };
    let s6 = if ni == 0.0 || ns == 0.0 {
        0.0
    } else {
        ((ni - c.n0 as f64) * (ns - c.n1 as f64) / (ni * ns)).clamp(0.0, 1.0)
    };
    let s = if rejected { 0.0 } else { s1 * s2 * s3 * s4 * s5 * s6 };
    [s1, s2, s3, s4, s5, s6, s]
}

/// The library's counts in the CPU scorer's terms (scene labels instead of dense indices), to
/// compare them with its own.
pub fn as_cpu(c: &rangesynth::verify::Counts, sensed: &rangesynth::verify::SensedImage, n_i: u64) -> CpuCounts {
    let nonzero = |v: &[u64]| v.iter().enumerate().filter(|(_, &n)| n != 0).map(|(m, &n)| (m as u32 + 1, n)).collect();
    CpuCounts {
        n1_plus: c.n1_plus,
        n1_minus: c.n1_minus,
        n0: c.n0,
        n1: c.n1,
        n_i,
        n_s: c.synthetic_valid(),
        overlap: c.overlap.iter().map(|&((k, m), t)| ((sensed.segments[k as usize], m), t)).collect(),
        scene_population: sensed.segments.iter().zip(&sensed.segment_population).map(|(&s, &n)| (s, n)).collect(),
        model_population: nonzero(&c.surface_population),
        scene_area_units: sensed
            .segments
            .iter()
            .zip(&sensed.segment_area_units)
            .filter(|(_, &a)| a != 0)
            .map(|(&s, &a)| (s, a))
            .collect(),
        model_area_units: nonzero(&c.surface_area_units),
    }
}
