//! What scoring BOP results holds at once, measured by a counting allocator over every thread
//! (this binary's one test, so that nothing else allocates meanwhile): in shadow mode `exact`
//! the rows of one image are cast, scored and dropped one at a time, so eight rows hold no
//! more at once than one (within a third of a rendering, 16 bytes a pixel). All eight
//! renderings were held together, each checked against the budget alone: under a 5793²
//! image, 0.5 GB more a row, past any budget.

mod common;

use common::bop_dataset::*;
use common::counting::{process_peak_during, Counting};
use rangesynth::bop::{BopScorer, BopSettings, Dataset, ResultRow};
use rangesynth::limits::Ledger;
use rangesynth::shadow::{ShadowMode, ShadowSettings};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn rows_of_one_image_are_cast_one_at_a_time() {
    let truth = at(0.0, 0.0, 1000.0);
    let root = dataset("rows_held", &[(1, square(295..=344, 215..=264, 1000), vec![truth])]);
    let rows: Vec<ResultRow> = (0..8).map(|i| row(1, at(f64::from(i), 0.0, 1000.0))).collect();
    let peak_scoring = |rows: &[ResultRow]| {
        let ledger = Ledger::default();
        let dataset = Dataset::open(&root, "test", &ledger).unwrap();
        let settings = BopSettings { rig: rig(75.0), delta: DELTA, shadow: ShadowSettings::of(ShadowMode::Exact) };
        let mut scorer = BopScorer::new(&dataset, &settings, None, &ledger).unwrap();
        process_peak_during(|| assert_eq!(scorer.score_rows(rows).unwrap().len(), rows.len()))
    };
    let (one, eight) = (peak_scoring(&rows[..1]), peak_scoring(&rows));
    let rendering = 16 * 640 * 480;
    assert!(eight <= one + rendering / 3, "one row held {one} bytes at most, eight {eight}");
}
