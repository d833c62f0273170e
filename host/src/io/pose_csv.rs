//! Pose CSV files (FORMATS.md "Pose files"): a header naming the columns, one pose per row,
//! `#` comment lines. Columns `q1..qN` (deg, mm for a prismatic joint) are required; `x,y,z`
//! (mm) are required when the caller needs measured positions and checked whenever present;
//! extensions (README "Pose files: extensions"): several measured points per pose as
//! `x1,y1,z1,...,xk,yk,zk` instead of `x,y,z` (all k complete, no empty cell; when `x,y,z`
//! are all present they are the measurement and numbered columns are other columns); the joint
//! columns named by the model's joint names ([`PoseSpec::joint_names`]) instead of `q1..qN`;
//! lengths and angles in other units ([`PoseSpec::units`], converted to mm / deg here);
//! `t` (s) is optional and numeric; `id` is optional text; any other column is kept as text and
//! ignored. A missing, non-numeric, NaN or infinite value in a used column, a wrong field
//! count, or a joint outside its limits is [`PoseCsvError`] (bad input) naming the file, the
//! line (1-based, physical) and the column.

use std::path::Path;

use super::dialect::Dialect;
use super::table::{Table, TableError};
use super::units::{AngleUnit, LengthUnit, Units};
use crate::error::{Classify, ErrorKind};

/// What a reader expects of a pose file (`PoseSpec::for_model` builds it from a model, in
/// `crate::model`, so that this reader does not depend on the model).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSpec {
    /// Number of joint columns `q1..qN` required.
    pub n_joints: usize,
    /// Joint limits `[min, max]` per joint; empty = no limit check.
    pub limits: Vec<[f64; 2]>,
    /// Whether `x, y, z` (or `x1, y1, z1, ...`) must be present.
    pub require_xyz: bool,
    /// Names of the joints (e.g. URDF joint names), used for the joint columns when the file
    /// has no `q1`; empty = `q1..qN` only.
    pub joint_names: Vec<String>,
    /// Which joints are prismatic (their readings are lengths); empty = all revolute.
    pub prismatic: Vec<bool>,
    /// Units of the file's lengths and angles.
    pub units: Units,
    /// The measured point reported as [`Pose::xyz_mm`] in a file with several (0-based).
    pub marker: usize,
    /// Field separator and decimal mark of the file (`--sep`, `--decimal`).
    pub dialect: Dialect,
}

/// One row of a pose file.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// Line number in the file (1-based).
    pub line: usize,
    /// Joint readings `q1..qN` (deg; mm for a prismatic joint).
    pub q: Vec<f64>,
    /// Measured tool point (mm, frame R), when the file has `x,y,z` (in a file with several
    /// points, point [`PoseSpec::marker`]).
    pub xyz_mm: Option<[f64; 3]>,
    /// Every measured point of the row (mm, frame R): one for `x,y,z`, k for `x1..zk`, none
    /// without measured positions.
    pub markers_mm: Vec<[f64; 3]>,
    /// Time since the start of the session (s), when the file has `t`.
    pub t_s: Option<f64>,
    /// Pose name, when the file has `id`.
    pub id: Option<String>,
    /// The other columns' text, in the order of [`PoseFile::extra_columns`].
    pub extra: Vec<String>,
}

/// A parsed pose file.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseFile {
    /// The file name used in messages.
    pub source: String,
    /// The header's column names.
    pub header: Vec<String>,
    /// Names of the columns kept as text (not q, x, y, z, t, id).
    pub extra_columns: Vec<String>,
    /// The poses, in file order.
    pub poses: Vec<Pose>,
}

impl PoseFile {
    /// Joint vectors of all poses.
    pub fn joints(&self) -> Vec<Vec<f64>> {
        self.poses.iter().map(|p| p.q.clone()).collect()
    }

    /// Measured positions of all poses (`None` if the file has no `x,y,z`).
    pub fn positions_mm(&self) -> Option<Vec<[f64; 3]>> {
        self.poses.iter().map(|p| p.xyz_mm).collect()
    }

    /// Number of measured points per pose (0 without measured positions).
    pub fn n_markers(&self) -> usize {
        self.poses.first().map_or(0, |p| p.markers_mm.len())
    }

    /// Text of extra column `name` of pose `i`.
    pub fn extra(&self, i: usize, name: &str) -> Option<&str> {
        let c = self.extra_columns.iter().position(|n| n == name)?;
        self.poses.get(i)?.extra.get(c).map(String::as_str)
    }
}

/// A pose file that cannot be used (always bad input, exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum PoseCsvError {
    #[error("cannot read pose file {file}: {source}")]
    Read {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// The shared table reader's errors (header, columns, field counts, numbers), with its
    /// messages naming the file, line and column.
    #[error(transparent)]
    Table(TableError),
    #[error("{file}: no pose rows")]
    NoPoses { file: String },
    /// A header that mixes part of `x,y,z` with numbered points `x1..`, or names a point beyond those
    /// the caller can use.
    #[error("{file}:{line}: column `{column}`: {problem}")]
    Columns {
        file: String,
        line: usize,
        column: String,
        problem: String,
    },
    /// A joint reading outside the model's limits, all in the file's own unit (`unit`);
    /// `hint` says when the value is within the limits read in the other unit.
    #[error(
        "{file}:{line}: column `{column}`: joint value {value} outside the limits [{min}, {max}] \
         {unit}{hint}"
    )]
    JointLimit {
        file: String,
        line: usize,
        column: String,
        value: f64,
        min: f64,
        max: f64,
        unit: &'static str,
        hint: String,
    },
    /// The file has fewer joint columns than the model has joints (another robot's file).
    #[error(
        "{file}:{line}: {in_file} joint{s} in the file ({columns}), {in_model} in the model \
         (not in the file: {missing}): a file of another robot, or another --robot / --model?",
        s = if *in_file == 1 { "" } else { "s" }
    )]
    JointCount {
        file: String,
        line: usize,
        in_file: usize,
        in_model: usize,
        columns: String,
        /// The model's joints the file lacks.
        missing: String,
    },
}

impl Classify for PoseCsvError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::BadInput
    }
}

/// The shared table reader's errors; a file with no data rows is [`PoseCsvError::NoPoses`].
impl From<TableError> for PoseCsvError {
    fn from(e: TableError) -> Self {
        match e {
            TableError::NoRows { file, .. } => Self::NoPoses { file },
            e => Self::Table(e),
        }
    }
}

/// Reads and checks a pose file.
pub fn read_poses(path: &Path, spec: &PoseSpec) -> Result<PoseFile, PoseCsvError> {
    let file = path.display().to_string();
    let text =
        crate::io::read::read_text_capped(path, crate::io::read::CAP_TABLE).map_err(|source| {
            PoseCsvError::Read {
                file: file.clone(),
                source,
            }
        })?;
    parse_poses(&text, &file, spec)
}

/// Where each used column sits in a row.
struct Layout {
    q: Vec<usize>,
    /// `[x, y, z]` columns of every measured point.
    markers: Vec<[usize; 3]>,
    t: Option<usize>,
    id: Option<usize>,
    extra: Vec<usize>,
}

/// The joint columns: `q1..qN`, or the joint names when the file has no `q1` and the spec
/// names the joints. A file with fewer of them than the model has joints (`q1..qM`, M < N,
/// or M of the names) is [`PoseCsvError::JointCount`].
fn joint_columns(table: &Table, spec: &PoseSpec) -> Result<Vec<usize>, PoseCsvError> {
    let by_name = table.find("q1").is_none()
        && spec.joint_names.len() == spec.n_joints
        && spec.joint_names.iter().any(|n| table.find(n).is_some());
    let name = |i: usize| match by_name {
        true => spec.joint_names[i].clone(),
        false => format!("q{}", i + 1),
    };
    let found: Vec<usize> = if by_name {
        (0..spec.n_joints)
            .filter(|&i| table.find(&name(i)).is_some())
            .collect()
    } else {
        (0..)
            .take_while(|&i| table.find(&name(i)).is_some())
            .collect()
    };
    if !found.is_empty() && found.len() < spec.n_joints {
        let columns = match by_name {
            true => found
                .iter()
                .map(|&i| name(i))
                .collect::<Vec<_>>()
                .join(", "),
            false if found.len() == 1 => "q1".into(),
            false => format!("q1..q{}", found.len()),
        };
        let missing = match by_name {
            true => (0..spec.n_joints)
                .filter(|i| !found.contains(i))
                .map(name)
                .collect::<Vec<_>>()
                .join(", "),
            false if found.len() + 1 == spec.n_joints => name(found.len()),
            false => format!("{}..{}", name(found.len()), name(spec.n_joints - 1)),
        };
        return Err(PoseCsvError::JointCount {
            file: table.file.clone(),
            line: table.header_line,
            in_file: found.len(),
            in_model: spec.n_joints,
            columns,
            missing,
        });
    }
    Ok((0..spec.n_joints)
        .map(|i| table.need(&name(i)))
        .collect::<Result<_, _>>()?)
}

/// The unit of a joint's readings in a file of `units` and, for the message, the other unit
/// and the `--units` value that names it.
fn joint_unit(units: Units, prismatic: bool) -> (&'static str, Units, &'static str) {
    let mut other = units;
    let (unit, other_name) = if prismatic {
        match units.length {
            LengthUnit::Mm => {
                other.length = LengthUnit::M;
                ("mm", "m")
            }
            LengthUnit::M => {
                other.length = LengthUnit::Mm;
                ("m", "mm")
            }
        }
    } else {
        match units.angle {
            AngleUnit::Deg => {
                other.angle = AngleUnit::Rad;
                ("deg", "rad")
            }
            AngleUnit::Rad => {
                other.angle = AngleUnit::Deg;
                ("rad", "deg")
            }
        }
    };
    (unit, other, other_name)
}

/// [`PoseCsvError::JointLimit`] for the file's value `raw` (in `spec.units`) of joint `j`,
/// limits `[min, max]` in model units (deg, mm).
fn limit_error(
    table: &Table,
    row: &super::table::Row,
    col: usize,
    spec: &PoseSpec,
    j: usize,
    raw: f64,
    [min, max]: [f64; 2],
) -> PoseCsvError {
    let prismatic = spec.prismatic.get(j).copied().unwrap_or(false);
    let (unit, other, other_name) = joint_unit(spec.units, prismatic);
    let per = spec.units.joint(1.0, prismatic);
    let in_other = other.joint(raw, prismatic);
    let hint = if (min..=max).contains(&in_other) {
        let flag = format!(
            "{},{}",
            if other.length == LengthUnit::M {
                "m"
            } else {
                "mm"
            },
            if other.angle == AngleUnit::Rad {
                "rad"
            } else {
                "deg"
            }
        );
        format!(
            "; read as {other_name} it is within them: is the file in {other_name}? \
             (--units {flag})"
        )
    } else {
        String::new()
    };
    PoseCsvError::JointLimit {
        file: table.file.clone(),
        line: row.line,
        column: table.header[col].clone(),
        value: raw,
        min: min / per,
        max: max / per,
        unit,
        hint,
    }
}

/// The measured points' columns: `x,y,z` when all three are present (FORMATS.md; any numbered
/// column `x1`, `z2`, .. is then an other column, kept and ignored), else `x1,y1,z1 .. xk,yk,zk`
/// (every point complete).
fn marker_columns(table: &Table, spec: &PoseSpec) -> Result<Vec<[usize; 3]>, PoseCsvError> {
    let numbered = |name: &str| -> Option<usize> {
        let rest = name.strip_prefix(['x', 'y', 'z'])?;
        let k: usize = rest
            .parse()
            .ok()
            .filter(|_| rest.bytes().all(|b| b.is_ascii_digit()))?;
        Some(k)
    };
    let plain = ["x", "y", "z"].map(|a| table.find(a));
    if let [Some(x), Some(y), Some(z)] = plain {
        return Ok(vec![[x, y, z]]);
    }
    let k_max = table.header.iter().filter_map(|h| numbered(h)).max();
    let cols = match k_max {
        Some(k_max) => {
            if let Some(c) = plain.iter().flatten().next() {
                return Err(PoseCsvError::Columns {
                    file: table.file.clone(),
                    line: table.header_line,
                    column: table.header[*c].clone(),
                    problem: "an incomplete plain x,y,z in a file with numbered points \
                              x1,y1,z1.. (give all of x,y,z or none)"
                        .into(),
                });
            }
            if k_max == 0 {
                return Err(TableError::MissingColumn {
                    file: table.file.clone(),
                    line: table.header_line,
                    column: "x1".into(),
                }
                .into());
            }
            (1..=k_max)
                .map(|k| {
                    Ok([
                        table.need(&format!("x{k}"))?,
                        table.need(&format!("y{k}"))?,
                        table.need(&format!("z{k}"))?,
                    ])
                })
                .collect::<Result<Vec<_>, TableError>>()?
        }
        None => match plain {
            [None, None, None] if !spec.require_xyz => Vec::new(),
            _ => vec![[table.need("x")?, table.need("y")?, table.need("z")?]],
        },
    };
    if !cols.is_empty() && spec.marker >= cols.len() {
        return Err(PoseCsvError::Columns {
            file: table.file.clone(),
            line: table.header_line,
            column: format!("x{}", spec.marker + 1),
            problem: format!(
                "point {} asked for, the file has {}",
                spec.marker + 1,
                cols.len()
            ),
        });
    }
    Ok(cols)
}

impl Layout {
    fn new(table: &Table, spec: &PoseSpec) -> Result<Self, PoseCsvError> {
        let q = joint_columns(table, spec)?;
        let markers = marker_columns(table, spec)?;
        let (t, id) = (table.find("t"), table.find("id"));
        let used: Vec<usize> = q
            .iter()
            .copied()
            .chain(markers.iter().flatten().copied())
            .chain(t)
            .chain(id)
            .collect();
        let extra = (0..table.header.len())
            .filter(|i| !used.contains(i))
            .collect();
        Ok(Self {
            q,
            markers,
            t,
            id,
            extra,
        })
    }
}

/// Parses pose-file text (a leading byte-order mark is ignored); `file` names it in messages.
pub fn parse_poses(text: &str, file: &str, spec: &PoseSpec) -> Result<PoseFile, PoseCsvError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let table = Table::parse_dialect(text, file, spec.dialect)?;
    let lay = Layout::new(&table, spec)?;
    let mut poses = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let mut q = Vec::with_capacity(lay.q.len());
        for (j, &col) in lay.q.iter().enumerate() {
            let prismatic = spec.prismatic.get(j).copied().unwrap_or(false);
            let raw = table.number(row, col)?;
            let v = spec.units.joint(raw, prismatic);
            if let Some(&[min, max]) = spec.limits.get(j) {
                if v < min || v > max {
                    return Err(limit_error(&table, row, col, spec, j, raw, [min, max]));
                }
            }
            q.push(v);
        }
        let markers_mm = lay
            .markers
            .iter()
            .map(|&cols| Ok(table.numbers(row, cols)?.map(|v| spec.units.length_mm(v))))
            .collect::<Result<Vec<_>, TableError>>()?;
        let xyz_mm = markers_mm.get(spec.marker).copied();
        let t_s = lay.t.map(|c| table.number(row, c)).transpose()?;
        poses.push(Pose {
            line: row.line,
            q,
            xyz_mm,
            markers_mm,
            t_s,
            id: lay.id.map(|c| row.fields[c].clone()),
            extra: lay.extra.iter().map(|&c| row.fields[c].clone()).collect(),
        });
    }
    Ok(PoseFile {
        extra_columns: lay.extra.iter().map(|&c| table.header[c].clone()).collect(),
        source: table.file,
        header: table.header,
        poses,
    })
}
