//! `rigctl report RUN_DIR --html OUT.html`: one self-contained HTML page (inline CSS and SVG, no
//! scripts, no external links) from whatever a run directory holds.
//!
//! | module | holds |
//! |---|---|
//! | [`run_dir`] | the files understood (`cal.csv`, `val.csv`, `truth.json`, `truth.toml`, `calibrate*.json`, `diagnose*.json`, `path_errors.csv`, `plan.csv`, `plan.json`, `*overlay*.png`, other `*.toml` = calibrated models, `commands.txt` / `*.cmd`) and their SHA-256 |
//! | [`summary`] | the first screen as data: error at each stage per set (every newer diagnose key optional) |
//! | [`diagnosis_words`] | a diagnose document in words: effects found with their evidence, floor verdict, aliased pairs |
//! | [`answer`] | the top of the first screen: the one sentence, the verdict in one line, "N of M parameters identified", the held-out error through the exported URDF beside the best model's |
//! | [`first_screen`] | builds the [`Summary`] (robot, data, next steps, the stage bar chart) |
//! | [`first_screen_html`] | renders the [`Summary`] as the page's first screen |
//! | [`table`] | thesis table 4.5 (min / max / average of abs(dX) abs(dY) abs(dZ) abs(dP)) from JSON stats or error vectors; tables of one set merged, each model once |
//! | `docs`, `pose_sets` | parameters, diagnosis and simulation facts from the JSON documents; the pose files recomputed with every model, before / after figures |
//! | [`extras`] | the plan section (`plan.csv` poses in the workspace, `plan.json` expected vs achieved sigma) and the trace overlays (PNG embedded, downscaled) |
//! | [`analysis`] | recomputed numbers: per-pose errors, parameter influence (fig. 3.8), moments and tilts (fig. 5.8-5.10), path error (fig. 5.12) |
//! | [`path_errors`] | the section "Path error along the drawn path (thesis fig. 5.12)" from `path_errors.csv`: the per-sample errors of the low-cost rig that `rigctl calibrate --samples FUSED.csv --errors-csv path_errors.csv` writes (columns `t,q1..qN,dev_u_before,dev_n_before,dp_before,dev_u_after,dev_n_after,dp_after,dev_u_standard,dev_n_standard,dp_standard`, mm; see [`crate::plot::path_errors`]), as a chart and a table of RMS / max / mean before, after the standard calibration and after the chosen method (named from `calibrate*.json`'s `method`) |
//! | [`captions`] | captions true to their plots: "near zero", "at most X mm", "no trend remains" computed from the values drawn (kept in [`Figure`]'s `series`) |
//! | [`tree`] | a tree's run: the tree the documents are of, its figures counted in points (one per tip of a pose), its pose files evaluated with the nominal tree and every tree model file (a table over every tip, one per tip, before / after figures per tip) |
//! | [`build`] | [`build_report`]: run directory -> [`Report`] |
//! | `markup` | what the sections share and that imports none of them: a chart as a [`Figure`], HTML escaping, a figure's HTML |
//! | [`html`] | [`render_html`]: [`Report`] -> page: the first screen, a table of contents, then the details; A4 print styles |
//!
//! Missing or unreadable pieces become notes on the page; a directory with nothing usable is
//! [`ReportError::NothingUsable`] (bad input, exit 2).

pub mod analysis;
pub mod answer;
pub mod build;
pub mod captions;
pub mod diagnosis_words;
mod docs;
pub mod extras;
pub mod first_screen;
pub mod first_screen_html;
pub mod html;
mod markup;
pub mod path_errors;
mod pose_sets;
pub mod run_dir;
pub mod suggest;
pub mod summary;
pub mod table;
pub mod tree;

use std::path::{Path, PathBuf};

pub use build::build_report;
pub use extras::{ImageFigure, PlanSection, SigmaRow};
pub use html::render_html;
pub use path_errors::PathErrorsSection;
pub use run_dir::{FileInfo, RunDir};
pub use summary::Summary;
pub use table::ErrorTable;

use crate::error::{Classify, ErrorKind};
use crate::io::atomic::AtomicWriteError;

/// Why a report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The run directory cannot be listed.
    #[error("cannot read run directory {path}: {source}")]
    Dir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Nothing in the directory could be used.
    #[error("{path}: nothing to report (expected cal.csv, val.csv, calibrate*.json, diagnose*.json or path_errors.csv){}", notes_suffix(.notes))]
    NothingUsable { path: PathBuf, notes: Vec<String> },
    /// The page could not be written.
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
    /// A result file of the run that is valid JSON but not the document its name says.
    #[error("{path}: {reason}")]
    Shape { path: PathBuf, reason: String },
}

fn notes_suffix(notes: &[String]) -> String {
    if notes.is_empty() {
        String::new()
    } else {
        format!("; {}", notes.join("; "))
    }
}

impl Classify for ReportError {
    fn kind(&self) -> ErrorKind {
        match self {
            ReportError::Dir { .. }
            | ReportError::NothingUsable { .. }
            | ReportError::Shape { .. } => ErrorKind::BadInput,
            ReportError::Write(e) => e.kind(),
        }
    }
}

/// Options of `rigctl report`.
#[derive(Debug, Clone, Default)]
pub struct ReportOptions {
    /// Declared (nominal) robot preset; default: `truth.json`'s `robot`, else `katana450`.
    pub robot: Option<String>,
    /// Katana tool length d5 (mm) of the declared model.
    pub tool_mm: Option<f64>,
    /// The declared model as a model file (instead of a preset).
    pub model_file: Option<PathBuf>,
    /// Overrides of the declared model's parameters (`NAME=VALUE`, as `--set`).
    pub sets: Vec<String>,
    /// The model flags of the commands the report suggests, each with a leading space (`Some("")`
    /// when a project file supplies the model); default: from the model file or robot.
    pub command_model: Option<String>,
    /// Units, separator and decimal mark of the run's pose files (`--units`, `--sep`,
    /// `--decimal`; default mm, deg, `,` and `.`).
    pub pose_units: crate::io::units::Units,
    pub pose_dialect: crate::io::dialect::Dialect,
}

/// A figure: caption and inline SVG.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// What the figure shows.
    pub caption: String,
    /// The SVG document.
    pub svg: String,
    /// The values the chart draws that the caption speaks of, by name (`before`, `after`, `x`,
    /// `mean`, `rms`): a caption's claims can be checked against them.
    pub series: Vec<(String, Vec<f64>)>,
}

/// One identified parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRow {
    /// Name (MODEL.md).
    pub name: String,
    /// Identified value (deg / mm).
    pub value: f64,
    /// One standard deviation, if fitted.
    pub sigma: Option<f64>,
    /// Value in the nominal model.
    pub nominal: Option<f64>,
    /// Value in the simulation truth (truth.toml), if present.
    pub truth: Option<f64>,
    /// Unit ("deg", "mm", ...) from the declared model, if it has the parameter.
    pub unit: Option<String>,
}

/// The parameters of one `calibrate --json` document.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamTable {
    /// File name.
    pub source: String,
    /// Method.
    pub method: String,
    /// Rows in document order.
    pub rows: Vec<ParamRow>,
    /// Unidentifiable parameters or combinations.
    pub unidentifiable: Vec<String>,
    /// Condition number, if given.
    pub condition_number: Option<f64>,
}

/// One effect added by `diagnose`.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectRow {
    /// Effect id (FORMATS.md).
    pub id: String,
    /// `name = value, ...`.
    pub parameters: String,
    /// Validation mean error before adding it (mm).
    pub validation_mean_mm_before: Option<f64>,
    /// ... and after (mm).
    pub validation_mean_mm_after: Option<f64>,
    /// Why it was accepted.
    pub evidence: String,
}

/// The `diagnose --json` part.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DiagnoseSection {
    /// File name.
    pub source: String,
    /// Declared vs final model tables.
    pub tables: Vec<ErrorTable>,
    /// Effects in the order added.
    pub effects: Vec<EffectRow>,
    /// What remains unexplained.
    pub unexplained: String,
    /// The verdict's kind (`floor`, `missing_effect`, `overfitting`, `change_between_sets`,
    /// `no_floor`), when the document has one.
    pub verdict_kind: Option<String>,
}

/// Everything on the page.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// The run directory as given.
    pub run_dir: String,
    /// rigctl's version.
    pub rigctl_version: &'static str,
    /// Table 4.5 style tables.
    pub tables: Vec<ErrorTable>,
    /// Figures.
    pub figures: Vec<Figure>,
    /// Identified parameters.
    pub parameters: Vec<ParamTable>,
    /// The first screen: the answer, before any table.
    pub summary: Summary,
    /// Diagnoses, one per `diagnose*.json`.
    pub diagnose: Vec<DiagnoseSection>,
    /// Planned poses (`plan.csv`, `plan.json`), when present.
    pub plan: Option<PlanSection>,
    /// Trace overlays (`*overlay*.png`), embedded.
    pub overlays: Vec<ImageFigure>,
    /// Path error along the drawn path (thesis fig. 5.12), from `path_errors.csv`.
    pub path_errors: Option<PathErrorsSection>,
    /// Facts from `truth.json`.
    pub simulation: Vec<(String, String)>,
    /// Recorded command lines (file, text).
    pub commands: Vec<(String, String)>,
    /// Files of the run directory.
    pub files: Vec<FileInfo>,
    /// What was skipped and why.
    pub notes: Vec<String>,
}

impl Report {
    /// Every figure on the page: the first screen's chart, the figures, the trace overlays, the
    /// path-error chart and the plan's.
    pub fn figure_count(&self) -> usize {
        usize::from(self.summary.figure.is_some())
            + self.figures.len()
            + self.overlays.len()
            + self
                .path_errors
                .as_ref()
                .map_or(0, |p| usize::from(p.figure.is_some()))
            + self
                .plan
                .as_ref()
                .map_or(0, |p| usize::from(p.figure.is_some()))
    }
}

/// Builds the report of `dir` and writes it to `out` atomically; returns the report.
pub fn write_report(dir: &Path, out: &Path, opts: &ReportOptions) -> Result<Report, ReportError> {
    let report = build_report(dir, opts)?;
    crate::io::atomic::write_bytes_atomic(out, render_html(&report).as_bytes())?;
    Ok(report)
}
