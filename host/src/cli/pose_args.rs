//! The pose-file arguments shared by the commands that read pose files: `--units LENGTH,ANGLE`
//! (README "Pose files: extensions"; lengths mm|m, angles deg|rad, converted on reading).

use rigctl::calib::MeasuredSet;
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
}

fn parse_units(s: &str) -> Result<Units, String> {
    s.parse()
}

impl PoseArgs {
    /// What a pose file must hold for `model`, in these units (point `marker`, 0-based, as the
    /// pose's `xyz_mm`).
    pub fn spec(&self, model: &Model, require_xyz: bool, marker: usize) -> PoseSpec {
        PoseSpec {
            units: self.units,
            marker,
            ..PoseSpec::for_model(model, require_xyz)
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
