//! The knobs `rangesynth accuracy` turns, and the names its table gives each setting: the
//! shadow mode (`exact`, `label`, `depth`, `none`), the shadow buffer's columns per range column
//! (`x1`, `x2`, `x4`), the label test's 2×2 neighbourhood (`2x2`), the raster path (`compute`),
//! and the tessellation of curved built-ins (`N=16`), as in `depth x2` or `depth x1 N=16`.

use crate::error::Result;
use crate::mesh::canonical_builtin_name;
use crate::render::Raster;
use crate::shadow::{Neighbourhood, ShadowMode, ShadowSettings};

/// One point of the sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setting {
    pub shadow: ShadowSettings,
    pub raster: Raster,
    /// Sides (cylinders) and segments (spheres) of every curved built-in, where set; measured
    /// against the shape itself (scenes.rs `REFERENCE_TESSELLATION`).
    pub tessellation: Option<u32>,
}

impl Setting {
    fn of(mode: ShadowMode, columns: u32) -> Self {
        Self {
            shadow: ShadowSettings { columns, ..ShadowSettings::of(mode) },
            raster: Raster::Graphics,
            tessellation: None,
        }
    }

    /// The setting's name in the table: the mode, then what differs from its plain form.
    pub fn name(&self) -> String {
        let mut name = self.shadow.mode.as_str().to_string();
        if matches!(self.shadow.mode, ShadowMode::Label | ShadowMode::Depth) {
            if self.shadow.neighbourhood == Neighbourhood::Square2 {
                name += " 2x2";
            }
            name += &format!(" x{}", self.shadow.columns);
        }
        if self.raster == Raster::Compute {
            name += " compute";
        }
        if let Some(n) = self.tessellation {
            name += &format!(" N={n}");
        }
        name
    }
}

/// The settings of a sweep, fastest knobs first; `compute` where the device has the compute
/// rasterizer. `--quick` keeps one point of each knob beside the plain modes.
pub fn sweep_settings(quick: bool, compute: bool) -> Vec<Setting> {
    let mut settings = vec![Setting::of(ShadowMode::None, 1)];
    let columns: &[u32] = if quick { &[1, 2] } else { &[1, 2, 4] };
    for mode in [ShadowMode::Label, ShadowMode::Depth] {
        settings.extend(columns.iter().map(|&k| Setting::of(mode, k)));
    }
    let square = ShadowSettings { neighbourhood: Neighbourhood::Square2, ..ShadowSettings::of(ShadowMode::Label) };
    settings.push(Setting { shadow: square, ..Setting::of(ShadowMode::Label, 1) });
    if compute {
        settings.push(Setting { raster: Raster::Compute, ..Setting::of(ShadowMode::Depth, 1) });
    }
    let tessellations: &[u32] = if quick { &[16, 64] } else { &[12, 24, 48, 96, 192] };
    settings
        .extend(tessellations.iter().map(|&n| Setting { tessellation: Some(n), ..Setting::of(ShadowMode::Depth, 1) }));
    settings.push(Setting::of(ShadowMode::Exact, 1));
    settings
}

/// `model` with `n` sides or segments where it is a curved built-in (`builtin:cylinder`,
/// `builtin:sphere`); `None` for any other model.
pub fn retessellated(model: &str, n: u32) -> Result<Option<String>> {
    if !model.starts_with("builtin:") {
        return Ok(None);
    }
    let canonical = canonical_builtin_name(model)?;
    Ok(["builtin:cylinder", "builtin:sphere"]
        .into_iter()
        .find(|kind| canonical.starts_with(&format!("{kind}:")))
        .map(|kind| format!("{kind}:{n}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn setting_names_say_the_mode_and_the_scale() {
        let names: Vec<String> = sweep_settings(false, true).iter().map(Setting::name).collect();
        for expected in
            ["none", "label x1", "label x4", "label 2x2 x1", "depth x2", "depth x1 compute", "depth x1 N=12", "exact"]
        {
            assert!(names.iter().any(|n| n == expected), "{expected} in {names:?}");
        }
        let unique: std::collections::HashSet<&String> = names.iter().collect();
        assert_eq!(unique.len(), names.len(), "names are unique: {names:?}");
    }

    #[test]
    fn only_curved_built_ins_are_retessellated() {
        assert_eq!(retessellated("builtin:sphere", 16).unwrap().as_deref(), Some("builtin:sphere:16"));
        assert_eq!(retessellated("builtin:cylinder:48", 8).unwrap().as_deref(), Some("builtin:cylinder:8"));
        assert_eq!(retessellated("builtin:step", 8).unwrap(), None);
        assert_eq!(retessellated("part.obj", 8).unwrap(), None);
    }
}
