//! Independent CPU scorer: counts and scores straight from the sensed and synthetic images,
//! written from docs/design.md "Verification scores" without the library's verify module. Area
//! units follow the arithmetic docs/design.md and src/verify/area.rs specify (f32, fixed order),
//! re-typed here, so the counts can be compared exactly.
#![allow(clippy::needless_range_loop)]

use std::collections::BTreeMap;

pub struct Images<'a> {
    pub width: usize,
    pub height: usize,
    pub pitch: [f64; 2],
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
            pitch: synthetic.sensor.scanner().expect("the paper's scanner").pitch,
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

fn areas(label: &[u32], z: &[f32], w: usize, h: usize, dx: f32, dy: f32) -> BTreeMap<u32, u64> {
    let scale = 0.5 * 65536.0 / (dx * dy);
    let mut out = BTreeMap::new();
    for r in 0..h.saturating_sub(1) {
        for c in 0..w.saturating_sub(1) {
            let i = r * w + c;
            let l = label[i];
            if l == 0 || label[i + 1] != l || label[i + w] != l || label[i + w + 1] != l {
                continue;
            }
            let (a, b, e) = (z[i + 1] - z[i], z[i + w + 1] - z[i], z[i + w] - z[i]);
            let level = (dx * dy) * (dx * dy);
            let units =
                triangle_units(dy * a, dx * (a - b), level, scale) + triangle_units(dy * (b - e), dx * e, level, scale);
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
                let d = im.synthetic_z[i] - im.sensed_z[i];
                if d.abs() <= tolerance {
                    c.n1_plus += 1;
                } else if d > tolerance {
                    c.n1_minus += 1;
                }
            }
            (false, false) => {}
        }
    }
    let (dx, dy) = (im.pitch[0] as f32, im.pitch[1] as f32);
    c.scene_area_units = areas(im.sensed_label, im.sensed_z, im.width, im.height, dx, dy);
    c.model_area_units = areas(im.synthetic_label, im.synthetic_z, im.width, im.height, dx, dy);
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
