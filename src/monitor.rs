//! Watching a frame's error while its passes run: log lines (`--log`, JSON lines), the true error
//! against a reference (`--reference`), and the stopping rule (`--target-error`).
//!
//! A log line is written after passes 1, 2, 4, 8, ... and after the last pass (which also says
//! what stopped the frame), so that error against time can be plotted on log axes.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde_json::json;

use crate::error::{
    image_error, pixel_errors, summarize, true_error, ErrorSummary, PixelError, Statistic, TrueError,
};
use crate::film::Film;

/// Passes before a target error may stop a frame: the variance estimated from fewer passes is too
/// uncertain itself (a mean bound of 0.25 was once met after 2 passes at a true error of 0.69).
const MIN_PASSES_TO_STOP: u64 = 16;

/// What `caustic render` was asked about errors.
#[derive(Clone, Debug)]
pub struct ErrorSettings {
    /// Confidence of the bound (0.9: 90% of pixels should be within it).
    pub confidence: f64,
    /// The JSON-lines log, if any.
    pub log: Option<PathBuf>,
    /// A converged reference EXR (`####` is replaced by the frame number), if any.
    pub reference: Option<PathBuf>,
    /// Stop a frame when this statistic of the relative bound falls below the target.
    pub target: Option<(f64, Statistic)>,
}

impl Default for ErrorSettings {
    fn default() -> Self {
        ErrorSettings { confidence: 0.9, log: None, reference: None, target: None }
    }
}

/// What ended a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// `--passes` (or the default pass count) was reached.
    Passes,
    /// `--time-budget` ran out.
    TimeBudget,
    /// `--target-error` was met.
    TargetError,
}

impl StopReason {
    /// The name used in logs and progress lines.
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::Passes => "passes",
            StopReason::TimeBudget => "time_budget",
            StopReason::TargetError => "target_error",
        }
    }
}

/// Reads the luminance (Rec.709 weights of `Combined.R/G/B`, or `R/G/B`) of an EXR.
pub fn read_luminance(path: &Path, what: &str) -> Result<(usize, usize, Vec<f64>), String> {
    use exr::prelude::read_all_flat_layers_from_file;
    let image = read_all_flat_layers_from_file(path)
        .map_err(|e| format!("cannot read {what} {}: {e}", path.display()))?;
    let layer = image.layer_data.first().ok_or_else(|| format!("{what} {}: no image", path.display()))?;
    let channel = |name: &str| -> Result<Vec<f32>, String> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| {
                let n = c.name.to_string();
                n == format!("Combined.{name}") || n == name
            })
            .map(|c| c.sample_data.values_as_f32().collect())
            .ok_or_else(|| format!("{what} {}: no channel Combined.{name} or {name}", path.display()))
    };
    let (r, g, b) = (channel("R")?, channel("G")?, channel("B")?);
    let y = (0..r.len())
        .map(|i| 0.2126 * f64::from(r[i]) + 0.7152 * f64::from(g[i]) + 0.0722 * f64::from(b[i]))
        .collect();
    Ok((layer.size.0, layer.size.1, y))
}

/// The luminance error of the EXR `image` against the EXR `reference`; refuses different sizes.
pub fn compare(image: &Path, reference: &Path) -> Result<TrueError, String> {
    let (w, h, values) = read_luminance(image, "image")?;
    let (rw, rh, truth) = read_luminance(reference, "reference")?;
    if (w, h) != (rw, rh) {
        return Err(format!(
            "{} is {w}x{h}, the reference {} is {rw}x{rh}",
            image.display(),
            reference.display()
        ));
    }
    Ok(image_error(&values, &truth))
}

/// Watches one frame.
pub struct Monitor {
    settings: ErrorSettings,
    frame: i32,
    reference: Option<Vec<f64>>,
    log: Option<std::fs::File>,
    next_log_pass: u64,
}

impl Monitor {
    /// A monitor for `frame` of a `width` x `height` film; checks the reference's size.
    pub fn new(settings: &ErrorSettings, frame: i32, width: u32, height: u32) -> Result<Self, String> {
        let reference = match &settings.reference {
            Some(pattern) => {
                let path = PathBuf::from(pattern.to_string_lossy().replace("####", &format!("{frame:04}")));
                let (w, h, y) = read_luminance(&path, "reference")?;
                if (w, h) != (width as usize, height as usize) {
                    return Err(format!(
                        "reference {} is {w}x{h}, the render is {width}x{height}",
                        path.display()
                    ));
                }
                Some(y)
            }
            None => None,
        };
        let log = match &settings.log {
            Some(path) => Some(
                std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(path)
                    .map_err(|e| format!("cannot open log {}: {e}", path.display()))?,
            ),
            None => None,
        };
        Ok(Monitor { settings: settings.clone(), frame, reference, log, next_log_pass: 1 })
    }

    /// Whether anything needs the error after each pass.
    fn watching(&self) -> bool {
        self.log.is_some() || self.settings.target.is_some()
    }

    /// Called after each pass: logs when due, and says whether the target error is met.
    pub fn after_pass(&mut self, film: &Film, elapsed_s: f64, photons: u64) -> Result<bool, String> {
        if !self.watching() {
            return Ok(false);
        }
        let due = film.passes >= self.next_log_pass;
        if !due && self.settings.target.is_none() {
            return Ok(false);
        }
        let errors = pixel_errors(film, self.settings.confidence);
        let summary = summarize(&errors);
        if due {
            self.next_log_pass *= 2;
            self.write_line(film, &errors, summary, elapsed_s, photons, None)?;
        }
        Ok(self.settings.target.is_some_and(|(target, statistic)| {
            film.passes >= MIN_PASSES_TO_STOP && summary.get(statistic) <= target
        }))
    }

    /// Called when the frame ends: the last log line, with what stopped it; gives the errors.
    pub fn finish(
        &mut self,
        film: &Film,
        elapsed_s: f64,
        photons: u64,
        stop: StopReason,
    ) -> Result<Vec<PixelError>, String> {
        let errors = pixel_errors(film, self.settings.confidence);
        if self.log.is_some() {
            self.write_line(film, &errors, summarize(&errors), elapsed_s, photons, Some(stop))?;
        }
        Ok(errors)
    }

    fn write_line(
        &mut self,
        film: &Film,
        errors: &[PixelError],
        summary: ErrorSummary,
        elapsed_s: f64,
        photons: u64,
        stop: Option<StopReason>,
    ) -> Result<(), String> {
        let mut line = json!({
            "frame": self.frame, "passes": film.passes, "elapsed_s": elapsed_s, "photons": photons,
            "confidence": self.settings.confidence, "error": summary,
        });
        if let Some(reference) = &self.reference {
            line["true"] = json!(true_error(errors, reference));
        }
        if let Some(stop) = stop {
            line["stopped_by"] = json!(stop);
        }
        let Some(log) = self.log.as_mut() else { return Ok(()) };
        writeln!(log, "{line}").map_err(|e| format!("cannot write the log: {e}"))
    }
}
