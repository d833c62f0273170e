//! The model against the reference tables of shared/data/reference (computed independently from
//! MODEL.md): every row of katana_fk.csv (FK with and without tilting, parameter overrides,
//! both tool lengths) and of katana_tilt.csv (moments and tilts).
//!
//! katana_fk.csv prints the joint angles to 6 decimals while its outputs were computed from
//! the unrounded angles (a joint-space offset of at most ~5e-7 deg explains every row's
//! deviation to 1e-9). So: (1) rows whose angles are exact (all 0) must match within 1e-6;
//! (2) every other row must match within 1e-6 plus the first-order effect of the printed
//! rounding, `5e-7 * sum_j |dy/dq_j|`; (3) the tilting increment `y(tilt) - y(no tilt)` of each
//! row pair, where that rounding cancels, must match within 1e-6.

use crate::common;
use crate::common::record::record;

use rigctl::model::{katana450, Model, Tilt};

const TOL: f64 = 1e-6;
/// Half of the last printed digit of the reference's joint angles (deg).
const Q_ROUNDING_DEG: f64 = 5e-7;

struct Table {
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Table {
    fn read(name: &str) -> Option<Table> {
        let path = common::shared_file(name, &format!("data/reference/{name}"))?;
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.starts_with('#') && !l.trim().is_empty());
        let header = lines
            .next()
            .expect("header")
            .1
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|(i, l)| (i + 1, l.split(',').map(str::to_string).collect()))
            .collect();
        Some(Table { header, rows })
    }

    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("column {name}"))
    }

    fn num(&self, row: &[String], name: &str) -> f64 {
        let v = &row[self.col(name)];
        v.parse()
            .unwrap_or_else(|_| panic!("number in column {name}: {v:?}"))
    }
}

const OUT: [&str; 6] = ["x", "y", "z", "phi", "theta", "psi"];

/// One row of katana_fk.csv, evaluated.
struct FkRow {
    line: usize,
    key: String,
    tilt: bool,
    q: Vec<f64>,
    want: [f64; 6],
    got: [f64; 6],
    /// `sum_j |dy_k/dq_j|` per output (per degree).
    q_sensitivity: [f64; 6],
}

fn outputs(model: &Model, q: &[f64], tilt: Tilt<'_>) -> [f64; 6] {
    let fk = model.fk(q, tilt).unwrap();
    let [phi, theta, psi] = fk.zxz_deg();
    [
        fk.position_mm.x,
        fk.position_mm.y,
        fk.position_mm.z,
        phi,
        theta,
        psi,
    ]
}

fn fk_rows() -> Option<Vec<FkRow>> {
    let t = Table::read("katana_fk.csv")?;
    assert!(t.rows.len() >= 100, "reference has {} rows", t.rows.len());
    let rows = t
        .rows
        .iter()
        .map(|(line, row)| {
            let mut model = katana450(t.num(row, "tool_mm")).unwrap();
            let set = &row[t.col("set")];
            for kv in set.split(';').filter(|s| !s.is_empty()) {
                let (k, v) = kv.split_once('=').unwrap();
                model.set_param(k, v.parse().unwrap()).unwrap();
            }
            let q: Vec<f64> = (1..=5).map(|i| t.num(row, &format!("q{i}"))).collect();
            let tilt_on = t.num(row, "tilt") != 0.0;
            let tilt = if tilt_on { Tilt::Static } else { Tilt::Off };
            let got = outputs(&model, &q, tilt);
            // Joint sensitivity: analytic for the position, central differences for the angles.
            let (_, jac) = model.joint_jacobian(&q, tilt).unwrap();
            let mut q_sensitivity = [0.0; 6];
            for j in 0..5 {
                let h = 1e-4;
                let mut qp = q.clone();
                qp[j] += h;
                let mut qm = q.clone();
                qm[j] -= h;
                let (yp, ym) = (outputs(&model, &qp, tilt), outputs(&model, &qm, tilt));
                for k in 0..6 {
                    let d = if k < 3 {
                        jac[(k, j)]
                    } else {
                        (yp[k] - ym[k]) / (2.0 * h)
                    };
                    q_sensitivity[k] += d.abs();
                }
            }
            FkRow {
                line: *line,
                key: format!(
                    "{}|{}|{}",
                    q.iter()
                        .map(|v| format!("{v}"))
                        .collect::<Vec<_>>()
                        .join(";"),
                    set,
                    t.num(row, "tool_mm")
                ),
                tilt: tilt_on,
                want: OUT.map(|c| t.num(row, c)),
                got,
                q,
                q_sensitivity,
            }
        })
        .collect();
    Some(rows)
}

#[test]
fn katana_fk_reference_rows() {
    let Some(rows) = fk_rows() else { return };
    let mut exact_rows = 0;
    for r in &rows {
        let exact_q = r.q.iter().all(|&q| q == 0.0);
        exact_rows += usize::from(exact_q);
        for (k, column) in OUT.iter().enumerate() {
            let allowed = if exact_q {
                TOL
            } else {
                TOL + Q_ROUNDING_DEG * r.q_sensitivity[k]
            };
            let err = (r.got[k] - r.want[k]).abs();
            assert!(
                err <= allowed,
                "katana_fk.csv line {}, column {}: got {:.9}, want {:.9} (|error| {err:.2e} > {allowed:.2e})",
                r.line,
                column,
                r.got[k],
                r.want[k]
            );
        }
    }
    assert!(exact_rows >= 2, "expected the q = 0 rows");
    record("fk_tolerance", TOL);
    record("fk_nonzero_rows", rows.len() - exact_rows);
    record("q_rounding_deg", Q_ROUNDING_DEG);
}

#[test]
fn katana_fk_reference_tilt_increments() {
    let Some(rows) = fk_rows() else { return };
    let mut pairs = 0;
    for on in rows.iter().filter(|r| r.tilt) {
        let Some(off) = rows.iter().find(|r| !r.tilt && r.key == on.key) else {
            continue;
        };
        pairs += 1;
        for (k, column) in OUT.iter().enumerate() {
            let got = on.got[k] - off.got[k];
            let want = on.want[k] - off.want[k];
            assert!(
                (got - want).abs() < TOL,
                "katana_fk.csv lines {} - {}, column {}: tilting moves it by {got:.9}, reference {want:.9}",
                on.line,
                off.line,
                column
            );
        }
    }
    assert!(pairs >= 50, "only {pairs} tilt on/off row pairs");
    record("tilt_pairs", pairs);
}

#[test]
fn katana_tilt_reference_rows() {
    let Some(t) = Table::read("katana_tilt.csv") else {
        return;
    };
    assert!(t.rows.len() >= 50, "reference has {} rows", t.rows.len());
    let model = katana450(200.0).unwrap();
    for (line, row) in &t.rows {
        let q: Vec<f64> = (1..=5).map(|i| t.num(row, &format!("q{i}"))).collect();
        let fk = model.fk(&q, Tilt::Static).unwrap();
        for i in 0..5 {
            let j = i + 1;
            for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                let want = t.num(row, &format!("eta{j}_{axis}"));
                let got = fk.moments_kgfm[i][k];
                assert!(
                    (got - want).abs() < TOL,
                    "katana_tilt.csv line {line}: eta{j}_{axis} got {got:.9} want {want:.9}"
                );
            }
            for (k, name) in ["da", "db", "dt"].iter().enumerate() {
                let want = t.num(row, &format!("{name}{j}"));
                let got = fk.tilts_deg[i][k];
                assert!(
                    (got - want).abs() < TOL,
                    "katana_tilt.csv line {line}: {name}{j} got {got:.9} want {want:.9}"
                );
            }
        }
    }
    record("tilt_tolerance", TOL);
}
