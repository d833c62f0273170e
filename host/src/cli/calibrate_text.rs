//! The text `rigctl calibrate` prints: the error tables (nominal, standard, chosen method), the
//! held-out lines, the poses left out named by line and id, the notes of the variant with
//! several points or compliance, and the tail of the parameter table.

use std::fmt::Write as _;

use nalgebra::Vector3;
use rigctl::calib::stats::AxisExtremes;
use rigctl::calib::MeasuredSet;

/// Line and id of every pose of a file, to name the poses left out as gross errors.
pub(super) struct PoseLabels {
    lines: Vec<usize>,
    ids: Vec<Option<String>>,
}

impl PoseLabels {
    pub(super) fn of(file: &rigctl::io::pose_csv::PoseFile) -> Self {
        Self {
            lines: file.poses.iter().map(|p| p.line).collect(),
            ids: file.poses.iter().map(|p| p.id.clone()).collect(),
        }
    }

    /// The line and id of the pose at `index`.
    pub(super) fn at(&self, index: usize) -> (Option<usize>, Option<String>) {
        (
            self.lines.get(index).copied(),
            self.ids.get(index).cloned().flatten(),
        )
    }

    /// Names `pose` by its line and id.
    pub(super) fn fill(&self, pose: &mut rigctl::calib::outliers::PoseError) {
        (pose.line, pose.id) = self.at(pose.index);
    }
}

/// The text lines that name the poses left out as gross errors.
pub(super) fn outlier_lines(
    r: &rigctl::calib::report::CalibrateReport,
    cal: &std::path::Path,
    val: Option<&std::path::Path>,
) -> String {
    let mut s = String::new();
    for o in &r.outliers {
        let path = if o.pose.file == "val" {
            val.unwrap_or(cal)
        } else {
            cal
        };
        let _ = writeln!(
            s,
            "outlier: {}:{}: {}",
            path.display(),
            o.pose.line_and_id(),
            o.note
        );
    }
    if !r.outliers.is_empty() {
        let _ = writeln!(
            s,
            "the statistics above leave these {} pose(s) out (--keep-outliers keeps every pose)",
            r.outliers.len()
        );
    }
    if let Some(note) = &r.outlier_note {
        let _ = writeln!(s, "gross errors: {note}");
    }
    s
}

/// The held-out figure over every held-out pose when some are listed, the poses the model
/// extrapolates to, and the prior of an ill-posed set.
pub(super) fn held_out_lines(r: &rigctl::calib::report::CalibrateReport) -> String {
    let mut s = String::new();
    if let Some(line) = r.prior.as_ref().and_then(|p| p.line()) {
        let _ = writeln!(s, "{line}");
    }
    let listed = r.outliers.iter().filter(|o| o.pose.file == "val").count();
    if let (Some(all), true) = (&r.validation_all, listed > 0) {
        let _ = writeln!(
            s,
            "held out over all {} poses (the {listed} listed included): mean {:.4} mm, RMS {:.4} mm, max {:.4} mm",
            all.after.n, all.after.mean_mm, all.after.rms_mm, all.after.max_mm
        );
    }
    if !r.extrapolated.is_empty() {
        let worst = r
            .extrapolated
            .iter()
            .map(|e| e.prediction_sd_mm)
            .fold(0.0, f64::max);
        let outside = r
            .extrapolated
            .iter()
            .filter(|e| !e.outside_joints.is_empty())
            .count();
        let _ = writeln!(
            s,
            "extrapolated: {} held-out pose(s) with errors beyond the calibration residual's \
             gross-error threshold lie where the fit extrapolates ({outside} with joints outside \
             the calibration poses' ranges; prediction sd up to {worst:.3} mm per coordinate; JSON \
             `extrapolated`): not gross errors, kept in the statistics",
            r.extrapolated.len()
        );
        for e in r
            .extrapolated
            .iter()
            .filter(|e| !e.outside_joints.is_empty())
        {
            let _ = writeln!(
                s,
                "  held-out line {}: error {:.3} mm, {} outside the calibration range",
                e.pose.line.map_or_else(|| "?".into(), |l| l.to_string()),
                e.pose.error_mm,
                e.outside_joints.join(", ")
            );
        }
    }
    s
}

/// What the variants with several points, PRESS or compliance add to the summary: the PRESS
/// choice and the validation error of every point.
pub(super) fn general_notes(
    g: &rigctl::calib::calibrate_general::GeneralOutcome,
    cal: &MeasuredSet,
) -> String {
    let mut s = String::new();
    if !g.added.is_empty() {
        let _ = writeln!(s, "added by PRESS selection: {}", g.added.join(", "));
    }
    for (slot, rms) in g.validation_rms_by_point_mm.iter().enumerate() {
        let _ = writeln!(
            s,
            "validation RMS of point {}: {rms:.4} mm",
            cal.markers.get(slot).map_or(slot, |m| *m) + 1
        );
    }
    s
}

/// Table 4.5 style: min / max / average of |dX|, |dY|, |dZ|, |dP| before, after the standard
/// calibration and after the chosen method.
pub(super) fn table(
    title: &str,
    noun: &str,
    errs: &[Vec<Vector3<f64>>; 3],
    method: &str,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{title} ({} {noun}), mm", errs[0].len());
    // nominal, standard and the chosen method (once when the method is the standard one)
    let cols: Vec<usize> = if method == "standard" {
        vec![0, 1]
    } else {
        vec![0, 1, 2]
    };
    let names = ["nominal", "standard", method];
    let _ = write!(s, "{:<8} {:<5}", "", "");
    for &c in &cols {
        let _ = write!(s, " {:>10}", names[c]);
    }
    s.push('\n');
    let stats: Vec<_> = errs
        .iter()
        .map(|e| rigctl::calib::Stats::from_errors(e))
        .collect();
    let ext: Vec<_> = errs.iter().map(|e| AxisExtremes::from_errors(e)).collect();
    let labels = ["|dX|", "|dY|", "|dZ|", "|dP|"];
    for (row, pick) in [("Minimum", 0), ("Maximum", 1), ("Average", 2)] {
        for (k, label) in labels.iter().enumerate() {
            let first = if k == 0 { row } else { "" };
            let _ = write!(s, "{first:<8} {label:<5}");
            for &c in &cols {
                let v = match (pick, k) {
                    (0, 3) => stats[c].min_mm,
                    (1, 3) => stats[c].max_mm,
                    (2, 3) => stats[c].mean_mm,
                    (0, _) => ext[c].min_abs_mm[k],
                    (1, _) => ext[c].max_abs_mm[k],
                    (_, 0) => stats[c].mean_abs_x_mm,
                    (_, 1) => stats[c].mean_abs_y_mm,
                    _ => stats[c].mean_abs_z_mm,
                };
                let _ = write!(s, " {v:>10.4}");
            }
            s.push('\n');
        }
    }
    s
}

pub(super) fn summary(o: &rigctl::calib::Outcome, with_val: bool) -> String {
    let r = &o.report;
    let mut s = table(
        "Calibration poses",
        "poses",
        &o.calibration_errors,
        &r.method,
    );
    if with_val {
        s.push('\n');
        s.push_str(&table(
            "Validation poses",
            "poses",
            &o.validation_errors,
            &r.method,
        ));
    }
    s.push_str(&report_tail(r));
    s
}

/// Method, rank, condition, unidentifiable parameters and the parameter table.
/// Most kept parameters or unidentifiable combinations named in the text (the JSON has all).
const LISTED_MAX: usize = 6;

/// The fitted parameters whose sigma is not a finite number (the kept ones have `null`).
pub(super) fn fitted_not_finite(r: &rigctl::calib::report::CalibrateReport) -> Vec<String> {
    r.sigma
        .not_finite()
        .into_iter()
        .filter(|n| !r.fixed.contains(n))
        .collect()
}

pub(super) fn report_tail(r: &rigctl::calib::report::CalibrateReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\nmethod {}{}; rank {}; condition number {:.1}; iterations {}{}",
        r.method,
        if r.tilting_applied {
            " (tilting applied)"
        } else {
            ""
        },
        r.rank,
        r.condition_number,
        r.iterations,
        if r.converged { "" } else { " (not converged)" }
    );
    if !r.fixed.is_empty() {
        let fitted = r.parameters.0.len().saturating_sub(r.fixed.len());
        let _ = writeln!(
            s,
            "{fitted} of {} parameters identified; the other {} kept at their input values{}",
            r.parameters.0.len(),
            r.fixed.len(),
            if r.fixed.len() <= LISTED_MAX {
                format!(": {}", r.fixed.join(", "))
            } else {
                " (JSON `fixed`)".to_string()
            }
        );
    }
    if !r.unidentifiable.is_empty() {
        if r.unidentifiable.len() <= LISTED_MAX {
            let _ = writeln!(s, "unidentifiable: {}", r.unidentifiable.join(", "));
        } else {
            let _ = writeln!(
                s,
                "unidentifiable: {} combinations the poses do not tell apart (JSON `unidentifiable`)",
                r.unidentifiable.len()
            );
        }
    }
    let _ = writeln!(s, "{:<12} {:>14} {:>12}", "parameter", "value", "sigma");
    for (name, v) in r.parameters.0.iter().chain(&r.terms.0) {
        let sig = r
            .sigma
            .get(name)
            .filter(|_| !r.fixed.contains(name))
            .map_or_else(|| "fixed".to_string(), |x| format!("{x:.6}"));
        let _ = writeln!(s, "{name:<12} {v:>14.6} {sig:>12}");
    }
    for u in &r.unphysical {
        let _ = writeln!(s, "unphysical: {u}");
    }
    s
}
