//! What `rangesynth accuracy` writes: `accuracy.csv` (one line per setting and scene, under
//! [`CSV_HEADER`], which scripts rely on), the table it prints, and `accuracy.png`, the error
//! of each setting against its time with the Pareto front marked.

use super::Row;
use crate::error::Result;
use crate::io::write_atomically;
use crate::plot::{self, FONT};
use plotters::prelude::*;
use std::fmt;
use std::io::Write;
use std::path::Path;

/// The CSV's header line, exactly.
pub const CSV_HEADER: &str = "setting,scene,pixels,wrong_pixels,wrong_pct,max_abs_dz,score_abs_error,ms_per_pose";

/// Writes the rows under [`CSV_HEADER`], atomically.
pub fn write_csv(path: &Path, rows: &[Row]) -> Result<()> {
    write_atomically(path, |file| {
        let mut text = format!("{CSV_HEADER}\n");
        for r in rows {
            text += &format!(
                "{},{},{},{},{:.4},{:e},{:e},{:.3}\n",
                r.setting,
                r.scene,
                r.pixels,
                r.wrong_pixels,
                r.wrong_pct,
                r.max_abs_dz,
                r.score_abs_error,
                r.ms_per_pose
            );
        }
        file.write_all(text.as_bytes()).map_err(|e| crate::Error::io(path, e))
    })
}

/// The rows as the command prints them.
pub struct Table<'a>(pub &'a [Row]);

impl fmt::Display for Table<'_> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        writeln!(
            f,
            "{:<18} {:<11} {:>8} {:>8} {:>10} {:>9} {:>9} {:>10}",
            "setting", "scene", "wrong", "wrong %", "max |dz|", "|ds|", "ms/pose", "render ms"
        )?;
        for r in self.0 {
            writeln!(
                f,
                "{:<18} {:<11} {:>8} {:>8.3} {:>10.2e} {:>9.4} {:>9.2} {:>10.2}",
                r.setting,
                r.scene,
                r.wrong_pixels,
                r.wrong_pct,
                r.max_abs_dz,
                r.score_abs_error,
                r.ms_per_pose,
                r.render_ms
            )?;
        }
        Ok(())
    }
}

/// Each setting's means over its scenes, as the command prints them after the table, the
/// Pareto front's settings marked `*`.
pub struct Summary<'a>(pub &'a [Row]);

impl fmt::Display for Summary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let summaries = summarise(self.0);
        let front = pareto_front(summaries.iter().filter(|s| !s.tessellated));
        writeln!(f, "\nmeans over scenes (* on the Pareto front; N= settings: curved scenes only)")?;
        writeln!(f, "  {:<18} {:>9} {:>9}", "setting", "wrong %", "ms/pose")?;
        for s in &summaries {
            let mark = if front.iter().any(|p| p.setting == s.setting) { '*' } else { ' ' };
            writeln!(f, "{mark} {:<18} {:>9.3} {:>9.2}", s.setting, s.wrong_pct, s.ms_per_pose)?;
        }
        Ok(())
    }
}

/// One setting over its scenes: mean time per pose and mean % wrong pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct SettingSummary {
    pub setting: String,
    pub ms_per_pose: f64,
    pub wrong_pct: f64,
    pub tessellated: bool,
}

/// Each setting's means over the scenes it was measured on, in first-seen order.
pub fn summarise(rows: &[Row]) -> Vec<SettingSummary> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.setting.as_str()) {
            names.push(&r.setting);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let of: Vec<&Row> = rows.iter().filter(|r| r.setting == name).collect();
            let mean = |f: &dyn Fn(&Row) -> f64| of.iter().map(|r| f(r)).sum::<f64>() / of.len() as f64;
            SettingSummary {
                setting: name.to_string(),
                ms_per_pose: mean(&|r| r.ms_per_pose),
                wrong_pct: mean(&|r| r.wrong_pct),
                tessellated: of[0].tessellated,
            }
        })
        .collect()
}

/// The summaries no other beats in both time and error (the Pareto front), by time.
pub fn pareto_front<'a>(summaries: impl IntoIterator<Item = &'a SettingSummary>) -> Vec<&'a SettingSummary> {
    let mut by_time: Vec<&SettingSummary> = summaries.into_iter().collect();
    by_time.sort_by(|a, b| a.ms_per_pose.total_cmp(&b.ms_per_pose).then(a.wrong_pct.total_cmp(&b.wrong_pct)));
    let mut front: Vec<&SettingSummary> = Vec::new();
    for s in by_time {
        if front.last().is_none_or(|best| s.wrong_pct < best.wrong_pct) {
            front.push(s);
        }
    }
    front
}

/// Draws each setting's mean error (log scale; none wrong on the bottom axis) against its mean
/// time per pose (log scale), with the Pareto front of the settings measured on every scene
/// joined in red. Tessellation settings, measured on the curved scenes only, are green and
/// stay off the front.
pub fn write_plot(path: &Path, rows: &[Row]) -> Result<()> {
    let summaries = summarise(rows);
    let front = pareto_front(summaries.iter().filter(|s| !s.tessellated));
    let (lo, hi) =
        summaries.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| (lo.min(s.ms_per_pose), hi.max(s.ms_per_pose)));
    let (lo, hi) = (lo.max(1e-3) / 1.6, hi.max(1e-3) * 1.6);
    let smallest = summaries.iter().map(|s| s.wrong_pct).filter(|&w| w > 0.0).fold(1.0f64, f64::min);
    let floor = smallest / 4.0;
    let top = summaries.iter().map(|s| s.wrong_pct).fold(floor, f64::max) * 2.0;
    let y = |s: &SettingSummary| s.wrong_pct.max(floor);
    plot::write_plot(path, (1100, 750), |area| {
        let mut chart = ChartBuilder::on(area)
            .caption("What accuracy costs: error against exact shadowing vs time per pose", (FONT, 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d((lo..hi).log_scale(), (floor..top).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("wall ms per pose (verifying a batch)")
            .y_desc("pixels wrong vs exact, % (mean over scenes; 0 on the bottom axis)")
            .x_labels(12)
            .x_label_formatter(&|x| format!("{x:.2}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .label_style((FONT, 14))
            .axis_desc_style((FONT, 16))
            .draw()?;
        chart
            .draw_series(LineSeries::new(front.iter().map(|s| (s.ms_per_pose, y(s))), RED.stroke_width(2)))?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        let colour = |s: &SettingSummary| match (front.iter().any(|f| f.setting == s.setting), s.tessellated) {
            (true, _) => RED,
            (false, true) => GREEN,
            (false, false) => BLUE,
        };
        chart
            .draw_series(summaries.iter().map(|s| Circle::new((s.ms_per_pose, y(s)), 5, colour(s).filled())))?
            .label("tessellation N of curved built-ins (green: curved scenes only, vs the shape)")
            .legend(|(x, y)| Circle::new((x + 10, y), 5, GREEN.filled()));
        // Labels alternate above and below their points, so neighbours do not overprint.
        let mut by_time: Vec<&SettingSummary> = summaries.iter().collect();
        by_time.sort_by(|a, b| a.ms_per_pose.total_cmp(&b.ms_per_pose));
        chart.draw_series(by_time.iter().enumerate().map(|(i, s)| {
            let dy = if i % 2 == 0 { -18 } else { 6 };
            EmptyElement::at((s.ms_per_pose, y(s))) + Text::new(s.setting.clone(), (8, dy), (FONT, 13))
        }))?;
        plot::draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary(setting: &str, ms_per_pose: f64, wrong_pct: f64) -> SettingSummary {
        SettingSummary { setting: setting.into(), ms_per_pose, wrong_pct, tessellated: false }
    }

    #[test]
    fn the_pareto_front_keeps_what_nothing_beats_in_both() {
        let all = [
            summary("fast rough", 1.0, 5.0),
            summary("slow rough", 3.0, 6.0),
            summary("middle", 2.0, 1.0),
            summary("worse middle", 2.5, 1.0),
            summary("exact", 10.0, 0.0),
        ];
        let names: Vec<&str> = pareto_front(&all).iter().map(|s| s.setting.as_str()).collect();
        assert_eq!(names, ["fast rough", "middle", "exact"]);
    }
}
