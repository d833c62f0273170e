//! `JOINTS_TILT.csv`: inclinometer readings for joint-tilting identification (see the module
//! doc of [`super`] for the columns).

use std::path::Path;

use super::table::{Table, TableError};
use crate::model::Model;

/// One inclinometer reading.
#[derive(Debug, Clone, PartialEq)]
pub struct TiltReading {
    /// Line in the file (1-based).
    pub line: usize,
    /// Joint whose tilt is read (0-based index; the file's `joint` column is 1-based).
    pub joint: usize,
    /// Free configuration label (`config` column).
    pub config: String,
    /// Joint readings q1..qN (deg).
    pub q_deg: Vec<f64>,
    /// Payload at the tool point (kg); 0 when the column is absent.
    pub payload_kg: f64,
    /// Inclinometer angles about x, y, z of joint frame i (deg); `None` = not measured.
    pub incl_deg: [Option<f64>; 3],
}

/// Reads `JOINTS_TILT.csv`, checking joint indices, joint limits and the payload against `model`.
pub fn read_readings(path: &Path, model: &Model) -> Result<Vec<TiltReading>, TableError> {
    parse_readings(&Table::read(path)?, model)
}

/// Readings from an already parsed table.
pub fn parse_readings(table: &Table, model: &Model) -> Result<Vec<TiltReading>, TableError> {
    let n = model.n_joints();
    let joint_col = table.need("joint")?;
    let config_col = table.need("config")?;
    let q_cols = (1..=n)
        .map(|i| table.need(&format!("q{i}")))
        .collect::<Result<Vec<_>, _>>()?;
    let payload_col = table.find("payload_kg");
    let incl_cols = [
        table.need("incl_x_deg")?,
        table.need("incl_y_deg")?,
        table.need("incl_z_deg")?,
    ];
    let limits = model.joint_limits();
    let mut out = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let j = table.number(row, joint_col)?;
        if j.fract() != 0.0 || j < 1.0 || j > n as f64 {
            return Err(table.bad(row, joint_col, format!("expected a joint number 1..{n}")));
        }
        let mut q_deg = Vec::with_capacity(n);
        for (&c, lim) in q_cols.iter().zip(&limits) {
            let v = table.number(row, c)?;
            if v < lim[0] - 1e-9 || v > lim[1] + 1e-9 {
                return Err(table.bad(
                    row,
                    c,
                    format!("outside the joint limits [{}, {}]", lim[0], lim[1]),
                ));
            }
            q_deg.push(v);
        }
        let payload_kg = match payload_col {
            Some(c) => {
                let p = table.optional_number(row, c)?.unwrap_or(0.0);
                if p < 0.0 {
                    return Err(table.bad(row, c, "negative mass"));
                }
                p
            }
            None => 0.0,
        };
        let mut incl_deg = [None; 3];
        for (slot, &c) in incl_deg.iter_mut().zip(&incl_cols) {
            *slot = table.optional_number(row, c)?;
        }
        out.push(TiltReading {
            line: row.line,
            joint: j as usize - 1,
            config: row.fields[config_col].clone(),
            q_deg,
            payload_kg,
            incl_deg,
        });
    }
    Ok(out)
}

/// The CSV header for a model with `n_joints` joints.
pub fn header(n_joints: usize) -> String {
    let q: Vec<String> = (1..=n_joints).map(|i| format!("q{i}")).collect();
    format!(
        "joint,config,{},payload_kg,incl_x_deg,incl_y_deg,incl_z_deg",
        q.join(",")
    )
}

/// One reading as a CSV row (9 decimals) in the order of [`header`].
pub fn row(r: &TiltReading) -> String {
    let q: Vec<String> = r.q_deg.iter().map(|v| format!("{v:.9}")).collect();
    let incl: Vec<String> = r
        .incl_deg
        .iter()
        .map(|v| v.map(|v| format!("{v:.9}")).unwrap_or_default())
        .collect();
    format!(
        "{},{},{},{:.9},{}",
        r.joint + 1,
        r.config,
        q.join(","),
        r.payload_kg,
        incl.join(",")
    )
}
