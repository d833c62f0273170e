//! Instrument logs: the measured point(s) over time, from a generic CSV (`t,x,y,z` or
//! `t,x1,y1,z1,x2,...`), a Vicon Nexus CSV export (its `Trajectories` section), an OptiTrack
//! Motive CSV export (rigid-body or marker positions) or a SpatialAnalyzer ASCII point export
//! with time stamps (a laser tracker's points as logged by SA). Lengths end in mm; an empty
//! or `NaN` cell (a marker not seen, a broken beam) is a missing point, counted, not an error.

mod motive;
mod tracker;
mod vicon;

use std::path::Path;

use super::error::CaptureError;
use crate::io::dialect::Dialect;

/// Which export an instrument log is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Recognised from the first line: `Trajectories` (Vicon), `Format Version` (Motive), `//`
    /// (SpatialAnalyzer), else the generic CSV.
    Auto,
    /// `t,x,y,z[,...]` or `t,x1,y1,z1,x2,y2,z2,...` (s, length unit of --units).
    Generic,
    /// Vicon Nexus CSV export, `Trajectories` section.
    Vicon,
    /// OptiTrack Motive CSV export.
    Motive,
    /// SpatialAnalyzer ASCII point export with time stamps (laser tracker).
    Sa,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Generic => "generic CSV",
            Self::Vicon => "Vicon Nexus CSV",
            Self::Motive => "OptiTrack Motive CSV",
            Self::Sa => "SpatialAnalyzer ASCII points",
        }
    }
}

/// How to read an instrument log.
#[derive(Debug, Clone)]
pub struct ReadOptions {
    pub format: Format,
    /// Separator and decimal mark (generic and SA files; Vicon and Motive files are
    /// recognised in either form unless given).
    pub dialect: Dialect,
    /// Whether `dialect` was given (else the Vicon/Motive readers detect it).
    pub dialect_given: bool,
    /// mm per length unit of a file that does not name its unit (generic, SA).
    pub mm_per_unit: f64,
    /// Markers / rigid bodies to take by name (empty: the reader's default).
    pub markers: Vec<String>,
}

/// A parsed instrument log.
#[derive(Debug, Clone, PartialEq)]
pub struct InstrumentLog {
    pub source: String,
    pub format: Format,
    pub marker_names: Vec<String>,
    /// Sample times (s, the instrument's clock), strictly increasing.
    pub t_s: Vec<f64>,
    /// `points[sample][marker]` (mm), `None` where missing.
    pub points: Vec<Vec<Option<[f64; 3]>>>,
    /// Marker samples missing (empty or NaN cells).
    pub missing: usize,
}

impl InstrumentLog {
    /// Median time between samples (s).
    pub fn median_period_s(&self) -> f64 {
        let mut d: Vec<f64> = self.t_s.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return 0.0;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }
}

/// Largest magnitude of a coordinate (in any unit, before scaling) or a time: 1e9 (a
/// kilometre in um, 30 years in s); beyond it a value is out of physical range.
pub const MAX_ABS_VALUE: f64 = 1e9;

/// One cell: empty or NaN = missing, else a finite number within [`MAX_ABS_VALUE`] (`Err`
/// otherwise).
pub(crate) fn cell(s: &str) -> Result<Option<f64>, String> {
    let s = s.trim();
    if s.is_empty() || s.eq_ignore_ascii_case("nan") {
        return Ok(None);
    }
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v.abs() > MAX_ABS_VALUE => {
            Err(format!("`{s}` is out of physical range"))
        }
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(_) => Err(format!("`{s}` is infinite")),
        Err(_) => Err(format!("`{s}` is not a number")),
    }
}

/// A point from three cells (any missing: `None`), scaled to mm.
pub(crate) fn point(cells: [&str; 3], mm: f64) -> Result<Option<[f64; 3]>, String> {
    let [x, y, z] = [cell(cells[0])?, cell(cells[1])?, cell(cells[2])?];
    Ok(match (x, y, z) {
        (Some(x), Some(y), Some(z)) => Some([x * mm, y * mm, z * mm]),
        _ => None,
    })
}

/// One parsed sample: its line, its time (s) and its points (mm, `None` where missing).
pub(crate) type SampleRow = (usize, f64, Vec<Option<[f64; 3]>>);

/// Builds the log from rows `(line, t, points)`, checking that times increase.
pub(crate) fn assemble(
    source: &str,
    format: Format,
    marker_names: Vec<String>,
    rows: Vec<SampleRow>,
) -> Result<InstrumentLog, CaptureError> {
    let mut log = InstrumentLog {
        source: source.into(),
        format,
        marker_names,
        t_s: Vec::with_capacity(rows.len()),
        points: Vec::with_capacity(rows.len()),
        missing: 0,
    };
    for (line, t, pts) in rows {
        if log.t_s.last().is_some_and(|&prev| t <= prev) {
            return Err(at_line(source)(
                line,
                format!("time {t} s does not increase"),
            ));
        }
        log.missing += pts.iter().filter(|p| p.is_none()).count();
        log.t_s.push(t);
        log.points.push(pts);
    }
    if log.t_s.len() < 3 {
        return Err(at_line(source)(
            1,
            format!("{} samples: an instrument log needs many", log.t_s.len()),
        ));
    }
    Ok(log)
}

/// The error of an instrument log `file` at a line: `at_line(file)(line, problem)`.
pub(crate) fn at_line(file: &str) -> impl Fn(usize, String) -> CaptureError + '_ {
    move |line, problem| CaptureError::Instrument {
        file: file.into(),
        line,
        problem,
    }
}

/// The lines of `text`, numbered from 1.
pub(crate) fn numbered_lines(text: &str) -> Vec<(usize, &str)> {
    text.lines().enumerate().map(|(i, l)| (i + 1, l)).collect()
}

/// The format of `text` from its first non-empty line.
fn detect(text: &str) -> Format {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty())
        .unwrap_or("");
    let head = first.split([',', ';', '\t']).next().unwrap_or("").trim();
    match head {
        "Trajectories" | "Devices" | "Joints" | "Model Outputs" | "Segments" => Format::Vicon,
        "Format Version" => Format::Motive,
        _ if first.starts_with("//") => Format::Sa,
        _ => Format::Generic,
    }
}

/// Reads an instrument log.
pub fn read_instrument(path: &Path, opts: &ReadOptions) -> Result<InstrumentLog, CaptureError> {
    let file = path.display().to_string();
    let text =
        crate::io::read::read_text_capped(path, crate::io::read::CAP_TABLE).map_err(|source| {
            CaptureError::Read {
                file: file.clone(),
                source,
            }
        })?;
    parse_instrument(&text, &file, opts)
}

/// Parses instrument-log text; `file` names it in messages.
pub fn parse_instrument(
    text: &str,
    file: &str,
    opts: &ReadOptions,
) -> Result<InstrumentLog, CaptureError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let format = match opts.format {
        Format::Auto => detect(text),
        f => f,
    };
    match format {
        Format::Vicon => vicon::parse(text, file, opts),
        Format::Motive => motive::parse(text, file, opts),
        Format::Sa => tracker::parse(text, file, opts),
        Format::Auto | Format::Generic => generic(text, file, opts),
    }
}

/// The separator and decimal mark of a structured export: the given ones, else `;` when the
/// line `probe` has `;` and no `,`, with decimal commas when a data line has them.
pub(crate) fn detect_dialect(opts: &ReadOptions, probe: &str, data: Option<&str>) -> Dialect {
    if opts.dialect_given {
        return opts.dialect;
    }
    let sep = if probe.contains(';') && !probe.contains(',') {
        ';'
    } else if probe.contains('\t') && !probe.contains(',') {
        '\t'
    } else {
        ','
    };
    let decimal = if sep != ','
        && data.is_some_and(|d| d.split(sep).any(crate::io::dialect::decimal_comma))
    {
        ','
    } else {
        '.'
    };
    Dialect { sep, decimal }
}

/// The generic CSV: `t` and `x,y,z` or `x1,y1,z1 .. xk,yk,zk`.
fn generic(text: &str, file: &str, opts: &ReadOptions) -> Result<InstrumentLog, CaptureError> {
    let table = crate::io::table::Table::parse_dialect(text, file, opts.dialect)?;
    let t_col = table.need("t")?;
    let plain = ["x", "y", "z"].map(|a| table.find(a));
    let (cols, names): (Vec<[usize; 3]>, Vec<String>) = match plain {
        [Some(x), Some(y), Some(z)] => (vec![[x, y, z]], vec!["x,y,z".into()]),
        _ => {
            let mut cols = Vec::new();
            let mut names = Vec::new();
            for k in 1.. {
                let Some(x) = table.find(&format!("x{k}")) else {
                    break;
                };
                cols.push([
                    x,
                    table.need(&format!("y{k}"))?,
                    table.need(&format!("z{k}"))?,
                ]);
                names.push(format!("x{k},y{k},z{k}"));
            }
            if cols.is_empty() {
                return Err(crate::io::table::TableError::MissingColumn {
                    file: file.into(),
                    line: table.header_line,
                    column: "x".into(),
                }
                .into());
            }
            (cols, names)
        }
    };
    let mut rows = Vec::with_capacity(table.rows.len());
    for row in &table.rows {
        let bad = |col: usize, problem: String| table.bad(row, col, problem);
        let t = match cell(&row.fields[t_col]) {
            Ok(Some(t)) => t,
            Ok(None) => return Err(bad(t_col, "missing time".into()).into()),
            Err(p) => return Err(bad(t_col, p).into()),
        };
        let mut pts = Vec::with_capacity(cols.len());
        for c in &cols {
            let mut v = [None; 3];
            for (slot, &i) in v.iter_mut().zip(c) {
                *slot = cell(&row.fields[i]).map_err(|p| bad(i, p))?;
            }
            pts.push(match v {
                [Some(x), Some(y), Some(z)] => Some([x, y, z].map(|u| u * opts.mm_per_unit)),
                _ => None,
            });
        }
        rows.push((row.line, t, pts));
    }
    assemble(file, Format::Generic, names, rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(super) fn opts() -> ReadOptions {
        ReadOptions {
            format: Format::Auto,
            dialect: Dialect::default(),
            dialect_given: false,
            mm_per_unit: 1.0,
            markers: Vec::new(),
        }
    }

    #[test]
    fn generic_logs_with_missing_cells() {
        let log = parse_instrument(
            "# tracker\nt,x1,y1,z1,x2,y2,z2\n0,1,2,3,4,5,6\n0.01,1,2,3,,,\n0.02,NaN,2,3,4,5,6\n",
            "g.csv",
            &opts(),
        )
        .unwrap();
        assert_eq!(log.format, Format::Generic);
        assert_eq!(log.marker_names.len(), 2);
        assert_eq!(log.missing, 2);
        assert_eq!(log.points[0][1], Some([4.0, 5.0, 6.0]));
        let e = parse_instrument("t,x,y,z\n0,1,2,3\n0,1,2,3\n1,1,2,3\n", "g.csv", &opts())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("g.csv:3") && e.contains("does not increase"),
            "{e}"
        );
        let e = parse_instrument("t,x,y,z\n0,1,2,1e300\n1,1,2,3\n2,1,2,3\n", "g.csv", &opts())
            .unwrap_err()
            .to_string();
        assert!(e.contains("out of physical range"), "{e}");
        let e = parse_instrument("t,x,y,z\n0,1,2,abc\n", "g.csv", &opts())
            .unwrap_err()
            .to_string();
        assert!(e.contains("column `z`") && e.contains("abc"), "{e}");
    }
}
