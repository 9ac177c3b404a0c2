//! `caustic plot LOG... -o chart.svg`: the error against time, one line per frame of each log:
//! the estimated mean relative bound (solid) and, where the log has a reference, the true mean
//! relative error (dashed), on log-log axes.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

/// One curve: its label and (seconds, error) points.
struct Series {
    label: String,
    points: Vec<(f64, f64)>,
    dashed: bool,
}

/// Reads the estimated and true curves of every frame in `log`.
fn read_log(log: &Path) -> Result<Vec<Series>, String> {
    let text = std::fs::read_to_string(log).map_err(|e| format!("cannot read log {}: {e}", log.display()))?;
    let name = log.file_stem().map_or("log".into(), |s| s.to_string_lossy().into_owned());
    let mut frames: Vec<(i64, Vec<(f64, f64)>, Vec<(f64, f64)>)> = Vec::new();
    for (number, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let value: serde_json::Value = serde_json::from_str(line)
            .map_err(|e| format!("{} line {}: not a log line: {e}", log.display(), number + 1))?;
        let (frame, time) =
            (value["frame"].as_i64().unwrap_or(0), value["elapsed_s"].as_f64().unwrap_or(0.0));
        let index = match frames.iter().position(|f| f.0 == frame) {
            Some(i) => i,
            None => {
                frames.push((frame, Vec::new(), Vec::new()));
                frames.len() - 1
            }
        };
        if let Some(e) = value["error"]["mean"].as_f64().filter(|e| *e > 0.0) {
            frames[index].1.push((time.max(1e-3), e));
        }
        if let Some(e) = value["true"]["mean_relative"].as_f64().filter(|e| *e > 0.0) {
            frames[index].2.push((time.max(1e-3), e));
        }
    }
    let mut series = Vec::new();
    for (frame, estimated, truth) in frames {
        series.push(Series {
            label: format!("{name} frame {frame}: estimated bound"),
            points: estimated,
            dashed: false,
        });
        if !truth.is_empty() {
            series.push(Series {
                label: format!("{name} frame {frame}: true error (dots)"),
                points: truth,
                dashed: true,
            });
        }
    }
    Ok(series)
}

/// Draws the chart of `logs` to `out`.
pub fn plot(logs: &[PathBuf], out: &Path) -> Result<(), String> {
    let series: Vec<Series> =
        logs.iter().map(|l| read_log(l)).collect::<Result<Vec<_>, _>>()?.into_iter().flatten().collect();
    let points = series.iter().flat_map(|s| s.points.iter());
    let (t_max, e_min, e_max) =
        points.fold((1e-3f64, f64::MAX, 0.0f64), |(t, lo, hi), &(x, y)| (t.max(x), lo.min(y), hi.max(y)));
    if e_max <= 0.0 {
        return Err("the logs have no error values to plot".into());
    }
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(out, (900, 560)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Relative error against time", ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (1e-2f64..t_max * 1.2).log_scale(),
                (e_min * 0.8..e_max * 1.25).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc("elapsed time (s)")
            .y_desc("mean relative error")
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.3}"))
            .draw()?;
        for (i, s) in series.iter().enumerate() {
            let colour = Palette99::pick(i / 2).to_rgba();
            let style = ShapeStyle { color: colour, filled: false, stroke_width: 2 };
            let label = chart.draw_series(LineSeries::new(s.points.clone(), style))?;
            let label = label.label(s.label.clone());
            if s.dashed {
                label.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], colour));
            } else {
                label.legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                });
            }
            if s.dashed {
                chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
            }
        }
        chart.configure_series_labels().border_style(BLACK).background_style(WHITE.mix(0.8)).draw()?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| format!("cannot draw {}: {e}", out.display()))
}
