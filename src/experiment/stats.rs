//! The figures of `rangesynth experiment`, from every hypothesis' score with and without
//! shadowing: the per-model table laid out like the paper's Table 1, the ROC AUC of correct
//! against incorrect hypotheses, the top-1 flips, and the score distributions' plot.
//!
//! Means and standard deviations are over hypotheses (the population s.d.), so the summary
//! line weighs each model by its number of hypotheses, as the paper's does. The AUC is the
//! Mann–Whitney statistic, the probability that a correct hypothesis outscores an incorrect one,
//! ties counting one half. The top-1 hypothesis of a view is its highest-scoring one, the first
//! in the file among equals; a flip is a view whose top-1 changes between correct and incorrect
//! when shadowing is added.

use crate::error::Result;
use crate::plot::{self, FONT};
use plotters::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// One verified hypothesis.
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    pub view: String,
    /// The view's true model.
    pub model: String,
    pub correct: bool,
    /// s without shadowing.
    pub plain: f64,
    /// s with shadowing.
    pub shadow: f64,
}

/// Which of a hypothesis' two scores a figure reads.
type Score = fn(&Scored) -> f64;

fn plain(s: &Scored) -> f64 {
    s.plain
}

fn shadow(s: &Scored) -> f64 {
    s.shadow
}

/// Mean and population standard deviation, `None` for no values.
fn mean_sd(values: impl Iterator<Item = f64> + Clone) -> Option<(f64, f64)> {
    let n = values.clone().count();
    if n == 0 {
        return None;
    }
    let mean = values.clone().sum::<f64>() / n as f64;
    let variance = values.map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
    Some((mean, variance.sqrt()))
}

/// One class's figures.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClassSummary {
    pub n: usize,
    pub mean_shadow: Option<f64>,
    pub mean_plain: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Flips {
    pub to_correct: usize,
    pub to_incorrect: usize,
}

/// `summary.json`, with exactly these keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Summary {
    pub correct: ClassSummary,
    pub incorrect: ClassSummary,
    pub auc_shadow: Option<f64>,
    pub auc_plain: Option<f64>,
    pub top1_flips: Flips,
}

/// P(correct > incorrect) + ½ P(equal), over every pair; `None` when a class is empty.
pub fn auc(correct: &[f64], incorrect: &[f64]) -> Option<f64> {
    if correct.is_empty() || incorrect.is_empty() {
        return None;
    }
    let mut sorted = incorrect.to_vec();
    sorted.sort_by(f64::total_cmp);
    let wins: f64 = correct
        .iter()
        .map(|&c| {
            let below = sorted.partition_point(|&i| i < c);
            let equal = sorted[below..].partition_point(|&i| i <= c);
            below as f64 + 0.5 * equal as f64
        })
        .sum();
    Some(wins / (correct.len() as f64 * incorrect.len() as f64))
}

/// The views in first-seen order, each with its hypotheses in file order.
fn views(scored: &[Scored]) -> Vec<Vec<&Scored>> {
    let mut names: Vec<&str> = Vec::new();
    for s in scored {
        if !names.contains(&s.view.as_str()) {
            names.push(&s.view);
        }
    }
    names.iter().map(|name| scored.iter().filter(|s| s.view == *name).collect()).collect()
}

/// Whether the view's top-1 hypothesis by `score` is correct.
fn top_is_correct(view: &[&Scored], score: Score) -> bool {
    let mut best: Option<&Scored> = None;
    for &s in view {
        if best.is_none_or(|b| score(s) > score(b)) {
            best = Some(s);
        }
    }
    best.is_some_and(|b| b.correct)
}

pub fn summarise(scored: &[Scored]) -> Summary {
    let class = |correct: bool| {
        let of = scored.iter().filter(move |s| s.correct == correct);
        ClassSummary {
            n: of.clone().count(),
            mean_shadow: mean_sd(of.clone().map(|s| s.shadow)).map(|m| m.0),
            mean_plain: mean_sd(of.map(|s| s.plain)).map(|m| m.0),
        }
    };
    let values = |correct: bool, score: Score| -> Vec<f64> {
        scored.iter().filter(|s| s.correct == correct).map(score).collect()
    };
    let mut flips = Flips { to_correct: 0, to_incorrect: 0 };
    for view in views(scored) {
        match (top_is_correct(&view, plain), top_is_correct(&view, shadow)) {
            (false, true) => flips.to_correct += 1,
            (true, false) => flips.to_incorrect += 1,
            _ => {}
        }
    }
    Summary {
        correct: class(true),
        incorrect: class(false),
        auc_shadow: auc(&values(true, shadow), &values(false, shadow)),
        auc_plain: auc(&values(true, plain), &values(false, plain)),
        top1_flips: flips,
    }
}

fn number(value: Option<f64>) -> String {
    value.map_or("N/A".into(), |v| format!("{v:.4e}"))
}

fn percent_increase(plain: Option<f64>, shadow: Option<f64>) -> String {
    match (plain, shadow) {
        (Some(p), Some(s)) if p > 0.0 => format!("{:.0}", 100.0 * (s - p) / p),
        _ => "N/A".into(),
    }
}

/// `table.md`: per model, as the paper's Table 1, then the summary lines, the AUC and the
/// top-1 figures.
pub fn table_markdown(scored: &[Scored]) -> String {
    let mut models: Vec<&str> = Vec::new();
    for s in scored {
        if !models.contains(&s.model.as_str()) {
            models.push(&s.model);
        }
    }
    let mut text = String::from(
        "| model | # views used | correct/incorrect | # hypotheses | average score (no shadowing) | standard deviation | \
         average score (shadowing) | standard deviation | increase (percent) |\n|---|---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    let mut line = |model: &str, views: String, correct: bool, of: &[&Scored]| {
        let plain = mean_sd(of.iter().map(|s| s.plain));
        let shadow = mean_sd(of.iter().map(|s| s.shadow));
        writeln!(
            text,
            "| {model} | {views} | {} | {} | {} | {} | {} | {} | {} |",
            if correct { "correct" } else { "incorrect" },
            of.len(),
            number(plain.map(|m| m.0)),
            number(plain.map(|m| m.1)),
            number(shadow.map(|m| m.0)),
            number(shadow.map(|m| m.1)),
            percent_increase(plain.map(|m| m.0), shadow.map(|m| m.0)),
        )
        .expect("writing to a String");
    };
    for model in &models {
        let of: Vec<&Scored> = scored.iter().filter(|s| s.model == *model).collect();
        let mut seen: Vec<&str> = of.iter().map(|s| s.view.as_str()).collect();
        seen.dedup();
        for correct in [true, false] {
            let class: Vec<&Scored> = of.iter().copied().filter(|s| s.correct == correct).collect();
            let views = if correct { seen.len().to_string() } else { String::new() };
            line(model, views, correct, &class);
        }
    }
    for correct in [true, false] {
        let class: Vec<&Scored> = scored.iter().filter(|s| s.correct == correct).collect();
        line("**all**", if correct { views(scored).len().to_string() } else { String::new() }, correct, &class);
    }
    let summary = summarise(scored);
    let all_views = views(scored);
    let top = |score: Score| all_views.iter().filter(|v| top_is_correct(v, score)).count();
    writeln!(
        text,
        "\nROC AUC, correct against incorrect: {} without shadowing, {} with shadowing.\n\n\
         Top-1 hypothesis correct in {} of {} views without shadowing, {} with shadowing; \
         shadowing turned an incorrect top-1 into a correct one in {} views, and a correct one into \
         an incorrect one in {}.",
        number(summary.auc_plain),
        number(summary.auc_shadow),
        top(plain),
        all_views.len(),
        top(shadow),
        summary.top1_flips.to_correct,
        summary.top1_flips.to_incorrect,
    )
    .expect("writing to a String");
    text
}

/// log10 of a score for the histograms; 0 and scores below `floor` go to the leftmost bin.
fn log_score(s: f64, floor: f64) -> f64 {
    s.max(floor).log10()
}

/// Scores below this share the histograms' leftmost bin with 0 (rejected hypotheses).
const SMALLEST_PLOTTED: f64 = 1e-5;

/// `scores.png`: histograms of log10 s, correct against incorrect (each as a fraction of its
/// class), without and with shadowing side by side. Scores of 0 (rejected hypotheses) and
/// below `SMALLEST_PLOTTED` sit in the leftmost bin.
pub fn write_plot(path: &Path, scored: &[Scored]) -> Result<()> {
    const BINS: usize = 30;
    let positive = scored.iter().flat_map(|s| [s.plain, s.shadow]).filter(|&s| s > 0.0);
    let floor = positive.clone().fold(1.0f64, f64::min).max(SMALLEST_PLOTTED);
    let (lo, hi) = (floor.log10(), positive.fold(floor, f64::max).log10().max(floor.log10() + 1.0));
    let width = (hi - lo) / BINS as f64;
    let histogram = |correct: bool, score: Score| -> Vec<f64> {
        let of: Vec<f64> = scored.iter().filter(|s| s.correct == correct).map(score).collect();
        let mut counts = vec![0.0; BINS];
        for s in &of {
            let bin = ((log_score(*s, floor) - lo) / width).floor().clamp(0.0, (BINS - 1) as f64) as usize;
            counts[bin] += 1.0 / of.len().max(1) as f64;
        }
        counts
    };
    let panels: [(&str, Score); 2] = [("without shadowing", plain), ("with shadowing", shadow)];
    let top = panels
        .iter()
        .flat_map(|&(_, score)| histogram(true, score).into_iter().chain(histogram(false, score)))
        .fold(0.0f64, f64::max)
        * 1.1;
    plot::write_plot(path, (1200, 520), |area| {
        let halves = area.split_evenly((1, 2));
        for (half, &(title, score)) in halves.iter().zip(&panels) {
            let mut chart = ChartBuilder::on(half)
                .caption(format!("verification score s, {title}"), (FONT, 20))
                .margin(15)
                .x_label_area_size(45)
                .y_label_area_size(60)
                .build_cartesian_2d(lo..hi, 0.0..top.max(1e-3))?;
            chart
                .configure_mesh()
                .x_desc(format!("log10 s (0 and below {SMALLEST_PLOTTED:e} in the leftmost bin)"))
                .y_desc("fraction of the class")
                .label_style((FONT, 13))
                .axis_desc_style((FONT, 14))
                .draw()?;
            for (correct, colour, name) in [(false, RED, "incorrect"), (true, GREEN, "correct")] {
                let counts = histogram(correct, score);
                chart
                    .draw_series(counts.iter().enumerate().map(|(i, &c)| {
                        let x0 = lo + i as f64 * width;
                        Rectangle::new([(x0, 0.0), (x0 + width, c)], colour.mix(0.45).filled())
                    }))?
                    .label(name)
                    .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.mix(0.45).filled()));
            }
            plot::draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scored(view: &str, correct: bool, plain: f64, shadow: f64) -> Scored {
        Scored { view: view.into(), model: "m".into(), correct, plain, shadow }
    }

    #[test]
    fn auc_counts_wins_and_half_ties() {
        assert_eq!(auc(&[3.0, 1.0], &[2.0, 1.0, 0.0]), Some((3.0 + 1.5) / 6.0));
        assert_eq!(auc(&[], &[1.0]), None);
    }

    #[test]
    fn flips_compare_each_views_top_hypothesis() {
        let all = [
            // Shadowing lifts the correct one above the incorrect one: a flip to correct.
            scored("a", false, 0.5, 0.4),
            scored("a", true, 0.4, 0.6),
            // Correct either way.
            scored("b", true, 0.9, 0.9),
            scored("b", false, 0.1, 0.2),
            // A tie goes to the first: the correct one, then the incorrect one wins.
            scored("c", true, 0.3, 0.3),
            scored("c", false, 0.3, 0.35),
        ];
        let summary = summarise(&all);
        assert_eq!(summary.top1_flips, Flips { to_correct: 1, to_incorrect: 1 });
        assert_eq!(summary.correct.n, 3);
        assert_eq!(summary.incorrect.mean_plain, Some((0.5 + 0.1 + 0.3) / 3.0));
    }
}
