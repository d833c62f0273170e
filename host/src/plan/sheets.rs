//! `rigctl plan --sheets`: candidate pencil-sheet placements and paths ranked by what they
//! identify.
//!
//! A candidate is a plane (azimuth of its centre about the base axis, distance from the axis,
//! height, tilt from horizontal; the sheet faces the robot, the thesis's 45-degree plane through
//! [`SESSION_SHEET_ORIGIN_MM`] among them) and a path on it (the 100 mm circle, or a 180 mm line
//! along the sheet's x or y axis), drawn as in the simulated session: the pencil axis fixed at
//! [`default_pencil_axis`], joints from the IK of the declared rigid model at
//! [`SHEET_SAMPLES`] points of the path. A candidate is kept when every point is reachable
//! within the joint limits and satisfies the workspace constraints (table clearance).
//!
//! What a sheet measures is what `rigctl fuse` gives: at every sample the deviation across the
//! path in the sheet plane (`u`, from the trace) and out of the sheet (`n`, from the pencil's
//! potentiometer) -- the along-path error is not measured. So a sample contributes the two rows
//! `u^T J` and `n^T J` of the identification Jacobian (the declared static tilting on);
//! [`SheetRows`] also offers the trace alone (`u`) and a time-stamped in-plane position (`u`
//! and along the path: the Jacobian projected onto the plane). Per
//! sheet and per pair of sheets: the parameters identifiable from those rows (SVD with
//! [`DEFAULT_RTOL`] on the column-scaled Jacobian), the blind ones (named null-space
//! combinations), the condition number of the identifiable part and the expected sigmas for
//! `noise_mm` per component. Samples along a path are taken as independent: the real residuals
//! are serially correlated, so the sigmas are lower bounds; the ranking is what matters.

use nalgebra::{DMatrix, Vector3};

use super::candidates::Workspace;
use super::metrics::{design_stats, median};
use super::PlanError;
use crate::calib::default_selection;
use crate::calib::identifiability::{analyse, DEFAULT_RTOL};
use crate::calib::MeasuredSet;
use crate::diagnose::extended::{ExtModel, Unknown};
use crate::fusion::SheetPlacement;
use crate::model::ik::KATANA_SEED_DEG;
use crate::model::ik::{solve, ArmGeometry, IkTilt, ToolTarget};
use crate::model::Model;
use crate::sheet::drawn::{default_pencil_axis, SessionPath, SESSION_SHEET_ORIGIN_MM};

/// Samples along every path (the circle every 5 deg; the line every 5 mm).
pub const SHEET_SAMPLES: usize = 37;

/// Half length of a candidate line, mm.
pub const LINE_HALF_LENGTH_MM: f64 = 90.0;

/// A path on a sheet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SheetPath {
    /// The 100 mm circle about the sheet origin.
    Circle,
    /// A line along the sheet's x axis through the origin.
    LineX,
    /// A line along the sheet's y axis (up the slope) through the origin.
    LineY,
}

impl SheetPath {
    /// Name in the table and the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            SheetPath::Circle => "circle",
            SheetPath::LineX => "line_x",
            SheetPath::LineY => "line_y",
        }
    }

    /// Sheet point (mm) at parameter `s` in 0..1.
    fn point(self, s: f64) -> [f64; 2] {
        let l = LINE_HALF_LENGTH_MM * (2.0 * s - 1.0);
        match self {
            SheetPath::Circle => SessionPath::Circle.sheet_point(s),
            SheetPath::LineX => [l, 0.0],
            SheetPath::LineY => [0.0, l],
        }
    }

    /// Samples: the circle's end is its start, so it is left out.
    fn params(self) -> Vec<f64> {
        let k = SHEET_SAMPLES;
        match self {
            SheetPath::Circle => (0..k).map(|i| i as f64 / k as f64).collect(),
            _ => (0..k).map(|i| i as f64 / (k - 1) as f64).collect(),
        }
    }
}

/// What a sheet sample measures (`plan --sheet-rows`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum SheetRows {
    /// What `rigctl fuse` gives: across the path in the plane (`u`, the trace) and out of the
    /// plane (`n`, the pencil's potentiometer).
    #[default]
    Fused,
    /// The trace alone (`u`): no potentiometer.
    Trace,
    /// Both in-plane directions (`u` and along the path): a time-stamped 2-D position on the
    /// sheet, no potentiometer.
    Plane,
}

impl SheetRows {
    /// Parses `fused`, `trace` or `plane`.
    pub fn parse(s: &str) -> Option<Self> {
        // the names are clap's (`ValueEnum`)
        <Self as clap::ValueEnum>::from_str(s, false).ok()
    }

    /// The name.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Fused => "fused",
            Self::Trace => "trace",
            Self::Plane => "plane",
        }
    }
}

/// Where a candidate sheet lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SheetSpec {
    /// Azimuth of the sheet centre about the base axis, deg (-90: the thesis's side, -y).
    pub azimuth_deg: f64,
    /// Horizontal distance of the centre from the base axis, mm.
    pub distance_mm: f64,
    /// Height of the centre above the base frame, mm.
    pub height_mm: f64,
    /// Tilt of the sheet from horizontal, deg (rising away from the robot; 45: the thesis).
    pub tilt_deg: f64,
    /// Azimuth the sheet faces away from, deg: it rises towards this azimuth (-90 on the
    /// thesis's plane wherever its centre is; the centre's azimuth on the grid).
    pub facing_deg: f64,
    /// The path.
    pub path: SheetPath,
}

impl SheetSpec {
    /// The placement: centre at the azimuth, distance and height; normal `cos t z - sin t e_f`
    /// (`e_f` horizontal towards `facing_deg`: facing the robot and up), x axis `-e_t`
    /// (`e_t = z x e_f`: the thesis's -x of R when facing -90), y axis `n x x` (up the slope).
    pub fn placement(&self) -> SheetPlacement {
        let (az, t) = (self.azimuth_deg.to_radians(), self.tilt_deg.to_radians());
        let f = self.facing_deg.to_radians();
        let e_r = Vector3::new(az.cos(), az.sin(), 0.0);
        let e_f = Vector3::new(f.cos(), f.sin(), 0.0);
        let e_t = Vector3::new(-f.sin(), f.cos(), 0.0);
        let n = Vector3::z() * t.cos() - e_f * t.sin();
        let x = -e_t;
        SheetPlacement {
            origin_mm: e_r * self.distance_mm + Vector3::z() * self.height_mm,
            x_axis: x,
            y_axis: n.cross(&x),
        }
    }

    /// A short label: `circle az-75 r207 h200 t45f-90` (`f`: facing, when not the azimuth).
    pub fn label(&self) -> String {
        let facing = if (self.facing_deg - self.azimuth_deg).abs() > 0.5 {
            format!("f{:.0}", self.facing_deg)
        } else {
            String::new()
        };
        format!(
            "{} az{:.0} r{:.0} h{:.0} t{:.0}{facing}",
            self.path.as_str(),
            self.azimuth_deg,
            self.distance_mm,
            self.height_mm,
            self.tilt_deg
        )
    }
}

/// The candidate sheets, each with every path: the thesis's 45-degree plane (facing -90) with
/// its centre at the simulated sessions' [`SESSION_SHEET_ORIGIN_MM`] and moved 50 mm along x, y
/// or z; and a grid of centre azimuths (-90, -45, 0 deg), distances (250, 350 mm), heights
/// (100, 250 mm) and tilts (0, 45, 90 deg), each sheet facing its own azimuth.
pub fn candidate_specs() -> Vec<SheetSpec> {
    let o = Vector3::from(SESSION_SHEET_ORIGIN_MM);
    let mut places = Vec::new();
    let shifts = [
        Vector3::zeros(),
        Vector3::x() * 50.0,
        Vector3::x() * -50.0,
        Vector3::y() * 50.0,
        Vector3::y() * -50.0,
        Vector3::z() * 50.0,
        Vector3::z() * -50.0,
    ];
    for d in shifts {
        let c = o + d;
        places.push((
            c.y.atan2(c.x).to_degrees(),
            c.x.hypot(c.y),
            c.z,
            45.0,
            -90.0,
        ));
    }
    for az in [-90.0, -45.0, 0.0] {
        for dist in [250.0, 350.0] {
            for h in [100.0, 250.0] {
                for tilt in [0.0, 45.0, 90.0] {
                    places.push((az, dist, h, tilt, az));
                }
            }
        }
    }
    let mut out = Vec::new();
    for (azimuth_deg, distance_mm, height_mm, tilt_deg, facing_deg) in places {
        for path in [SheetPath::Circle, SheetPath::LineX, SheetPath::LineY] {
            out.push(SheetSpec {
                azimuth_deg,
                distance_mm,
                height_mm,
                tilt_deg,
                facing_deg,
                path,
            });
        }
    }
    out
}

/// A reachable sheet with its samples' identification rows.
#[derive(Debug, Clone)]
pub struct SheetSamples {
    pub spec: SheetSpec,
    /// Joints of every sample, deg.
    pub q_deg: Vec<Vec<f64>>,
    /// Identification rows (per sample: see [`SheetRows`]), parameter units.
    pub rows: DMatrix<f64>,
}

/// The joints along `spec`'s path (IK of the declared rigid model, pencil axis fixed), or
/// `None` when a point is out of reach or outside `ws`.
pub fn sheet_joints(model: &Model, spec: &SheetSpec, ws: &Workspace) -> Option<Vec<Vec<f64>>> {
    let pl = spec.placement();
    let n = pl.normal();
    let axis = default_pencil_axis(&n);
    let mut seed = KATANA_SEED_DEG.to_vec();
    seed.resize(model.n_joints(), 0.0);
    let mut out = Vec::with_capacity(SHEET_SAMPLES);
    for s in spec.path.params() {
        let p = pl.to_r_mm(spec.path.point(s));
        if !ws.admits(&p, &axis) {
            return None;
        }
        let target = ToolTarget {
            position_mm: p,
            axis,
        };
        let q = solve(model, &target, &seed, IkTilt::Off).ok()?;
        if ws.violation(model, &q, &p, &axis).ok()?.is_some() {
            return None;
        }
        seed.clone_from(&q);
        out.push(q);
    }
    Some(out)
}

/// The measured directions at every sample (`u` across the path in the plane, `t` along it,
/// `n` the normal) for `what`.
fn directions(spec: &SheetSpec, what: SheetRows) -> Vec<Vec<Vector3<f64>>> {
    let pl = spec.placement();
    let n = pl.normal();
    let params = spec.path.params();
    let h = 1e-4;
    params
        .iter()
        .map(|&s| {
            let (a, b) = (spec.path.point(s + h), spec.path.point(s - h));
            let t = pl.dir_to_r([a[0] - b[0], a[1] - b[1]]).normalize();
            match what {
                SheetRows::Fused => vec![n.cross(&t), n],
                SheetRows::Trace => vec![n.cross(&t)],
                SheetRows::Plane => vec![n.cross(&t), t],
            }
        })
        .collect()
}

/// The identification rows of `q_deg` measured along `dirs`.
fn rows_of(
    ext: &ExtModel,
    unknowns: &[Unknown],
    q_deg: &[Vec<f64>],
    dirs: Vec<Vec<Vector3<f64>>>,
) -> Result<DMatrix<f64>, PlanError> {
    let data = MeasuredSet {
        directions: Some(dirs),
        ..MeasuredSet::from_points(q_deg.to_vec(), vec![Vector3::zeros(); q_deg.len()])
    };
    Ok(ext.stacked(&data, unknowns)?.0)
}

/// What one sheet (or a pair) identifies.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetScore {
    /// Indices into the reachable sheets (one or two).
    pub sheets: Vec<usize>,
    pub n_samples: usize,
    /// Identifiable parameters.
    pub identifiable: Vec<String>,
    /// Blind parameters or combinations (`"dth1"`, `"dth2+al3"`).
    pub blind: Vec<String>,
    /// Condition number of the column-scaled Jacobian of the identifiable parameters.
    pub condition_number: f64,
    /// Expected sigma of every parameter (infinite when blind), parameter units.
    pub sigma: Vec<f64>,
    /// Median sigma over the identifiable parameters (scaled by each parameter's 3-D
    /// candidate-set RMS column norm: mm of tool point per parameter unit, so degrees and mm
    /// compare; smaller is better).
    pub median_scaled_sigma: f64,
}

/// The `--sheets` result.
#[derive(Debug, Clone)]
pub struct SheetRanking {
    /// The parameters (those identifiable from 3-D poses).
    pub parameters: Vec<String>,
    /// Reachable candidate sheets with their samples.
    pub sheets: Vec<SheetSamples>,
    /// Candidates tried.
    pub tried: usize,
    /// What a sample measures.
    pub rows: SheetRows,
    /// Single sheets, best first.
    pub singles: Vec<SheetScore>,
    /// Pairs, best first.
    pub pairs: Vec<SheetScore>,
}

fn score(
    rows: &DMatrix<f64>,
    n_samples: usize,
    names: &[String],
    scale: &[f64],
    noise_mm: f64,
) -> SheetScore {
    let id = analyse(rows, DEFAULT_RTOL);
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let sub = DMatrix::from_fn(rows.nrows(), id.kept.len(), |r, c| rows[(r, id.kept[c])]);
    let st = design_stats(&sub, n_samples, noise_mm);
    let mut sigma = vec![f64::INFINITY; names.len()];
    for (k, &c) in id.kept.iter().enumerate() {
        sigma[c] = st.sigma[k];
    }
    let scaled: Vec<f64> = id.kept.iter().map(|&c| sigma[c] * scale[c]).collect();
    SheetScore {
        sheets: Vec::new(),
        n_samples,
        identifiable: id.kept.iter().map(|&c| names[c].clone()).collect(),
        blind: id.combinations.iter().map(|c| c.name(&refs)).collect(),
        condition_number: st.condition_number,
        sigma,
        median_scaled_sigma: median(&scaled),
    }
}

/// Best first: fewest blind, then smallest median scaled sigma, then condition number.
fn rank(v: &mut [SheetScore]) {
    v.sort_by(|a, b| {
        a.blind
            .len()
            .cmp(&b.blind.len())
            .then(a.median_scaled_sigma.total_cmp(&b.median_scaled_sigma))
            .then(a.condition_number.total_cmp(&b.condition_number))
    });
}

/// Ranks the candidate sheets `specs` for `model` (the parameters identifiable on 3-D poses:
/// `parameters`, column scale `scale` from the 3-D candidates), each sample measuring `what`.
pub fn rank_sheets(
    model: &Model,
    specs: &[SheetSpec],
    ws: &Workspace,
    parameters: &[String],
    scale: &[f64],
    noise_mm: f64,
    what: SheetRows,
) -> Result<SheetRanking, PlanError> {
    ArmGeometry::of(model).map_err(|e| {
        PlanError::Config(format!(
            "--sheets needs a Katana-type arm (the pencil rig's IK): {e}"
        ))
    })?;
    let mut ext = ExtModel::new(model.clone());
    ext.model.set_tilt_direction_frozen(true);
    let unknowns: Vec<Unknown> = default_selection(model, false)
        .into_iter()
        .map(Unknown::Param)
        .filter(|u| parameters.contains(&u.name(model)))
        .collect();
    let names: Vec<String> = unknowns.iter().map(|u| u.name(model)).collect();
    let scale: Vec<f64> = names
        .iter()
        .map(|n| {
            parameters
                .iter()
                .position(|p| p == n)
                .and_then(|k| scale.get(k).copied())
                .unwrap_or(1.0)
        })
        .collect();
    let scale = &scale[..];
    let mut sheets = Vec::new();
    for spec in specs {
        if let Some(q) = sheet_joints(model, spec, ws) {
            let rows = rows_of(&ext, &unknowns, &q, directions(spec, what))?;
            sheets.push(SheetSamples {
                spec: *spec,
                q_deg: q,
                rows,
            });
        }
    }
    let mut singles: Vec<SheetScore> = Vec::with_capacity(sheets.len());
    for (i, s) in sheets.iter().enumerate() {
        let mut sc = score(&s.rows, s.q_deg.len(), &names, scale, noise_mm);
        sc.sheets = vec![i];
        singles.push(sc);
    }
    let mut pairs = Vec::new();
    for i in 0..sheets.len() {
        for j in i + 1..sheets.len() {
            let (a, b) = (&sheets[i].rows, &sheets[j].rows);
            let both = DMatrix::from_fn(a.nrows() + b.nrows(), a.ncols(), |r, c| {
                if r < a.nrows() {
                    a[(r, c)]
                } else {
                    b[(r - a.nrows(), c)]
                }
            });
            let k = sheets[i].q_deg.len() + sheets[j].q_deg.len();
            let mut sc = score(&both, k, &names, scale, noise_mm);
            sc.sheets = vec![i, j];
            pairs.push(sc);
        }
    }
    rank(&mut singles);
    rank(&mut pairs);
    Ok(SheetRanking {
        parameters: names,
        sheets,
        tried: specs.len(),
        rows: what,
        singles,
        pairs,
    })
}
