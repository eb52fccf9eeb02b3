//! Hypothesis verification (paper §4): render each hypothesis with its shadows, count on the
//! GPU how its synthetic image agrees with the sensed one, and turn the exact counts into the
//! six scores on the host in f64.

pub mod area;
mod batch;
mod counts;
mod hypothesis;
mod lanes;
mod report;
mod score_pass;
mod scores;
mod sensed;
mod verifier;

pub use counts::{Counts, CountsLayout};
pub use hypothesis::{HypothesisEntry, HypothesisFile, DEFAULT_TOLERANCE};
pub use lanes::MAX_CHUNKS_IN_FLIGHT;
pub use report::{CountsRecord, Record, ScoresRecord};
pub use scores::{score, BindingDetail, Scores};
pub use sensed::SensedImage;
pub use verifier::{
    Hypothesis, Model, Verification, Verifier, VerifySettings, CHUNK_COUNTS_BUDGET, EXACT_CHUNK, MAX_CHUNK,
};
