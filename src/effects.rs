//! Sensor effects beyond the shadow (docs/design.md "Sensor effects"): the scene's `[effects]`
//! table, or a hypothesis file's `"effects"` object, names them, and only the named ones are
//! recorded as passes (src/render/stages/effects.rs, shaders/stages/effect_*.comp).
//!
//! Each effect is evaluated on the image after shadowing, and every lost pixel carries the
//! [`Reason`] it was lost for. The losses depend only on the pixel and its neighbourhood, not
//! on the order of the passes, so the set of lost pixels is the union of what each effect
//! loses; where several effects lose one pixel, its reason is the first in [`EFFECT_ORDER`].
//! Random effects draw from a counter-based generator keyed by (seed, pixel, effect)
//! (shaders/stages/random.glsl), so an image is bit-identical across runs, batch sizes and orders.

use crate::error::{Error, Result};
use crate::sensor::{Sensor, View, WitnessGeometry};
use serde::{Deserialize, Serialize};

/// Why a pixel of `range.exr` holds no point (its `reason` channel); 0 is a valid point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
#[non_exhaustive]
pub enum Reason {
    Valid = 0,
    /// No surface in front of the sensor at this pixel.
    NoSurface = 1,
    /// In triangulation shadow: the camera cannot see the lit point.
    Shadow = 2,
    /// `[effects.grazing]`: the surface is seen or lit too obliquely.
    Grazing = 3,
    /// `[effects.range]`: outside the working volume.
    OutOfRange = 4,
    /// `[effects.reflectivity]`: too dark a surface.
    Dark = 5,
    /// `[effects.edges]`: next to a depth edge or a hole (a mixed pixel).
    Edge = 6,
    /// `[effects.dropout]`: lost at random.
    Dropout = 7,
}

impl Reason {
    pub const ALL: [Reason; 8] = [
        Reason::Valid,
        Reason::NoSurface,
        Reason::Shadow,
        Reason::Grazing,
        Reason::OutOfRange,
        Reason::Dark,
        Reason::Edge,
        Reason::Dropout,
    ];

    pub fn code(self) -> u32 {
        self as u32
    }

    pub fn from_code(code: u32) -> Option<Reason> {
        Self::ALL.get(code as usize).copied()
    }

    pub fn name(self) -> &'static str {
        match self {
            Reason::Valid => "valid",
            Reason::NoSurface => "no surface",
            Reason::Shadow => "shadow",
            Reason::Grazing => "grazing",
            Reason::OutOfRange => "out of range",
            Reason::Dark => "too dark",
            Reason::Edge => "edge",
            Reason::Dropout => "dropout",
        }
    }
}

/// One effect's pass: what it is called in the pass timings, and the reason it records
/// (`None` for the effects that change z rather than lose points).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Effect {
    Grazing,
    Range,
    Reflectivity,
    Edges,
    Dropout,
    Noise,
    Quantize,
    Disparity,
}

/// The order the effect passes run in: the losses, then noise, then quantization of the
/// noisy z (a real sensor digitises what it measured), then disparity (a stereo or
/// structured-light sensor's measurement of the depth the others left, and its search range).
pub const EFFECT_ORDER: [Effect; 8] = [
    Effect::Grazing,
    Effect::Range,
    Effect::Reflectivity,
    Effect::Edges,
    Effect::Dropout,
    Effect::Noise,
    Effect::Quantize,
    Effect::Disparity,
];

impl Effect {
    /// The pass's name in the render summary's "GPU time per pass".
    pub fn pass_name(self) -> &'static str {
        match self {
            Effect::Grazing => "grazing",
            Effect::Range => "working volume",
            Effect::Reflectivity => "reflectivity",
            Effect::Edges => "edges",
            Effect::Dropout => "dropout",
            Effect::Noise => "noise",
            Effect::Quantize => "quantize",
            Effect::Disparity => "disparity",
        }
    }

    /// Whether this effect changes z rather than losing points: the one list of such effects.
    /// Where one is named, z goes through a buffer of measured values from its pass on.
    pub fn changes_z(self) -> bool {
        matches!(self, Effect::Noise | Effect::Quantize | Effect::Disparity)
    }

    /// The reason a pixel this effect loses records; `None` for those that only change z.
    pub fn reason(self) -> Option<Reason> {
        match self {
            Effect::Grazing => Some(Reason::Grazing),
            Effect::Range => Some(Reason::OutOfRange),
            Effect::Reflectivity => Some(Reason::Dark),
            Effect::Edges => Some(Reason::Edge),
            Effect::Dropout => Some(Reason::Dropout),
            // Outside its search range.
            Effect::Disparity => Some(Reason::OutOfRange),
            Effect::Noise | Effect::Quantize => None,
        }
    }
}

/// The `[effects]` table. Every effect is off unless its table is present.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Effects {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grazing: Option<Grazing>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<WorkingVolume>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflectivity: Option<Reflectivity>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edges: Option<Edges>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dropout: Option<Dropout>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<Noise>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantize: Option<Quantize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub disparity: Option<Disparity>,
}

/// `[effects.grazing]`: a point is lost when the angle between its surface normal and the
/// direction toward the reference view or toward any witness exceeds `max_incidence_deg`: for
/// the paper's scanner, the projector (+z) and the camera; under a rig, back along the pixel's
/// ray, toward each pinhole witness's centre and along each directional witness's direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Grazing {
    pub max_incidence_deg: f64,
}

/// `[effects.range]`: the working volume in z; a point with z below `min_z` or above `max_z`
/// (range frame, model units) is lost. Either bound may be left out.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorkingVolume {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_z: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_z: Option<f64>,
}

/// `[effects.reflectivity]`: a point on a surface whose reflectivity is below `threshold` is
/// lost. A surface's reflectivity is its object's `reflectivity` in the scene, else the mean
/// of its OBJ material's `Kd`, else `default`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reflectivity {
    pub threshold: f64,
    #[serde(default = "full_reflectivity")]
    pub default: f64,
}

fn full_reflectivity() -> f64 {
    1.0
}

/// `[effects.edges]`: the mixed-pixel filter. A valid pixel is lost when any pixel within
/// `width_px` of it (Chebyshev distance, inside the image) holds no surface or differs from it
/// in z by more than `jump`, on the image after shadowing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Edges {
    pub jump: f64,
    #[serde(default = "one_pixel")]
    pub width_px: u32,
}

fn one_pixel() -> u32 {
    1
}

/// Largest `width_px`: a pixel reads (2·width + 1)² neighbours.
pub const MAX_EDGE_WIDTH_PX: u32 = 16;

/// `[effects.dropout]`: each point is lost with `probability`, independently.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dropout {
    pub probability: f64,
    #[serde(default)]
    pub seed: u32,
}

/// `[effects.noise]`: Gaussian noise along z with standard deviation
///
/// σ = sigma + depth_coefficient·(z − depth_reference)² + incidence_coefficient·α²/(π/2 − α)²
///
/// where α is the angle between the surface normal and the direction toward the reference view
/// (the paper's projector, +z; back along the pixel's ray under a pinhole view), and z the
/// range frame's z (the depth along the optical axis under a pinhole view): the axial model of
/// Nguyen, Izadi and Lovell (2012) for the Kinect, σ = 0.0012 + 0.0019·(z − 0.4)² +
/// 0.0001/√z·α²/(π/2 − α)² in metres, with the distance to the sensor as z. α is capped
/// at [`MAX_NOISE_INCIDENCE_DEG`] so that σ stays finite.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Noise {
    pub sigma: f64,
    #[serde(default)]
    pub seed: u32,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub depth_coefficient: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub depth_reference: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub incidence_coefficient: f64,
}

fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

/// The largest value of each σ term's coefficient: noise beyond it would overflow f32 z.
pub const MAX_SIGMA: f64 = 1e18;

/// The incidence angle the noise model's α²/(π/2 − α)² term is capped at, degrees.
pub const MAX_NOISE_INCIDENCE_DEG: f64 = 89.0;

/// `[effects.quantize]`: the stored z is rounded to the nearest multiple of `z_step`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Quantize {
    pub z_step: f64,
}

/// `[effects.disparity]`: depth measured as a disparity, as a structured-light or stereo
/// sensor with a pinhole reference view measures it. A valid pixel at depth z has disparity
/// d = f·b/z (`focal_px` f, `baseline` b in model units); Gaussian noise of `noise_px` pixels is
/// added to it, and it is rounded to 1/`subpixel` of a pixel: d' = round((d + noise)·s)/s. A
/// pixel whose d' lies outside [`min_px`, `max_px`] (the sensor's disparity search) is lost
/// (reason "out of range"); the others measure z' = f·b/d'. The depth step at z is about
/// z²/(f·b·s) and the noise σ_z ≈ z²·σ_d/(f·b). A pinhole reference view's alone; left out,
/// `focal_px` is its fx and `baseline` the distance to its first witness's centre
/// ([`Effects::for_sensor`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Disparity {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focal_px: Option<f64>,
    pub subpixel: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub min_px: f64,
    #[serde(default = "no_limit", skip_serializing_if = "is_no_limit")]
    pub max_px: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub noise_px: f64,
    #[serde(default)]
    pub seed: u32,
}

fn no_limit() -> f64 {
    f64::MAX
}

fn is_no_limit(value: &f64) -> bool {
    *value == f64::MAX
}

impl Effects {
    /// The effects as `sensor` has them, its disparity's focal length and baseline filled in
    /// where they were left out (the reference view's fx; the distance from its centre to the
    /// first witness's, a pinhole one); refuses what it cannot have: disparity without a
    /// pinhole reference view, or without the first witness it would take its baseline from.
    pub fn for_sensor(&self, sensor: &Sensor) -> Result<Effects> {
        let refuse = |m: String| Err(Error::Scene(m));
        let mut effects = *self;
        if let Some(d) = &mut effects.disparity {
            let View::Pinhole(view) = sensor.reference else {
                return refuse(format!(
                    "effects.disparity measures depth along a pinhole reference view's optical axis; this sensor's \
                     reference view is {}",
                    sensor.reference.kind()
                ));
            };
            d.focal_px = d.focal_px.or(Some(view.intrinsics.fx));
            if d.baseline.is_none() {
                match sensor.witnesses.first().map(|w| w.geometry) {
                    Some(WitnessGeometry::Pinhole { pose, .. }) => d.baseline = Some(pose.w_axis.truncate().length()),
                    _ => {
                        return refuse(
                            "effects.disparity.baseline is left out, but the sensor's first witness is no pinhole \
                             view to measure it to"
                                .into(),
                        )
                    }
                }
            }
            effects.validate()?;
        }
        Ok(effects)
    }

    /// Whether no effect is named: then no effect pass is recorded.
    pub fn is_empty(&self) -> bool {
        self.passes().next().is_none()
    }

    /// The named effects, in [`EFFECT_ORDER`].
    pub fn passes(&self) -> impl Iterator<Item = Effect> + '_ {
        EFFECT_ORDER.into_iter().filter(|effect| self.names(*effect))
    }

    fn names(&self, effect: Effect) -> bool {
        match effect {
            Effect::Grazing => self.grazing.is_some(),
            Effect::Range => self.range.is_some(),
            Effect::Reflectivity => self.reflectivity.is_some(),
            Effect::Edges => self.edges.is_some(),
            Effect::Dropout => self.dropout.is_some(),
            Effect::Noise => self.noise.is_some(),
            Effect::Quantize => self.quantize.is_some(),
            Effect::Disparity => self.disparity.is_some(),
        }
    }

    /// Whether a named effect changes z ([`Effect::changes_z`]).
    pub fn changes_z(&self) -> bool {
        self.passes().any(Effect::changes_z)
    }

    /// Checks every parameter; the error names the key and the allowed range. The GPU takes
    /// them as f32, so lengths must be finite in f32 too, and σ terms at most [`MAX_SIGMA`].
    pub fn validate(&self) -> Result<()> {
        let bad = |key: &str, value: &dyn std::fmt::Display, allowed: &str| {
            Err(Error::Scene(format!("effects.{key} = {value} is out of range: it must be {allowed}")))
        };
        let finite =
            |key: &str, value: f64| if (value as f32).is_finite() { Ok(()) } else { bad(key, &value, "finite in f32") };
        if let Some(g) = &self.grazing {
            if !(g.max_incidence_deg > 0.0 && g.max_incidence_deg <= 90.0) {
                return bad("grazing.max_incidence_deg", &g.max_incidence_deg, "in (0, 90] degrees");
            }
        }
        if let Some(r) = &self.range {
            if r.min_z.is_none() && r.max_z.is_none() {
                return Err(Error::Scene("effects.range needs min_z, max_z or both".into()));
            }
            for (key, bound) in [("range.min_z", r.min_z), ("range.max_z", r.max_z)] {
                bound.map_or(Ok(()), |v| finite(key, v))?;
            }
            if let (Some(lo), Some(hi)) = (r.min_z, r.max_z) {
                if lo >= hi {
                    return bad("range.min_z", &lo, &format!("less than effects.range.max_z = {hi}"));
                }
            }
        }
        if let Some(r) = &self.reflectivity {
            for (key, value) in [("reflectivity.threshold", r.threshold), ("reflectivity.default", r.default)] {
                if !(0.0..=1.0).contains(&value) {
                    return bad(key, &value, "in [0, 1]");
                }
            }
        }
        if let Some(e) = &self.edges {
            if !(e.jump > 0.0 && (e.jump as f32).is_finite()) {
                return bad("edges.jump", &e.jump, "positive and finite (model units)");
            }
            if !(1..=MAX_EDGE_WIDTH_PX).contains(&e.width_px) {
                return bad("edges.width_px", &e.width_px, &format!("in 1..={MAX_EDGE_WIDTH_PX} pixels"));
            }
        }
        if let Some(d) = &self.dropout {
            if !(0.0..=1.0).contains(&d.probability) {
                return bad("dropout.probability", &d.probability, "in [0, 1]");
            }
        }
        if let Some(n) = &self.noise {
            for (key, value) in [
                ("noise.sigma", n.sigma),
                ("noise.depth_coefficient", n.depth_coefficient),
                ("noise.incidence_coefficient", n.incidence_coefficient),
            ] {
                if !(0.0..=MAX_SIGMA).contains(&value) {
                    return bad(key, &value, &format!("in [0, {MAX_SIGMA:e}]"));
                }
            }
            finite("noise.depth_reference", n.depth_reference)?;
        }
        if let Some(q) = &self.quantize {
            if !(q.z_step as f32 >= f32::MIN_POSITIVE && (q.z_step as f32).is_finite()) {
                return bad("quantize.z_step", &q.z_step, "positive and finite (model units)");
            }
        }
        if let Some(d) = &self.disparity {
            for (key, value) in [("disparity.baseline", d.baseline), ("disparity.focal_px", d.focal_px)] {
                match value {
                    Some(v) if !(v.is_finite() && v > 0.0) => return bad(key, &v, "positive and finite"),
                    _ => {}
                }
            }
            if let (Some(b), Some(f)) = (d.baseline, d.focal_px) {
                if !((b * f) as f32).is_normal() {
                    return bad("disparity.baseline", &b, "such that baseline · focal_px is a normal f32");
                }
            }
            if !(1.0..=256.0).contains(&d.subpixel) {
                return bad("disparity.subpixel", &d.subpixel, "in [1, 256] steps a pixel");
            }
            if d.max_px.is_nan() || d.max_px <= 0.0 {
                return bad("disparity.max_px", &d.max_px, "positive (pixels)");
            }
            if !(d.min_px >= 0.0 && d.min_px < d.max_px) {
                return bad(
                    "disparity.min_px",
                    &d.min_px,
                    &format!("at least 0 and below effects.disparity.max_px = {}", d.max_px),
                );
            }
            if !(0.0..=1e6).contains(&d.noise_px) {
                return bad("disparity.noise_px", &d.noise_px, "in [0, 1e6] pixels");
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Effects {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn absent_effects_record_nothing_and_the_order_is_fixed() {
        assert!(Effects::default().is_empty());
        let all = parse(
            "[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 8\n[quantize]\nz_step = 0.1\n[noise]\nsigma = 0.1\n\
             [dropout]\nprobability = 0.5\n[edges]\njump = 1\n[reflectivity]\nthreshold = 0.5\n[range]\nmax_z = 1\n\
             [grazing]\nmax_incidence_deg = 80\n",
        );
        assert_eq!(all.passes().collect::<Vec<_>>(), EFFECT_ORDER);
        assert_eq!(parse("[noise]\nsigma = 0\n").passes().collect::<Vec<_>>(), [Effect::Noise]);
    }

    /// Keys left out take the defaults docs/effects.md states: a surface without a
    /// reflectivity of its own is fully reflective; the edge filter is one pixel wide.
    #[test]
    fn left_out_keys_take_their_documented_defaults() {
        let reflectivity = parse("[reflectivity]\nthreshold = 0.5").reflectivity.unwrap();
        assert_eq!((reflectivity.threshold, reflectivity.default), (0.5, 1.0));
        assert_eq!(parse("[edges]\njump = 0.2").edges.unwrap().width_px, 1);
    }

    /// The settings a header records (src/io/exr_file.rs) leave out only the noise terms that
    /// are 0, and read back as they were.
    #[test]
    fn settings_written_leave_out_zero_noise_terms_and_read_back_whole() {
        let effects = parse("[noise]\nsigma = 0.01\ndepth_coefficient = 0.002\ndepth_reference = 0.4");
        let text = toml::to_string(&effects).unwrap();
        assert!(text.contains("depth_coefficient = 0.002") && text.contains("depth_reference = 0.4"), "{text}");
        assert!(!text.contains("incidence_coefficient"), "{text}");
        assert_eq!(toml::from_str::<Effects>(&text).unwrap(), effects, "{text}");
    }

    #[test]
    fn out_of_range_parameters_are_refused_by_name() {
        for (text, key) in [
            ("[noise]\nsigma = -1", "noise.sigma"),
            ("[dropout]\nprobability = 1.5", "dropout.probability"),
            ("[dropout]\nprobability = -0.1", "dropout.probability"),
            ("[quantize]\nz_step = 0", "quantize.z_step"),
            ("[quantize]\nz_step = -2", "quantize.z_step"),
            ("[grazing]\nmax_incidence_deg = 0", "grazing.max_incidence_deg"),
            ("[grazing]\nmax_incidence_deg = 90.5", "grazing.max_incidence_deg"),
            ("[edges]\njump = 0.1\nwidth_px = 0", "edges.width_px"),
            ("[edges]\njump = -1", "edges.jump"),
            ("[edges]\njump = 0", "edges.jump"),
            ("[range]\nmin_z = 2\nmax_z = 1", "range.min_z"),
            ("[range]", "effects.range needs"),
            ("[reflectivity]\nthreshold = 2", "reflectivity.threshold"),
            ("[noise]\nsigma = nan", "noise.sigma"),
            ("[noise]\nsigma = 1e30", "noise.sigma"),
            ("[quantize]\nz_step = 1e39", "quantize.z_step"),
            ("[quantize]\nz_step = 1e-46", "quantize.z_step"),
            ("[range]\nmax_z = 1e39", "range.max_z"),
            ("[edges]\njump = 1e39", "edges.jump"),
            ("[disparity]\nbaseline = 0\nfocal_px = 500\nsubpixel = 8", "disparity.baseline"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = nan\nsubpixel = 8", "disparity.focal_px"),
            ("[disparity]\nbaseline = 1e-45\nfocal_px = 500\nsubpixel = 8", "disparity.baseline"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 0.5", "disparity.subpixel"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 512", "disparity.subpixel"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 8\nmin_px = 40\nmax_px = 30", "disparity.min_px"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 8\nmin_px = -1", "disparity.min_px"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 8\nmax_px = nan", "disparity.max_px"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 8\nmax_px = 0", "disparity.max_px"),
            ("[disparity]\nbaseline = 0.1\nfocal_px = 500\nsubpixel = 8\nnoise_px = -0.1", "disparity.noise_px"),
        ] {
            let message = parse(text).validate().unwrap_err().to_string();
            assert!(message.contains(key), "{text}: {message}");
        }
        let fine = "[noise]\nsigma = 0\n[dropout]\nprobability = 1\n[grazing]\nmax_incidence_deg = 90\n";
        parse(fine).validate().unwrap();
    }

    #[test]
    fn an_effect_either_loses_points_for_a_reason_or_changes_z() {
        // Disparity does both: it measures z, and loses what lies outside its search.
        for effect in EFFECT_ORDER {
            let both = effect == Effect::Disparity;
            assert_eq!(effect.reason().is_none(), effect.changes_z() && !both, "{effect:?}");
            assert!(effect.reason().is_some() || effect.changes_z(), "{effect:?}");
        }
        assert!(!parse("[dropout]\nprobability = 0.5\n").changes_z());
        assert!(parse("[quantize]\nz_step = 0.1\n").changes_z());
    }

    #[test]
    fn reason_codes_round_trip() {
        for reason in Reason::ALL {
            assert_eq!(Reason::from_code(reason.code()), Some(reason));
        }
        assert_eq!(Reason::from_code(8), None);
    }
}
