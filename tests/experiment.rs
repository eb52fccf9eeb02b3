//! `rangesynth experiment --quick` end to end (validation on): the table and the summary
//! recomputed here, independently, from the `scores.jsonl` files it wrote; `rangesynth verify`
//! reproducing a view's `scores.jsonl` byte for byte from its `hypotheses.json` and
//! `range.exr`; and the sizes the issue asks of a quick run.

mod common;

use common::cli::{fresh_dir, rangesynth_command};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn rangesynth(args: &[&str], dir: &Path) -> std::process::Output {
    rangesynth_command().args(args).current_dir(dir).output().expect("the binary runs")
}

fn out_dir(name: &str) -> PathBuf {
    fresh_dir("experiment", name)
}

/// One hypothesis as scores.jsonl records it.
struct Line {
    view: String,
    correct: bool,
    shadow: f64,
    plain: f64,
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// Pairs won by the correct hypothesis, ties counting one half, over all pairs.
fn pairwise_auc(correct: &[f64], incorrect: &[f64]) -> f64 {
    let mut wins = 0.0;
    for c in correct {
        for i in incorrect {
            wins += if c > i {
                1.0
            } else if c == i {
                0.5
            } else {
                0.0
            };
        }
    }
    wins / (correct.len() * incorrect.len()) as f64
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300)
}

#[test]
fn the_quick_experiment_writes_figures_that_its_scores_reproduce() {
    let out = out_dir("quick");
    let run = rangesynth(&["experiment", "--quick", "--seed", "3", "--out", out.to_str().unwrap()], &out);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}{}", String::from_utf8_lossy(&run.stderr));

    let mut lines = Vec::new();
    let mut views: Vec<String> = std::fs::read_dir(out.join("views"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    views.sort();
    for view in &views {
        let text = std::fs::read_to_string(out.join("views").join(view).join("scores.jsonl")).unwrap();
        for line in text.lines() {
            let v: Value = serde_json::from_str(line).unwrap();
            lines.push(Line {
                view: view.clone(),
                correct: v["id"].as_str().unwrap().starts_with("correct"),
                shadow: v["s"].as_f64().unwrap(),
                plain: v["unshadowed"]["s"].as_f64().unwrap(),
            });
        }
    }
    let of = |correct: bool, plain: bool| -> Vec<f64> {
        lines.iter().filter(|l| l.correct == correct).map(|l| if plain { l.plain } else { l.shadow }).collect()
    };
    let (correct_n, incorrect_n) = (of(true, true).len(), of(false, true).len());
    // What a quick run must hold.
    assert!(views.len() >= 5, "{} views", views.len());
    assert!(correct_n >= 20 && incorrect_n >= 100, "{correct_n} correct, {incorrect_n} incorrect");
    for view in &views {
        let c = lines.iter().filter(|l| &l.view == view && l.correct).count();
        let i = lines.iter().filter(|l| &l.view == view && !l.correct).count();
        assert!(c > 0 && (10 * c..=30 * c).contains(&i), "{view}: {c} correct, {i} incorrect");
    }

    // The summary, recomputed.
    let summary: Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let keys = |v: &Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
    assert_eq!(keys(&summary), ["auc_plain", "auc_shadow", "correct", "incorrect", "top1_flips"]);
    assert_eq!(keys(&summary["correct"]), ["mean_plain", "mean_shadow", "n"]);
    assert_eq!(keys(&summary["top1_flips"]), ["to_correct", "to_incorrect"]);
    for (class, correct) in [("correct", true), ("incorrect", false)] {
        assert_eq!(summary[class]["n"].as_u64().unwrap() as usize, of(correct, true).len());
        assert!(close(summary[class]["mean_plain"].as_f64().unwrap(), mean(&of(correct, true))), "{class}");
        assert!(close(summary[class]["mean_shadow"].as_f64().unwrap(), mean(&of(correct, false))), "{class}");
    }
    assert!(close(summary["auc_plain"].as_f64().unwrap(), pairwise_auc(&of(true, true), &of(false, true))));
    assert!(close(summary["auc_shadow"].as_f64().unwrap(), pairwise_auc(&of(true, false), &of(false, false))));
    let top_correct = |view: &str, plain: bool| {
        let score = |l: &Line| if plain { l.plain } else { l.shadow };
        let of_view: Vec<&Line> = lines.iter().filter(|l| l.view == view).collect();
        let best = of_view.iter().map(|l| score(l)).fold(f64::NEG_INFINITY, f64::max);
        of_view.iter().find(|l| score(l) == best).unwrap().correct
    };
    let flips = |to_correct: bool| {
        views.iter().filter(|v| top_correct(v, true) != to_correct && top_correct(v, false) == to_correct).count()
    };
    assert_eq!(summary["top1_flips"]["to_correct"].as_u64().unwrap() as usize, flips(true));
    assert_eq!(summary["top1_flips"]["to_incorrect"].as_u64().unwrap() as usize, flips(false));

    // The table's summary lines, recomputed (population s.d.).
    let table = std::fs::read_to_string(out.join("table.md")).unwrap();
    for (class, correct, views_column) in
        [("correct", true, views.len().to_string()), ("incorrect", false, String::new())]
    {
        let (plain, shadow) = (of(correct, true), of(correct, false));
        let sd = |v: &[f64]| (v.iter().map(|x| (x - mean(v)).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        let increase = 100.0 * (mean(&shadow) - mean(&plain)) / mean(&plain);
        let line = format!(
            "| **all** | {views_column} | {class} | {} | {:.4e} | {:.4e} | {:.4e} | {:.4e} | {increase:.0} |",
            plain.len(),
            mean(&plain),
            sd(&plain),
            mean(&shadow),
            sd(&shadow)
        );
        assert!(table.contains(&line), "{line}\nnot in\n{table}");
    }
    assert!(stdout.contains("ROC AUC"), "the table is printed");

    // `verify` reproduces a view's scores byte for byte: a built-in's and a generated part's.
    for view in ["box-1", "stairs-1"] {
        let dir = out.join("views").join(view);
        let again = out.join(format!("{view}.again.jsonl"));
        let args =
            ["verify", "hypotheses.json", "--scene", "range.exr", "--compare-shadow", "--out", again.to_str().unwrap()];
        let run = rangesynth(&args, &dir);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
        assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(dir.join("scores.jsonl")).unwrap(), "{view}");
    }
    let decoder = png::Decoder::new(std::fs::File::open(out.join("scores.png")).unwrap());
    assert_eq!(decoder.read_info().expect("a PNG").info().width, 1200);
}

#[test]
fn the_same_seed_gives_the_same_experiment() {
    let (a, b) = (out_dir("seed-a"), out_dir("seed-b"));
    for d in [&a, &b] {
        let run = rangesynth(&["experiment", "--quick", "--seed", "5", "--out", d.to_str().unwrap()], d);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    }
    for file in ["summary.json", "table.md", "views/stairs-1/hypotheses.json", "views/stairs-1/scores.jsonl"] {
        assert_eq!(std::fs::read(a.join(file)).unwrap(), std::fs::read(b.join(file)).unwrap(), "{file}");
    }
}
