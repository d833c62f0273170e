//! The fused-samples file (`FUSED.csv`, format `rigctl-fused/1`), written by `rigctl fuse`
//! ([`super::fuse`]) and read by `calibrate --samples` and `diagnose --samples`.
//! Comma separated, UTF-8, `#` lines are comments (the first names the format), then a header
//! row and one row per fused sample:
//!
//! | column | unit | meaning |
//! |---|---|---|
//! | `t` | s | robot-clock time of the joint sample |
//! | `q1` .. `qN` | deg | joint readings |
//! | `nom_x`, `nom_y`, `nom_z` | mm | nominal tool point of the fusing model, frame R |
//! | `dev_u` | mm | measured minus nominal tool point along `u` (in plane, across the path) |
//! | `u_x`, `u_y`, `u_z` | 1 | unit in-plane normal of the path, frame R |
//! | `dev_n` | mm | measured minus nominal tool point along `n` (out of plane) |
//! | `n_x`, `n_y`, `n_z` | 1 | unit sheet normal (out of the paper), frame R |
//!
//! So the measured tool point `P` satisfies `u . P = u . nom + dev_u` and
//! `n . P = n . nom + dev_n`; these two projections are what a calibration may use
//! ([`crate::calib::projected`]), independently of the model used for fusing.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::Vector3;

use super::error::FusionError;
use crate::calib::samples::FusedSample;
use crate::io::atomic::write_text_atomic;
use crate::io::finite::TextFormat;
use crate::io::table::Table;

/// Format tag in the first comment line of `FUSED.csv`.
pub const FUSED_FORMAT: &str = "rigctl-fused/1";

/// The header row of `FUSED.csv` for `n_joints` joints.
pub fn fused_header(n_joints: usize) -> String {
    let mut h = String::from("t");
    for j in 1..=n_joints {
        let _ = write!(h, ",q{j}");
    }
    h.push_str(",nom_x,nom_y,nom_z,dev_u,u_x,u_y,u_z,dev_n,n_x,n_y,n_z");
    h
}

/// The text of `FUSED.csv`.
pub fn fused_csv(samples: &[FusedSample]) -> String {
    let nj = samples.first().map_or(0, |s| s.q_deg.len());
    let mut out =
        format!("# {FUSED_FORMAT}: partial tool-point errors, see rigctl::fusion::fuse\n");
    out.push_str(&fused_header(nj));
    out.push('\n');
    for s in samples {
        let _ = write!(out, "{}", s.t_s);
        for q in &s.q_deg {
            let _ = write!(out, ",{q}");
        }
        let v = [
            s.nominal_mm.x,
            s.nominal_mm.y,
            s.nominal_mm.z,
            s.dev_u_mm,
            s.u.x,
            s.u.y,
            s.u.z,
            s.dev_n_mm,
            s.n.x,
            s.n.y,
            s.n.z,
        ];
        for x in v {
            let _ = write!(out, ",{x}");
        }
        out.push('\n');
    }
    out
}

/// Writes `FUSED.csv` atomically.
pub fn write_fused(path: &Path, samples: &[FusedSample]) -> Result<(), FusionError> {
    write_text_atomic(path, TextFormat::Csv, &fused_csv(samples))?;
    Ok(())
}

/// What a `FUSED.csv` without sample rows lacks.
const NO_FUSED_ROWS: &str = "no sample rows";

/// Parses the text of `FUSED.csv` with `n_joints` joints (`path` names it in errors).
pub fn parse_fused(
    text: &str,
    path: &Path,
    n_joints: usize,
) -> Result<Vec<FusedSample>, FusionError> {
    let table = Table::parse(text, &path.display().to_string())
        .map_err(|e| FusionError::from_table(e, path, NO_FUSED_ROWS))?;
    fused_from_table(&table, path, n_joints)
}

/// Reads `FUSED.csv`.
pub fn read_fused(path: &Path, n_joints: usize) -> Result<Vec<FusedSample>, FusionError> {
    let table = Table::read(path).map_err(|e| FusionError::from_table(e, path, NO_FUSED_ROWS))?;
    fused_from_table(&table, path, n_joints)
}

/// The samples of a parsed `FUSED.csv` table (every column of [`fused_header`] required,
/// finite; `u` and `n` unit vectors).
fn fused_from_table(
    table: &Table,
    path: &Path,
    n_joints: usize,
) -> Result<Vec<FusedSample>, FusionError> {
    let table_err = |e| FusionError::from_table(e, path, NO_FUSED_ROWS);
    let cols: Vec<usize> = fused_header(n_joints)
        .split(',')
        .map(|name| table.need(name))
        .collect::<Result<_, _>>()
        .map_err(table_err)?;
    let mut out = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let v: Vec<f64> = cols
            .iter()
            .map(|&c| table.number(row, c))
            .collect::<Result<_, _>>()
            .map_err(table_err)?;
        let at = |k: usize| v[1 + n_joints + k];
        let u = Vector3::new(at(4), at(5), at(6));
        let n = Vector3::new(at(8), at(9), at(10));
        for (dir, name) in [(u, "u_x"), (n, "n_x")] {
            if (dir.norm() - 1.0).abs() > 1e-6 {
                return Err(FusionError::csv(
                    path,
                    row.line,
                    name,
                    format!("direction of length {} is not a unit vector", dir.norm()),
                ));
            }
        }
        // u lies in the sheet, n is the sheet's normal: two independent measured directions
        if u.dot(&n).abs() > 1e-3 {
            return Err(FusionError::csv(
                path,
                row.line,
                "u_x",
                format!(
                    "u is not perpendicular to n (u.n = {:.6}): the two measured components are not independent",
                    u.dot(&n)
                ),
            ));
        }
        out.push(FusedSample {
            t_s: v[0],
            q_deg: v[1..=n_joints].to_vec(),
            nominal_mm: Vector3::new(at(0), at(1), at(2)),
            dev_u_mm: at(3),
            u,
            dev_n_mm: at(7),
            n,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
