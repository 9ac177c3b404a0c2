//! Watching a frame's error while its passes run: log lines (`--log`, JSON lines), the true error
//! against a reference (`--reference`), and the stopping rule (`--target-error`).
//!
//! A log line is written after passes 1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, ... (four in each
//! doubling, the powers of two among them) and after the last pass (which also says what stopped
//! the frame), so that error against time can be plotted on log axes and read between lines: a
//! benchmark's error at a budget is interpolated between the two lines around it, which with a
//! line per doubling was off by up to 7% where the curve bends (VCM's early passes).
//!
//! The progress display shows the error as it falls: measured after passes 1, 2, 4, 8, ..., and
//! after every pass when a target error is set. With a target, the time left is forecast from the
//! error measured so far: SPPM's error falls as a power of time (Knaus & Zwicker: variance as
//! `t^(-alpha)`, bias as `t^(alpha - 1)`, their sum as whichever dominates), so a line fitted to
//! log error against log time over the later half of the time so far (the earlier passes, whose
//! radius is still large, fall differently) is extended to the target. Its slope is held between
//! the fall of noise at a fixed radius, `t^(-1/2)`, and the slowest of the two terms, `t^(-alpha/2)`
//! and `t^(alpha - 1)`: early passes fall faster than they go on to (on the gems at 128x96 the
//! unheld forecast after a tenth of the render was 49% short, held 13%).

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

/// A frame's error as last measured, and the forecast time to its target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStatus {
    /// The statistic of the relative error bound the target is on (the mean without a target).
    pub error: f64,
    /// The target error, if any.
    pub target: Option<f64>,
    /// Seconds of rendering left until the target is met, once it can be forecast.
    pub seconds_left: Option<f64>,
}

/// The error measured against rendering time.
#[derive(Clone, Debug, Default)]
pub struct ErrorHistory {
    /// (elapsed seconds, error) after each measurement.
    points: Vec<(f64, f64)>,
}

/// Measurements the forecast needs in the later half of the time so far.
const FORECAST_POINTS: usize = 4;

impl ErrorHistory {
    /// Adds a measurement.
    pub fn push(&mut self, elapsed_s: f64, error: f64) {
        if elapsed_s > 0.0 && error > 0.0 && error.is_finite() {
            self.points.push((elapsed_s, error));
        }
    }

    /// Seconds from the last measurement until the error falls to `target`: the power law
    /// fitted (least squares on log error against log time) to the measurements of the later
    /// half of the time so far, its slope held within `slopes`, extended; `None` with too few of
    /// them or an error not falling.
    pub fn seconds_to(&self, target: f64, slopes: [f64; 2]) -> Option<f64> {
        let &(now, _) = self.points.last()?;
        let recent: Vec<(f64, f64)> =
            self.points.iter().filter(|p| p.0 >= now / 2.0).map(|&(t, e)| (t.ln(), e.ln())).collect();
        if recent.len() < FORECAST_POINTS {
            return None;
        }
        let n = recent.len() as f64;
        let (mean_t, mean_e) = recent.iter().fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
        let covariance: f64 = recent.iter().map(|p| (p.0 - mean_t) * (p.1 - mean_e)).sum();
        let spread: f64 = recent.iter().map(|p| (p.0 - mean_t).powi(2)).sum();
        let slope = covariance / spread;
        if !(slope < -0.02) {
            return None;
        }
        let slope = slope.clamp(slopes[0], slopes[1]);
        // ln e = mean_e + slope (ln t - mean_t): solve for ln t at the target.
        let target_t = (mean_t + (target.ln() - mean_e) / slope).exp();
        Some((target_t - now).max(0.0))
    }
}

/// The pass after which the log's next line is due, after one due after `passes`: a quarter of
/// the power of two at or below it later (every pass up to 8).
fn next_log_pass(passes: u64) -> u64 {
    let octave = 1u64 << (63 - passes.max(1).leading_zeros());
    passes + (octave / 4).max(1)
}

/// Watches one frame.
pub struct Monitor {
    settings: ErrorSettings,
    frame: i32,
    reference: Option<Vec<f64>>,
    log: Option<std::fs::File>,
    next_log_pass: u64,
    next_status_pass: u64,
    history: ErrorHistory,
    /// The steepest and the shallowest slope of log error against log time to forecast with.
    slopes: [f64; 2],
    status: Option<ErrorStatus>,
}

impl Monitor {
    /// A monitor for `frame` of a `width` x `height` film rendered with radius reduction `alpha`,
    /// measuring the error for the progress display too if `shown`; checks the reference's size.
    pub fn new(
        settings: &ErrorSettings,
        frame: i32,
        [width, height]: [u32; 2],
        alpha: f64,
        shown: bool,
    ) -> Result<Self, String> {
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
        Ok(Monitor {
            settings: settings.clone(),
            frame,
            reference,
            log,
            next_log_pass: 1,
            next_status_pass: if shown { 1 } else { u64::MAX },
            history: ErrorHistory::default(),
            slopes: [-0.5, -(alpha / 2.0).min(1.0 - alpha)],
            status: None,
        })
    }

    /// The error as last measured, with the forecast time to the target.
    pub fn status(&self) -> Option<ErrorStatus> {
        self.status
    }

    /// Whether [`Monitor::after_pass`] measures the error after `passes` passes (else it does
    /// not read the film).
    pub fn measures_after(&self, passes: u64) -> bool {
        let log_due = self.log.is_some() && passes >= self.next_log_pass;
        log_due || passes >= self.next_status_pass || self.settings.target.is_some()
    }

    /// Called after each pass: measures the error when due (passes 1, 2, 4, ..., or every pass
    /// with a target), logs it when due, and says whether the target error is met.
    pub fn after_pass(&mut self, film: &Film, elapsed_s: f64, photons: u64) -> Result<bool, String> {
        let log_due = self.log.is_some() && film.passes >= self.next_log_pass;
        let status_due = film.passes >= self.next_status_pass;
        if !self.measures_after(film.passes) {
            return Ok(false);
        }
        let errors = pixel_errors(film, self.settings.confidence);
        let summary = summarize(&errors);
        if log_due {
            while self.next_log_pass <= film.passes {
                self.next_log_pass = next_log_pass(self.next_log_pass);
            }
            self.write_line(film, &errors, summary, elapsed_s, photons, None)?;
        }
        if status_due {
            self.next_status_pass *= 2;
        }
        let target = self.settings.target;
        let error = summary.get(target.map_or(Statistic::Mean, |(_, statistic)| statistic));
        self.history.push(elapsed_s, error);
        let seconds_left = target.and_then(|(t, _)| self.history.seconds_to(t, self.slopes));
        // After one pass the variance, and with it the error, is not known yet.
        self.status =
            error.is_finite().then_some(ErrorStatus { error, target: target.map(|(t, _)| t), seconds_left });
        Ok(target.is_some_and(|(t, _)| film.passes >= MIN_PASSES_TO_STOP && error <= t))
    }

    /// The error estimates of every pixel of the frame's finished film.
    pub fn final_errors(&self, film: &Film) -> Vec<PixelError> {
        pixel_errors(film, self.settings.confidence)
    }

    /// Called when the frame ends, with its [`Monitor::final_errors`]: the last log line, with
    /// what stopped it.
    pub fn finish(
        &mut self,
        film: &Film,
        errors: &[PixelError],
        elapsed_s: f64,
        photons: u64,
        stop: StopReason,
    ) -> Result<(), String> {
        if self.log.is_none() {
            return Ok(());
        }
        self.write_line(film, errors, summarize(errors), elapsed_s, photons, Some(stop))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The log's lines fall every pass up to 8, then four to each doubling, on every power of two.
    #[test]
    fn log_lines_fall_four_to_a_doubling_on_the_powers_of_two() {
        let schedule: Vec<u64> =
            std::iter::successors(Some(1), |&p| Some(next_log_pass(p))).take(24).collect();
        assert_eq!(
            schedule,
            [1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 14, 16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96, 112, 128]
        );
        let mut p: u64 = 128;
        for _ in 0..40 {
            assert!(p.is_power_of_two(), "{p}");
            p = (0..4).fold(p, |p, _| next_log_pass(p));
        }
    }

    #[test]
    fn an_error_falling_as_a_power_of_time_is_forecast_to_its_target() {
        let mut history = ErrorHistory::default();
        // error = 0.5 t^(-0.4), measured each second for 20 s (a noisier start does not matter).
        history.push(0.5, 3.0);
        for t in 1..=20 {
            history.push(f64::from(t), 0.5 * f64::from(t).powf(-0.4));
        }
        // 0.05 = 0.5 t^(-0.4) at t = 10^(1/0.4) = 316.2 s: 296.2 s after the 20th.
        let left = history.seconds_to(0.05, [-0.5, -0.2]).unwrap();
        assert!((left - 296.2).abs() < 0.5, "{left}");
        assert_eq!(history.seconds_to(0.9, [-0.5, -0.2]), Some(0.0), "a target already met");
        // Held to a slope of -0.35, through the mean of the later half's points (t from 10 to 20 s).
        let held = history.seconds_to(0.05, [-0.35, -0.3]).unwrap();
        let mean_t = (10..=20).map(|t| f64::from(t).ln()).sum::<f64>() / 11.0;
        let mean_e = 0.5f64.ln() - 0.4 * mean_t;
        let expected = (mean_t + (0.05f64.ln() - mean_e) / -0.35).exp() - 20.0;
        assert!((held / expected - 1.0).abs() < 1e-6 && held > left, "{held} against {expected}");
    }

    #[test]
    fn no_forecast_from_too_few_points_or_an_error_that_does_not_fall() {
        let mut history = ErrorHistory::default();
        history.push(1.0, 0.3);
        history.push(2.0, 0.2);
        assert_eq!(history.seconds_to(0.1, [-0.5, -0.2]), None);
        let mut flat = ErrorHistory::default();
        (1..10).for_each(|t| flat.push(f64::from(t), 0.2));
        assert_eq!(flat.seconds_to(0.1, [-0.5, -0.2]), None);
    }
}
