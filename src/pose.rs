//! Rigid poses (model → range frame), given as row-major 4×4 matrices in files and kept in
//! f64 on the host (docs/design.md "Coordinates"). A pose that is not rigid would silently scale
//! or shear the model, and a mirroring one would turn its solids inside out for culling
//! (src/mesh/solid.rs), so either is refused: when read from a file, and again where the
//! library takes a pose (`Renderer::render`, `Verifier::verify`).

use crate::error::{Error, Result};
use glam::{DMat3, DMat4};

/// How far the rotation part may stray from orthonormal (per entry of RᵀR − I).
pub const RIGIDITY_TOLERANCE: f64 = 1e-6;

/// Builds a pose from row-major rows, checking that it is a finite rigid transform; `owner`
/// ("object 2 (part.obj)", "hypothesis \"h7\"") starts the message of a refusal.
pub fn pose_from_rows(rows: [[f64; 4]; 4], owner: &str) -> Result<DMat4> {
    let pose = DMat4::from_cols_array_2d(&rows).transpose();
    check_rigid(&pose, owner)?;
    Ok(pose)
}

/// Checks that a pose is a finite rigid transform: a rotation (no scale, shear or mirror)
/// and a translation. `owner` starts the message of a refusal.
pub fn check_rigid(pose: &DMat4, owner: &str) -> Result<()> {
    let rows = pose_rows(pose);
    let bad = |why: &str| Err(Error::Scene(format!("{owner}: pose {rows:?} {why}")));
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return bad("has a non-finite entry");
    }
    if rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return bad("must have [0, 0, 0, 1] as its last row");
    }
    let rotation = DMat3::from_mat4(*pose);
    let error =
        (rotation.transpose() * rotation - DMat3::IDENTITY).to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if error > RIGIDITY_TOLERANCE || rotation.determinant() < 0.0 {
        return bad("is not a rigid transform (its 3×3 part must be a rotation)");
    }
    Ok(())
}

/// Row-major rows of a pose, as files write them.
pub fn pose_rows(pose: &DMat4) -> [[f64; 4]; 4] {
    pose.transpose().to_cols_array_2d()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sheared(by: f64) -> [[f64; 4]; 4] {
        [[1.0, by, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
    }

    /// The tolerance is inclusive: a shear of exactly RIGIDITY_TOLERANCE (RᵀR − I then has
    /// exactly that entry, its others 1e-12) passes, twice that is refused, as is a mirror.
    #[test]
    fn a_pose_may_stray_from_rigid_by_the_tolerance_and_no_more() {
        assert!(pose_from_rows(sheared(RIGIDITY_TOLERANCE), "object 1").is_ok());
        let e = pose_from_rows(sheared(2.0 * RIGIDITY_TOLERANCE), "object 1").unwrap_err().to_string();
        assert!(e.contains("object 1: pose [[1.0, 2e-6") && e.contains("is not a rigid transform"), "{e}");
        let mirror = [[-1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
        assert!(pose_from_rows(mirror, "object 1").is_err(), "a mirror is orthonormal, but not a rotation");
    }
}
