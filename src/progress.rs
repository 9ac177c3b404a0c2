//! Progress as the user sees it: a bar on the terminal, or JSON lines on stdout for the add-on.

use crate::monitor::ErrorStatus;

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ProgressStyle {
    /// A progress bar on the terminal (stderr).
    Bar,
    /// One JSON object per pass on stdout.
    Json,
    /// Nothing.
    None,
}

/// Prints one JSON line on stdout. A reader that has gone away (a closed pipe) does not stop the
/// render: its frames are still written.
fn json_line(line: serde_json::Value) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(stdout, "{line}").and_then(|()| stdout.flush());
}

/// The error and the forecast for the bar: "error 3.4%", "error 3.4% (2% in about 12 s)".
fn describe(status: ErrorStatus) -> String {
    let percent =
        |e: f64| format!("{}%", format!("{:.2}", e * 100.0).trim_end_matches('0').trim_end_matches('.'));
    let error = format!("error {}", percent(status.error));
    match (status.target, status.seconds_left) {
        (Some(target), Some(left)) => format!("{error} ({} in about {left:.0} s)", percent(target)),
        (Some(target), None) => format!("{error} (target {})", percent(target)),
        (None, _) => error,
    }
}

/// Shows passes as they finish.
pub struct Progress {
    style: ProgressStyle,
    bar: Option<indicatif::ProgressBar>,
    limit: Option<u64>,
}

impl Progress {
    /// A display for `frames` rendered together, for `limit` passes (or until the time budget or
    /// the target error).
    pub fn new(style: ProgressStyle, frames: &[i32], limit: Option<u64>) -> Self {
        let bar = (style == ProgressStyle::Bar).then(|| {
            let bar =
                indicatif::ProgressBar::with_draw_target(limit, indicatif::ProgressDrawTarget::stderr());
            // Without a pass count the time budget ends the frame: show passes and time only.
            let template = match limit {
                Some(_) => "{prefix} [{bar:40}] pass {pos}/{len} {elapsed_precise} eta {eta} {msg}",
                None => "{prefix} pass {pos} {elapsed_precise} {msg}",
            };
            let style = indicatif::ProgressStyle::with_template(template).expect("valid template");
            bar.set_style(style.progress_chars("=> "));
            bar.set_prefix(match frames {
                [frame] => format!("frame {frame}"),
                _ => format!("frames {}-{}", frames[0], frames[frames.len() - 1]),
            });
            bar
        });
        Progress { style, bar, limit }
    }

    /// Reports that `frames` have rendered `pass` passes, after `elapsed_s` seconds each (a frame's
    /// share of the time its block took), with the first frame's error as last measured. A JSON
    /// line is `{"frame", "frames", "pass", "passes", "elapsed_s"}`, where `frame` is the first of
    /// `frames`, plus `error` (the relative error bound's statistic), and with a target error
    /// `target_error` and, once it can be forecast, `seconds_left`.
    pub fn update(&self, frames: &[i32], pass: u64, elapsed_s: f64, status: Option<ErrorStatus>) {
        match self.style {
            ProgressStyle::Bar => {
                let bar = self.bar.as_ref().expect("bar style has a bar");
                bar.set_position(pass);
                if let Some(status) = status {
                    bar.set_message(describe(status));
                }
            }
            ProgressStyle::Json => {
                let mut line = serde_json::json!({"frame": frames[0], "frames": frames, "pass": pass,
                    "passes": self.limit, "elapsed_s": elapsed_s});
                if let Some(status) = status {
                    line["error"] = serde_json::json!(status.error);
                    if let Some(target) = status.target {
                        line["target_error"] = serde_json::json!(target);
                        line["seconds_left"] = serde_json::json!(status.seconds_left);
                    }
                }
                json_line(line)
            }
            ProgressStyle::None => {}
        }
    }

    /// Clears the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }

    /// Tells that the frame's EXR is written: a line on stderr, or a JSON line on stdout
    /// (`{"frame", "written", "passes", "elapsed_s", "stopped_by", "peak_memory_mib"}`) that the add-on can load at once.
    pub fn written(
        style: ProgressStyle,
        frame: i32,
        path: &std::path::Path,
        passes: u64,
        elapsed_s: f64,
        stopped_by: &str,
    ) {
        match style {
            ProgressStyle::Json => {
                json_line(serde_json::json!({"frame": frame, "written": path.display().to_string(),
                "passes": passes, "elapsed_s": elapsed_s, "stopped_by": stopped_by,
                "peak_memory_mib": crate::memory::peak_mib()}))
            }
            ProgressStyle::Bar => {
                eprintln!("caustic: wrote {} ({passes} passes, {elapsed_s:.1} s)", path.display())
            }
            ProgressStyle::None => {}
        }
    }
}
