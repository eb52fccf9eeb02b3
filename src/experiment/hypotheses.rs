//! The hypotheses a recognizer would propose for one view of `rangesynth experiment`: a few
//! correct ones (the true model, its pose off by a small rotation and translation as a real
//! estimate is, bound to the surfaces the image shows) and, for each, eleven incorrect ones:
//! other models where the part is, the true model turned upside down, wrong poses, and the
//! true pose with wrong bindings. The kind starts each id (`correct-1`, `other-3`, `flip-2`,
//! `pose-4`, `bindings-1`).

use crate::mesh::Mesh;
use glam::{DMat4, DQuat, DVec3};
use rand::seq::SliceRandom;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Correct hypotheses per view.
pub const CORRECT_PER_VIEW: usize = 3;
/// Incorrect hypotheses per view, by kind: other models, flips, wrong poses, wrong bindings.
const OTHERS: usize = 12;
const FLIPS: usize = 6;
const WRONG_POSES: usize = 10;
const WRONG_BINDINGS: usize = 5;

/// The id prefix of correct hypotheses.
pub const CORRECT: &str = "correct";

/// A model a hypothesis may name: its reference (as the hypothesis file gives it) and its mesh.
pub struct Candidate<'a> {
    pub reference: &'a str,
    pub mesh: &'a Mesh,
}

impl Candidate<'_> {
    fn surfaces(&self) -> u32 {
        self.mesh.surface_count()
    }

    /// The lowest z of its vertices under `pose`: how far a flipped part must rise to rest on
    /// the table again.
    fn lowest(&self, pose: &DMat4) -> f64 {
        (0..self.mesh.positions.len() as u32)
            .map(|v| pose.transform_point3(self.mesh.vertex(v)).z)
            .fold(f64::INFINITY, f64::min)
    }
}

/// One proposed hypothesis.
pub struct Proposal {
    pub id: String,
    pub model: String,
    pub pose: DMat4,
    pub bindings: Vec<(u32, u32)>,
}

/// A small error like a real pose estimate's: a rotation of about 1.5° about a random axis
/// through `centre`, and a translation of about 0.015 units.
fn estimate_error(rng: &mut ChaCha8Rng, centre: DVec3) -> DMat4 {
    let axis =
        DVec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)).normalize_or(DVec3::Z);
    let angle = normal(rng) * 1.5f64.to_radians();
    let shift = DVec3::new(normal(rng), normal(rng), normal(rng)) * 0.015;
    DMat4::from_translation(shift + centre)
        * DMat4::from_quat(DQuat::from_axis_angle(axis, angle))
        * DMat4::from_translation(-centre)
}

/// A standard normal draw (Box–Muller).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let (u, v): (f64, f64) = (rng.gen_range(f64::EPSILON..1.0), rng.gen());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// The hypotheses of one view: `truth` is the true model among `candidates`, posed at `pose`
/// with its centre at `centre` (range frame); `visible` are its surfaces the sensed image shows
/// (scene label = surface id), most populous first.
pub fn propose(
    rng: &mut ChaCha8Rng,
    candidates: &[Candidate],
    truth: usize,
    (pose, centre): (DMat4, DVec3),
    visible: &[u32],
) -> Vec<Proposal> {
    let true_model = &candidates[truth];
    let true_bindings: Vec<(u32, u32)> = visible.iter().map(|&s| (s, s)).collect();
    let mut out = Vec::new();
    let mut push = |id: String, model: &str, pose: DMat4, bindings: Vec<(u32, u32)>| {
        out.push(Proposal { id, model: model.to_string(), pose, bindings })
    };
    for k in 1..=CORRECT_PER_VIEW {
        let estimate = estimate_error(rng, centre) * pose;
        push(format!("{CORRECT}-{k}"), true_model.reference, estimate, true_bindings.clone());
    }
    // Other models where the part is, turned at random about z, the largest segments bound to
    // surfaces of theirs at random.
    let others: Vec<usize> = (0..candidates.len()).filter(|&i| i != truth).collect();
    for k in 1..=OTHERS {
        let other = &candidates[others[(k - 1) % others.len()]];
        let turn = DMat4::from_rotation_z(rng.gen_range(0.0..std::f64::consts::TAU));
        let placed = DMat4::from_translation(DVec3::new(centre.x, centre.y, 0.0)) * turn;
        let mut surfaces: Vec<u32> = (1..=other.surfaces()).collect();
        surfaces.shuffle(rng);
        let bindings = visible.iter().take(3).zip(surfaces).map(|(&scene, model)| (scene, model)).collect();
        push(format!("other-{k}"), other.reference, placed, bindings);
    }
    // Flips: the part turned upside down (about x or about y through its centre) and rested on
    // the table again, its surfaces bound as they are seen: the outline may match, the surfaces
    // do not. (A turn about the vertical can be a symmetry of the part, which would make a
    // correct hypothesis of an "incorrect" one; upside down, top and bottom trade places.)
    let single = true_model.surfaces() == 1;
    for k in (1..=FLIPS).filter(|_| !single) {
        let about = DMat4::from_translation(centre);
        let flip = match k % 2 {
            0 => about * DMat4::from_rotation_y(std::f64::consts::PI) * about.inverse(),
            _ => about * DMat4::from_rotation_x(std::f64::consts::PI) * about.inverse(),
        };
        let flipped = estimate_error(rng, centre) * flip * pose;
        let rest = DMat4::from_translation(DVec3::new(0.0, 0.0, -true_model.lowest(&flipped)));
        push(format!("flip-{k}"), true_model.reference, rest * flipped, true_bindings.clone());
    }
    // Wrong poses, half of them near misses (moved 0.1 to 0.3 units and turned 5° to 20° either
    // way about z, as a recognizer's mis-estimated features give), half gross (0.3 to 0.8 units,
    // 20° to 90°). A part of one surface (the sphere), which no flip or binding can get wrong,
    // has more of them instead.
    let wrong_poses = WRONG_POSES + if single { FLIPS + WRONG_BINDINGS } else { 0 };
    for k in 1..=wrong_poses {
        let ((near, far), (least, most)) = match k % 2 {
            1 => ((0.1, 0.3), (5f64, 20f64)),
            _ => ((0.3, 0.8), (20.0, 90.0)),
        };
        let direction = rng.gen_range(0.0..std::f64::consts::TAU);
        let distance = rng.gen_range(near..far);
        let angle = rng.gen_range(least..most).to_radians() * if rng.gen() { 1.0 } else { -1.0 };
        let moved = DVec3::new(direction.cos(), direction.sin(), 0.0) * distance;
        let about = DMat4::from_translation(centre);
        let wrong = DMat4::from_translation(moved) * about * DMat4::from_rotation_z(angle) * about.inverse() * pose;
        push(format!("pose-{k}"), true_model.reference, wrong, true_bindings.clone());
    }
    // The true pose with the visible surfaces bound to the wrong ones.
    for k in (1..=WRONG_BINDINGS).filter(|_| !single) {
        let estimate = estimate_error(rng, centre) * pose;
        let mut wrong: Vec<u32> = (1..=true_model.surfaces()).collect();
        wrong.shuffle(rng);
        let bindings = visible
            .iter()
            .enumerate()
            .map(|(i, &s)| {
                let mut m = wrong[i % wrong.len()];
                if m == s {
                    m = m % true_model.surfaces() + 1;
                }
                (s, m)
            })
            .collect();
        push(format!("bindings-{k}"), true_model.reference, estimate, bindings);
    }
    out
}
