//! The pose-file arguments shared by the commands that read pose files: `--units LENGTH,ANGLE`
//! (README "Pose files: extensions"; lengths mm|m, angles deg|rad, converted on reading).

use rigctl::calib::MeasuredSet;
use rigctl::io::dialect::Dialect;
use rigctl::io::pose_csv::PoseSpec;
use rigctl::io::units::Units;
use rigctl::model::Model;

/// Units of the pose files a command reads.
#[derive(clap::Args, Debug, Clone)]
pub struct PoseArgs {
    /// Units of the pose files' measured points, joint readings (lengths for prismatic joints)
    /// and nothing else: LENGTH,ANGLE with LENGTH mm|m and ANGLE deg|rad.
    #[arg(long, value_name = "LENGTH,ANGLE", default_value = "mm,deg", value_parser = parse_units)]
    pub units: Units,
    /// Field separator of the CSV files read: `,` (default), `;` (a spreadsheet in a German or
    /// French locale) or `\t`.
    #[arg(long, value_name = "CHAR", default_value = ",", value_parser = parse_sep)]
    pub sep: char,
    /// Decimal mark of the CSV files read: `.` (default) or `,` (with --sep ';').
    #[arg(long, value_name = "CHAR", default_value = ".", value_parser = parse_decimal)]
    pub decimal: char,
}

fn parse_units(s: &str) -> Result<Units, String> {
    s.parse()
}

fn parse_sep(s: &str) -> Result<char, String> {
    Dialect::new(s, ".").map(|d| d.sep).map_err(|e| e.0)
}

fn parse_decimal(s: &str) -> Result<char, String> {
    Dialect::new(";", s).map(|d| d.decimal).map_err(|e| e.0)
}

impl PoseArgs {
    /// What a pose file must hold for `model`, in these units (point `marker`, 0-based, as the
    /// pose's `xyz_mm`).
    pub fn spec(&self, model: &Model, require_xyz: bool, marker: usize) -> PoseSpec {
        PoseSpec {
            units: self.units,
            marker,
            dialect: self.dialect(),
            ..PoseSpec::for_model(model, require_xyz)
        }
    }

    /// The separator and decimal mark given (a pair that cannot be used, both `,`, is
    /// refused when a file is read).
    pub fn dialect(&self) -> Dialect {
        Dialect {
            sep: self.sep,
            decimal: self.decimal,
        }
    }
}

/// Refuses the pose file `path` (read into `set`) when its points cannot be of `model` as given
/// (units, joint order, another robot: [`rigctl::calib::plausible`]), naming the file.
pub fn check_plausible(
    model: &Model,
    set: &MeasuredSet,
    path: &std::path::Path,
) -> Result<(), rigctl::calib::CalibError> {
    rigctl::calib::plausible::check_set(model, set, &path.display().to_string()).map(|_| ())
}

/// Refuses held-out poses that repeat calibration poses exactly (a renamed copy of the
/// calibration file): the held-out numbers would be the calibration numbers.
pub fn check_apart(
    cal: &MeasuredSet,
    val: &MeasuredSet,
    cal_path: &std::path::Path,
    val_path: &std::path::Path,
) -> Result<(), super::CliError> {
    let repeats = cal.repeats(val);
    let Some(&(k, h)) = repeats.first() else {
        return Ok(());
    };
    let line = |set: &MeasuredSet, i: usize| {
        set.lines
            .as_ref()
            .and_then(|l| l.get(i))
            .map_or_else(|| format!("pose {}", i + 1), |l| format!("line {l}"))
    };
    Err(super::CliError::bad_input(format!(
        "{}: {} of {} held-out poses repeat calibration poses exactly ({} = {} {}): the held-out \
         numbers would be the calibration numbers; give poses measured apart from the calibration",
        val_path.display(),
        repeats.len(),
        val.len(),
        line(val, k),
        cal_path.display(),
        line(cal, h)
    )))
}
