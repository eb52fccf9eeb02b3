//! The f32 arithmetic a render asks of the GPU, bounded on the host before anything is
//! recorded. Parameters each valid alone (an effect's, the sensor's, a pose) can still
//! overflow or lose their meaning where the shaders combine them: noise whose σ grows with
//! the square of a depth far from its reference, a quantization step too fine for the
//! scene's depth, a model reaching so many pixels that f32 window coordinates no longer hold
//! its edges. The GPU would then write a non-finite z into a valid pixel, or cover the wrong
//! pixels, and say nothing. Each check evaluates the shaders' own expressions in f32 at the
//! extremes of what a view can hold (its depth range, the farthest point of a bounding
//! sphere), with a margin for a GPU's operations, which may err by a few ulps.

use crate::effects::{Effects, MAX_NOISE_INCIDENCE_DEG};
use crate::error::{Error, Result};
use crate::mesh::MAX_COORDINATE;
use crate::sensor::ViewGrid;
use glam::DVec3;

/// The largest |standard normal variate| shaders/stages/random.glsl draws (below 5.8), with a margin.
const GAUSSIAN_BOUND: f32 = 6.0;

/// How far, in pixels of a view, a model that shows in the view may reach from its first
/// pixel: below 2^23 pixels, f32 window coordinates (shaders/raster/draw.glsl, `clip_position`) are
/// spaced at most half a pixel, so a corner rounds by at most a quarter pixel and an edge
/// crossing the view lies within about half a pixel of where f64 puts it. Farther, a pixel's
/// coverage is decided by rounding (a 16-pixel image of a 1-unit box at a pitch of 1e-30 lost
/// half its pixels on either rasterizer).
pub const MAX_SEEN_REACH_PIXELS: f64 = 8_388_608.0;

/// How far, in pixels of a view, a model that does not show in it may lie: its window
/// coordinates and depths stay finite, with room for the compute rasterizer's snapping
/// (×256) and the viewport transform, so the pipelines clip it rather than meet an infinity.
const MAX_UNSEEN_REACH_PIXELS: f64 = 1e30;

/// Checks a view's grid as a draw hands it to the shaders (draw.rs, `DrawConstants`): its
/// first pixel and depth range as f32 offsets from the view's local origin (`local`, in the
/// view's frame), its pitch a normal f32 (the shadow view's is the range view's divided by
/// `[shadow] columns`), and its depth range a positive, finite f32 span, which every depth
/// divides by.
pub(super) fn check_grid(grid: &ViewGrid, view: &str, local: DVec3) -> Result<()> {
    let [dx, dy] = grid.pitch.map(|p| p as f32);
    let first = [grid.origin[0] - local.x, grid.origin[1] - local.y].map(|v| v as f32);
    let [near, far] = [grid.z_range.0 - local.z, grid.z_range.1 - local.z].map(|v| v as f32);
    let span = far - near;
    if !(dx.is_normal() && dy.is_normal()) {
        return Err(Error::Scene(format!(
            "the {view} view's pitch {:?} is not a normal f32 (the shaders divide by it){}",
            grid.pitch,
            if view == "shadow" { ": the sensor's pitch divided by [shadow] columns" } else { "" }
        )));
    }
    if !first.iter().all(|v| v.is_finite()) {
        return Err(Error::Scene(format!(
            "the {view} view's first pixel lies beyond f32's range from its local origin ({first:?})"
        )));
    }
    if !(span.is_normal() && span > 0.0) {
        return Err(Error::Scene(format!(
            "the {view} view's depth range ({:.6e} to {:.6e}) has no f32 span the shaders can divide by \
             ({span:e}): the scene is too deep, or too thin for its distance from the range frame's origin",
            grid.z_range.0, grid.z_range.1
        )));
    }
    Ok(())
}

/// Checks one model's bounding sphere (`centre` in the view's frame) against a view whose
/// local origin is `local` (the view's frame): whether it shows there (`seen`) decides how
/// far it may reach. `name` names it.
pub(super) fn check_reach(
    grid: &ViewGrid,
    view: &str,
    local: DVec3,
    (centre, radius): (DVec3, f64),
    seen: bool,
    name: &str,
) -> Result<()> {
    let farthest = (centre - local).length() + radius;
    if farthest.is_nan() || farthest > f64::from(MAX_COORDINATE) {
        return Err(Error::Scene(format!(
            "{name} reaches {farthest:.3e} model units from the {view} view's local origin, more than \
             {MAX_COORDINATE:e}: the GPU's f32 coordinates would overflow; leave it out of the scene"
        )));
    }
    let across = grid.reach(centre, radius);
    let span = grid.z_range.1 - grid.z_range.0;
    let deep = ((centre.z - grid.z_range.1).abs().max((centre.z - grid.z_range.0).abs()) + radius) / span;
    let (limit, why) = match seen {
        true => (
            MAX_SEEN_REACH_PIXELS,
            "there the GPU's f32 window coordinates no longer place its edges within half a pixel; use a coarser \
             pitch or split the model",
        ),
        false => {
            (MAX_UNSEEN_REACH_PIXELS, "the GPU's f32 window coordinates would overflow; leave it out of the scene")
        }
    };
    if across.is_nan() || across > limit {
        return Err(Error::Scene(format!(
            "{name} reaches {across:.3e} pixels from the {view} view's first pixel, more than {limit:e}: {why}"
        )));
    }
    if deep.is_nan() || deep > MAX_UNSEEN_REACH_PIXELS {
        return Err(Error::Scene(format!(
            "{name} lies {deep:.3e} times the {view} view's depth range from it, more than {MAX_UNSEEN_REACH_PIXELS:e}: \
             the GPU's f32 depths would overflow; leave it out of the scene"
        )));
    }
    Ok(())
}

/// Checks that the effects that change z keep every valid pixel's z finite, as the effect
/// shaders compute it (shaders/stages/effect_noise.comp, effect_quantize.comp), for any z the range
/// view (`range`) can hold: its depth range, measured from the local origin `local` as the GPU
/// adds it back.
pub(super) fn check_effects(effects: &Effects, range: &ViewGrid, local: DVec3) -> Result<()> {
    let z_origin = local.z as f32;
    let rendered = |z: f64| (z - local.z) as f32 + z_origin;
    let (near, far) = range.z_range;
    let depths = format!("z from {near:.6e} to {far:.6e}");
    // The lowest and the highest z a pass may see.
    let mut ends = [rendered(near), rendered(far)];
    if let Some(noise) = &effects.noise {
        let [sigma, coefficient, reference, incidence] =
            [noise.sigma, noise.depth_coefficient, noise.depth_reference, noise.incidence_coefficient]
                .map(|v| v as f32);
        let alpha = MAX_NOISE_INCIDENCE_DEG.to_radians() as f32;
        let oblique = alpha / (std::f32::consts::FRAC_PI_2 - alpha);
        let sigma_at = |z: f32| {
            let from_reference = z - reference;
            sigma + coefficient * from_reference * from_reference + incidence * oblique * oblique
        };
        // σ is convex in z, so z − kσ and z + kσ are extreme at the ends of the depth range.
        let low = ends.map(|z| z - GAUSSIAN_BOUND * sigma_at(z)).into_iter().fold(f32::INFINITY, f32::min);
        let high = ends.map(|z| z + GAUSSIAN_BOUND * sigma_at(z)).into_iter().fold(f32::NEG_INFINITY, f32::max);
        if !(low.is_finite() && high.is_finite()) {
            return Err(Error::Scene(format!(
                "effects.noise: σ = {:e} + {:e}·(z − {:e})² + {:e}·(incidence term) reaches {:.3e} over this scene's depths \
                 ({depths}), and the GPU's f32 z ± {GAUSSIAN_BOUND}σ overflows: lower depth_coefficient or bring \
                 depth_reference nearer the scene",
                noise.sigma,
                noise.depth_coefficient,
                noise.depth_reference,
                noise.incidence_coefficient,
                ends.map(sigma_at).into_iter().fold(0.0, f32::max)
            )));
        }
        ends = [low, high];
    }
    if let Some(quantize) = &effects.quantize {
        let step = quantize.z_step as f32;
        let fits = |z: f32| (z / step).abs() <= f32::MAX / 2.0 && ((z / step).round_ties_even() * step).is_finite();
        if !ends.iter().all(|&z| fits(z)) {
            return Err(Error::Scene(format!(
                "effects.quantize.z_step = {:e} is too fine for this scene's depths ({depths}{}): the GPU divides z by \
                 it in f32, which overflows; use a coarser step",
                quantize.z_step,
                if effects.noise.is_some() { ", and the noise around them" } else { "" }
            )));
        }
    }
    Ok(())
}
