//! `diagnose --plots DIR`: one SVG per accepted effect, `NN_<id>.svg` (`:` replaced by `_`):
//! the calibration residual of every pose against the regressor that traced the effect, before
//! (blue) and after (red) adding it, with the effect's own contribution (black).
//!
//! The plotted residual is signed along the effect's contribution at that pose:
//! `y_k = r_k . d_k / |d_k|` (mm), so "before" scatters about `|d_k|` and "after" about 0.

use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use plotters::prelude::*;

use super::residual::Regressor;
use super::{Diagnosis, EffectTrace};
use crate::error::{Classify, ErrorKind};
use crate::io::atomic::{write_text_atomic, AtomicWriteError};
use crate::io::finite::TextFormat;

/// Why a plot could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The plot could not be drawn.
    #[error("plot {name}: {message}")]
    Draw { name: String, message: String },
    /// The directory could not be created.
    #[error("cannot create {path}: {source}")]
    Dir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
}

impl Classify for PlotError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Failure
    }
}

fn along(r: &[Vector3<f64>], d: &[Vector3<f64>]) -> Vec<f64> {
    r.iter()
        .zip(d)
        .map(|(r, d)| {
            let n = d.norm();
            if n > 0.0 {
                r.dot(d) / n
            } else {
                0.0
            }
        })
        .collect()
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-9);
    (lo - pad, hi + pad)
}

/// The SVG text of one effect's plot.
pub fn effect_svg(trace: &EffectTrace, reg: &Regressor) -> Result<String, PlotError> {
    let err = |e: String| PlotError::Draw {
        name: trace.id.clone(),
        message: e,
    };
    // Text needs the embedded font registered (plotters is built with `ab_glyph`).
    crate::plot::register_fonts().map_err(|e| err(e.to_string()))?;
    let before = along(&trace.errors_before, &trace.contribution);
    let after = along(&trace.errors_after, &trace.contribution);
    let model: Vec<f64> = trace.contribution.iter().map(|d| d.norm()).collect();
    let x = &reg.x;
    let (x0, x1) = range(x.iter().copied());
    let (y0, y1) = range(before.iter().chain(&after).chain(&model).copied());
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 540)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{}: residual along the effect vs {}", trace.id, reg.name),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc(reg.x_label.as_str())
            .y_desc("residual along the effect (mm)")
            .draw()
            .map_err(|e| err(e.to_string()))?;
        let series = [
            (&before, BLUE, "before"),
            (&after, RED, "after"),
            (&model, BLACK, "effect"),
        ];
        for (ys, colour, label) in series {
            let size = if label == "effect" { 2 } else { 3 };
            chart
                .draw_series(
                    x.iter()
                        .zip(ys.iter())
                        .map(move |(&a, &b)| Circle::new((a, b), size, colour.filled())),
                )
                .map_err(|e| err(e.to_string()))?
                .label(label)
                .legend(move |(a, b)| Circle::new((a, b), 3, colour.filled()));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(svg)
}

/// Writes one SVG per accepted effect into `dir` (created if missing); returns the paths.
pub fn write_plots(dir: &Path, diag: &Diagnosis) -> Result<Vec<PathBuf>, PlotError> {
    std::fs::create_dir_all(dir).map_err(|source| PlotError::Dir {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    for (k, trace) in diag.traces.iter().enumerate() {
        let Some(reg) = diag.regressors.get(trace.regressor) else {
            continue;
        };
        let svg = effect_svg(trace, reg)?;
        let path = dir.join(format!("{:02}_{}.svg", k + 1, trace.id.replace(':', "_")));
        write_text_atomic(&path, TextFormat::Xml, &svg)?;
        out.push(path);
    }
    Ok(out)
}
