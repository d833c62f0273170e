//! Potentiometer calibration: raw ADC counts -> pencil travel (mm) along the tool axis.
//!
//! Pencil travel is the pencil tip's position along the tool axis relative to the model's tool
//! point (d5 = 330 mm with the pencil holder): positive = pencil extended out of the holder
//! (the tool point is above the paper), 0 = tip at the tool point. The spring pushes the pencil
//! out against a stop, so off the paper the travel reads the stop value.
//!
//! The jig holds the pencil at known travels (gauge blocks under the tip) and the board records
//! the counts. Two points give a line; more points give a least-squares polynomial of the chosen
//! degree (1 by default, up to [`MAX_DEGREE`]) with its residuals, and a linearity check: with
//! at least 4 points a linear fit is compared with a quadratic one
//! ([`PotCalibration::nonlinearity`]).
//!
//! The polynomial is in the normalised count `x = (raw - centre_raw) / half_range_raw` over the
//! calibrated range, for conditioning: `travel_mm = sum_i coefficients[i] x^i`.
//!
//! # Jig file (`--points JIG.csv`)
//! A header row, then one row per gauge; `#` lines are comments. Either
//! * `raw,travel_mm`: the counts read for each known travel, or
//! * `start_s,end_s,travel_mm`: with `--recording`, the window (seconds after the recording's
//!   first potentiometer sample, board clock) during which the pencil sat on that gauge; the
//!   counts are the window's mean.
//!
//! # Calibration file (`POT.toml`)
//! ```toml
//! format = "rigctl-potcal/1"
//! centre_raw = 2000.0
//! half_range_raw = 950.0
//! coefficients = [0.0, -2.5]   # travel_mm = c0 + c1 x + ...
//! raw_min = 1050.0             # calibrated range of counts
//! raw_max = 2950.0
//! points = 6
//! rms_residual_mm = 0.004      # absent for an exact fit (points = degree + 1)
//! max_residual_mm = 0.007
//! ```

use std::path::Path;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::error::FusionError;
use super::pot::PotSample;
use crate::io::atomic::write_text_atomic;
use crate::io::finite::TextFormat;
use crate::io::table::{Table, TableError};

/// Format tag of the calibration file.
pub const POTCAL_FORMAT: &str = "rigctl-potcal/1";
/// Highest polynomial degree offered.
pub const MAX_DEGREE: usize = 3;

/// One gauge: the counts read and the known travel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JigPoint {
    /// Raw ADC counts (a mean, so fractional).
    pub raw: f64,
    /// Known pencil travel, mm.
    pub travel_mm: f64,
}

/// A jig gauge given as a time window of a recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JigWindow {
    /// Window start, s after the first pot sample (board clock).
    pub start_s: f64,
    /// Window end, s.
    pub end_s: f64,
    /// Known travel, mm.
    pub travel_mm: f64,
}

/// The contents of a jig file.
#[derive(Debug, Clone, PartialEq)]
pub enum JigFile {
    /// `raw,travel_mm` rows.
    Points(Vec<JigPoint>),
    /// `start_s,end_s,travel_mm` rows.
    Windows(Vec<JigWindow>),
}

/// A fitted counts -> travel map (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PotCalibration {
    /// Always [`POTCAL_FORMAT`].
    pub format: String,
    /// Centre of the normalised count.
    pub centre_raw: f64,
    /// Half range of the normalised count.
    pub half_range_raw: f64,
    /// Polynomial coefficients in the normalised count, constant first (mm).
    pub coefficients: Vec<f64>,
    /// Lowest calibrated count.
    pub raw_min: f64,
    /// Highest calibrated count.
    pub raw_max: f64,
    /// Number of jig points.
    pub points: usize,
    /// RMS of the fit residuals, mm (absent for an exact fit).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rms_residual_mm: Option<f64>,
    /// Largest absolute residual, mm (absent for an exact fit).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub max_residual_mm: Option<f64>,
}

/// Least-squares polynomial of `degree` through `(x, y)`; returns the coefficients.
fn polyfit(x: &[f64], y: &[f64], degree: usize) -> Option<Vec<f64>> {
    let a = DMatrix::from_fn(x.len(), degree + 1, |r, c| x[r].powi(c as i32));
    let b = DVector::from_column_slice(y);
    let svd = a.svd(true, true);
    let s_max = svd.singular_values.max();
    if svd.singular_values.min() < 1e-9 * s_max {
        return None;
    }
    svd.solve(&b, 0.0).ok().map(|c| c.iter().copied().collect())
}

fn polyval(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ci| acc * x + ci)
}

impl PotCalibration {
    /// Fits a polynomial of `degree` (1..=[`MAX_DEGREE`]) to the jig points. Needs at least
    /// `degree + 1` points with distinct counts, and a map that is monotonic over the calibrated
    /// range (a pencil travel must map to one count).
    pub fn fit(points: &[JigPoint], degree: usize) -> Result<Self, FusionError> {
        if !(1..=MAX_DEGREE).contains(&degree) {
            return Err(FusionError::Invalid(format!(
                "potentiometer calibration degree {degree}: must be 1..={MAX_DEGREE}"
            )));
        }
        if let Some(p) = points
            .iter()
            .find(|p| !(p.raw.is_finite() && p.travel_mm.is_finite()))
        {
            return Err(FusionError::Invalid(format!(
                "jig point ({}, {}) is not finite",
                p.raw, p.travel_mm
            )));
        }
        let raw_min = points.iter().map(|p| p.raw).fold(f64::INFINITY, f64::min);
        let raw_max = points
            .iter()
            .map(|p| p.raw)
            .fold(f64::NEG_INFINITY, f64::max);
        let mut distinct: Vec<f64> = points.iter().map(|p| p.raw).collect();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        if distinct.len() < degree + 1 {
            return Err(FusionError::Invalid(format!(
                "a degree-{degree} potentiometer calibration needs at least {} jig points with \
                 different counts, got {}",
                degree + 1,
                distinct.len()
            )));
        }
        let centre_raw = 0.5 * (raw_min + raw_max);
        let half_range_raw = 0.5 * (raw_max - raw_min);
        let x: Vec<f64> = points
            .iter()
            .map(|p| (p.raw - centre_raw) / half_range_raw)
            .collect();
        let y: Vec<f64> = points.iter().map(|p| p.travel_mm).collect();
        let coefficients = polyfit(&x, &y, degree).ok_or_else(|| {
            FusionError::Invalid("potentiometer calibration: singular jig points".into())
        })?;
        // monotonic over the range: the derivative keeps one sign
        let deriv: Vec<f64> = (1..coefficients.len())
            .map(|i| coefficients[i] * i as f64)
            .collect();
        let slopes: Vec<f64> = (0..=200)
            .map(|k| polyval(&deriv, -1.0 + k as f64 / 100.0))
            .collect();
        let all_pos = slopes.iter().all(|&s| s > 0.0);
        let all_neg = slopes.iter().all(|&s| s < 0.0);
        if !(all_pos || all_neg) {
            return Err(FusionError::Invalid(format!(
                "the degree-{degree} potentiometer calibration is not monotonic over counts \
                 {raw_min}..{raw_max}; use a lower degree or check the jig points"
            )));
        }
        let residuals: Vec<f64> = x
            .iter()
            .zip(&y)
            .map(|(&xi, &yi)| yi - polyval(&coefficients, xi))
            .collect();
        let (rms, max) = if points.len() > degree + 1 {
            let rms =
                (residuals.iter().map(|r| r * r).sum::<f64>() / residuals.len() as f64).sqrt();
            let max = residuals.iter().fold(0.0f64, |m, r| m.max(r.abs()));
            (Some(rms), Some(max))
        } else {
            (None, None)
        };
        Ok(Self {
            format: POTCAL_FORMAT.into(),
            centre_raw,
            half_range_raw,
            coefficients,
            raw_min,
            raw_max,
            points: points.len(),
            rms_residual_mm: rms,
            max_residual_mm: max,
        })
    }

    /// Pencil travel (mm) for a count.
    pub fn travel_mm(&self, raw: f64) -> f64 {
        polyval(
            &self.coefficients,
            (raw - self.centre_raw) / self.half_range_raw,
        )
    }

    /// Sensitivity at the centre of the range, mm per count.
    pub fn mm_per_count(&self) -> f64 {
        self.coefficients.get(1).copied().unwrap_or(0.0) / self.half_range_raw
    }

    /// Linearity check (needs at least 4 points): `Some(message)` when a quadratic fits the
    /// points clearly better than a line (RMS more than 3x lower and the linear RMS above
    /// 0.005 mm), i.e. a degree-2 calibration is advisable.
    pub fn nonlinearity(points: &[JigPoint]) -> Option<String> {
        if points.len() < 4 {
            return None;
        }
        let lin = Self::fit(points, 1).ok()?.rms_residual_mm?;
        let quad = Self::fit(points, 2).ok()?.rms_residual_mm?;
        (lin > 0.005 && lin > 3.0 * quad).then(|| {
            format!(
                "the potentiometer looks non-linear: linear fit RMS {lin:.4} mm, quadratic {quad:.4} \
                 mm (consider --degree 2)"
            )
        })
    }

    /// The calibration file's text.
    pub fn to_toml_string(&self) -> String {
        format!(
            "# rigctl potcal: pencil travel (mm, + = extended, 0 = model tool point) = \
             sum coefficients[i] * ((raw - centre_raw) / half_range_raw)^i\n{}",
            toml::to_string(self).unwrap_or_default()
        )
    }

    /// Parses a calibration file's text.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Self, FusionError> {
        let bad = |reason: String| FusionError::Toml {
            path: path.to_path_buf(),
            reason,
        };
        let c: Self = toml::from_str(text).map_err(|e| bad(e.to_string()))?;
        if c.format != POTCAL_FORMAT {
            return Err(bad(format!(
                "format `{}`, expected `{POTCAL_FORMAT}`",
                c.format
            )));
        }
        let finite = c.coefficients.iter().all(|v| v.is_finite())
            && c.centre_raw.is_finite()
            && c.half_range_raw.is_finite();
        if c.coefficients.len() < 2 || !finite || c.half_range_raw <= 0.0 {
            return Err(bad(
                "needs finite coefficients (at least 2) and half_range_raw > 0".into(),
            ));
        }
        let counts = crate::io::ranges::MAX_RAW_COUNTS;
        let in_counts = [c.raw_min, c.raw_max, c.centre_raw, c.half_range_raw]
            .iter()
            .all(|v| v.is_finite() && v.abs() <= counts);
        if !in_counts || c.raw_min > c.raw_max {
            return Err(bad(format!(
                "raw_min {} .. raw_max {}, centre_raw, half_range_raw: finite counts within 2^32 and raw_min <= raw_max",
                c.raw_min, c.raw_max
            )));
        }
        if c.coefficients.len() > 16
            || c.coefficients
                .iter()
                .any(|v| v.abs() > crate::io::ranges::MAX_POSITION_MM)
        {
            return Err(bad(
                "coefficients: at most 16, each within 100 m (mm)".into()
            ));
        }
        Ok(c)
    }

    /// Reads a calibration file.
    pub fn read(path: &Path) -> Result<Self, FusionError> {
        let text = crate::io::read::read_text_capped(path, crate::io::read::CAP_SMALL_TEXT)
            .map_err(|source| FusionError::Read {
                path: path.to_path_buf(),
                source,
            })?;
        Self::from_toml_str(&text, path)
    }

    /// Writes the calibration file atomically.
    pub fn write(&self, path: &Path) -> Result<(), FusionError> {
        write_text_atomic(path, TextFormat::Toml, &self.to_toml_string())?;
        Ok(())
    }
}

/// What a jig file without data rows lacks.
const NO_JIG_ROWS: &str = "no jig rows";

/// Parses a jig file's text (see the module documentation).
pub fn parse_jig_csv(text: &str, path: &Path) -> Result<JigFile, FusionError> {
    let table = Table::parse(text, &path.display().to_string())
        .map_err(|e| FusionError::from_table(e, path, NO_JIG_ROWS))?;
    jig_from_table(&table, path)
}

/// Reads a jig file.
pub fn read_jig_csv(path: &Path) -> Result<JigFile, FusionError> {
    let table = Table::read(path).map_err(|e| FusionError::from_table(e, path, NO_JIG_ROWS))?;
    jig_from_table(&table, path)
}

/// The gauges of a parsed jig table: `travel_mm` and either `raw` or `start_s,end_s`.
fn jig_from_table(table: &Table, path: &Path) -> Result<JigFile, FusionError> {
    let table_err = |e| FusionError::from_table(e, path, NO_JIG_ROWS);
    let travel = table.need("travel_mm").map_err(table_err)?;
    match (
        table.find("raw"),
        table.find("start_s"),
        table.find("end_s"),
    ) {
        (Some(raw), _, _) => {
            let points = table
                .rows
                .iter()
                .map(|row| {
                    let [travel_mm, raw] = table.numbers(row, [travel, raw])?;
                    Ok(JigPoint { raw, travel_mm })
                })
                .collect::<Result<_, TableError>>()
                .map_err(table_err)?;
            Ok(JigFile::Points(points))
        }
        (None, Some(start), Some(end)) => {
            let mut windows = Vec::with_capacity(table.rows.len());
            for row in &table.rows {
                let [travel_mm, start_s, end_s] = table
                    .numbers(row, [travel, start, end])
                    .map_err(table_err)?;
                if end_s <= start_s {
                    return Err(FusionError::csv(
                        path,
                        row.line,
                        "end_s",
                        "must be after start_s",
                    ));
                }
                windows.push(JigWindow {
                    start_s,
                    end_s,
                    travel_mm,
                });
            }
            Ok(JigFile::Windows(windows))
        }
        _ => Err(FusionError::csv(
            path,
            table.header_line,
            "raw",
            "the header needs `raw` or `start_s,end_s`",
        )),
    }
}

/// Jig points from recording windows: the mean count of the samples inside each window (times
/// relative to the first sample). A window with no sample is an error.
pub fn points_from_windows(
    samples: &[PotSample],
    windows: &[JigWindow],
) -> Result<Vec<JigPoint>, FusionError> {
    let Some(first) = samples.first() else {
        return Err(FusionError::Invalid(
            "the recording has no potentiometer sample".into(),
        ));
    };
    windows
        .iter()
        .map(|w| {
            let (lo, hi) = (
                first.t_us as f64 + w.start_s * 1e6,
                first.t_us as f64 + w.end_s * 1e6,
            );
            let inside: Vec<f64> = samples
                .iter()
                .filter(|s| (lo..=hi).contains(&(s.t_us as f64)))
                .map(|s| f64::from(s.raw))
                .collect();
            if inside.is_empty() {
                return Err(FusionError::Invalid(format!(
                    "jig window {}..{} s holds no potentiometer sample",
                    w.start_s, w.end_s
                )));
            }
            Ok(JigPoint {
                raw: inside.iter().sum::<f64>() / inside.len() as f64,
                travel_mm: w.travel_mm,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests;
