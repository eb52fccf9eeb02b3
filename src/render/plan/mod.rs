//! Planning a render's views before anything is recorded: the range grid over the scene's
//! depth bounds, the shadow grid that covers what the range view can see, and the checks
//! that the GPU's f32 arithmetic holds them (plan/gpu_arithmetic.rs). `render` plans one scene's
//! views, `verify` one hypothesis' at a time.

pub(crate) mod gpu_arithmetic;

use crate::effects::Effects;
use crate::error::{Error, Result};
use crate::sensor::{depth_bounds, Scanner, ViewGrid};
use crate::shadow::{ShadowMode, ShadowSettings};
use glam::DVec3;

/// The two views of one render, with the grids they were rendered on.
pub(crate) struct Views {
    /// The local origin both views measure from (range frame; `ViewGrid::local_origin`).
    pub origin: DVec3,
    pub range: ViewGrid,
    /// `None` when no shadow pass is recorded (mode `none` or θ = 0).
    pub shadow: Option<ViewGrid>,
}

impl Views {
    /// The views of a `width`×`height` image cast on the CPU (a rig other than the paper's
    /// scanner), as the GPU's effect and score passes see it: its pixels on a grid of unit
    /// pitch (no pass reads the pitch), z as cast (no local origin), no shadow view.
    pub fn cast(width: u32, height: u32) -> Self {
        let range = ViewGrid { origin: [0.0; 2], pitch: [1.0; 2], width, height, z_range: (0.0, 1.0) };
        Self { origin: DVec3::ZERO, range, shadow: None }
    }

    /// 1, or 2 with a shadow view.
    pub fn count(&self) -> u64 {
        1 + u64::from(self.shadow.is_some())
    }

    /// How far, in pixels, a bounding sphere (centre in the range frame) reaches from the first
    /// pixel of either view (`ViewGrid::reach`): what the compute rasterizer's choice reads.
    pub fn reach(&self, sensor: &Scanner, (centre, radius): (DVec3, f64)) -> f64 {
        let shadow = self.shadow.map_or(0.0, |g| g.reach(sensor.to_shadow_frame().transform_point3(centre), radius));
        self.range.reach(centre, radius).max(shadow)
    }
}

/// Plans the views of a render: the range grid over the scene's depth bounds and, unless mode
/// `none` or θ = 0, the shadow grid (sensor.rs) for bounding spheres (centre, radius) given in
/// the range frame, `name(i)` naming sphere i's model in errors. The plan is refused where the
/// GPU's f32 arithmetic would not hold it: its grids, each model's reach, and the effects that
/// change z over its depth range (plan/gpu_arithmetic.rs).
///
/// Only what a view can show sizes it: an object whose footprint misses the range image
/// cannot put a point into it, so it neither widens the range view's depth range nor the
/// shadow view's columns (which cover every point the range view can see); and one whose
/// footprint misses the shadow grid cannot shadow any of those points, so it leaves the
/// shadow view's depth range alone. Such objects are still drawn, and clipped. A box far away
/// in depth beside the image therefore no longer makes the shadow view impossibly wide.
pub(crate) fn plan_views(
    sensor: &Scanner,
    shadow: &ShadowSettings,
    effects: &Effects,
    spheres: &[(DVec3, f64)],
    name: &dyn Fn(usize) -> String,
    max_side: u32,
) -> Result<Views> {
    let full_range = sensor.range_grid((0.0, 0.0));
    let seen = |grid: &ViewGrid, (centre, radius): (DVec3, f64)| grid.footprint(centre, radius, 1).is_some();
    let z_range = depth_bounds(spheres.iter().copied().filter(|&s| seen(&full_range, s)));
    let range = sensor.range_grid(z_range);
    let origin = range.local_origin();
    if !origin.is_finite() {
        return Err(Error::Scene(format!(
            "the scene's depth range ({} to {}) is not finite: an object is posed too far away",
            z_range.0, z_range.1
        )));
    }
    // The shadow view's frame, and its local origin: the range view's, rotated.
    let to_shadow = sensor.to_shadow_frame();
    let shadow_local = to_shadow.transform_point3(origin);
    let shadow_grid = match shadow.mode.needs_shadow_pass(sensor.theta_deg) {
        false => None,
        true => {
            let in_shadow_frame = spheres.iter().map(|&(c, r)| (to_shadow.transform_point3(c), r));
            let columns = sensor.shadow_grid(z_range, (0.0, 0.0), origin.z, shadow.columns)?;
            let seen_there: Vec<_> = in_shadow_frame.filter(|&s| seen(&columns, s)).collect();
            // Where nothing shows, a depth range about the view's local origin: far from the
            // frame's origin, one about 0 would have no f32 span there.
            let shadow_z = match seen_there.is_empty() {
                true => (shadow_local.z - 1.0, shadow_local.z + 1.0),
                false => depth_bounds(seen_there),
            };
            Some(ViewGrid { z_range: shadow_z, ..columns })
        }
    };
    for grid in std::iter::once(&range).chain(shadow_grid.as_ref()) {
        if grid.width > max_side || grid.height > max_side {
            return Err(Error::Scene(format!(
                "a {}×{} view exceeds this device's limit of {max_side} pixels per side (its largest image and viewport)",
                grid.width, grid.height
            )));
        }
    }
    let views = Views { origin, range, shadow: shadow_grid };
    let shadow_view = views.shadow.as_ref().map(|grid| (grid, shadow_local));
    // Shadow mode `exact` casts its rays on the host and rasterizes nothing.
    if shadow.mode != ShadowMode::Exact {
        gpu_arithmetic::check_grid(&views.range, "range", origin)?;
        if let Some((grid, local)) = shadow_view {
            gpu_arithmetic::check_grid(grid, "shadow", local)?;
        }
        for (i, &(centre, radius)) in spheres.iter().enumerate() {
            let in_range = (centre, radius);
            let seen_in_range = seen(&views.range, in_range);
            gpu_arithmetic::check_reach(&views.range, "range", origin, in_range, seen_in_range, &name(i))?;
            if let Some((grid, local)) = shadow_view {
                let in_shadow = (to_shadow.transform_point3(centre), radius);
                gpu_arithmetic::check_reach(grid, "shadow", local, in_shadow, seen(grid, in_shadow), &name(i))?;
            }
        }
    }
    // Where nothing shows in the range view, no pixel holds a z for an effect to change.
    if spheres.iter().any(|&sphere| seen(&views.range, sphere)) {
        gpu_arithmetic::check_effects(effects, &views.range, origin)?;
    }
    Ok(views)
}
