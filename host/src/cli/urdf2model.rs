//! `rigctl urdf2model --urdf FILE --tip LINK [--base-link LINK] [--tool-mm X,Y,Z]
//! [--limit-margin-pct P] --out MODEL.toml`: writes the serial chain base link .. tip link of a URDF as a model file
//! (structure and parameter names: `rigctl::urdf::import`), for any command's `--model`. The
//! model carries the URDF's link masses (gravity torques: `compliance`) and joint names (pose
//! files may name their joint columns by them).

use std::path::PathBuf;

use rigctl::urdf::{import_chain_with_masses, widen_limits, ImportOptions, Urdf};

use super::out::errln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The URDF file.
    #[arg(long, value_name = "FILE.urdf")]
    pub urdf: PathBuf,
    /// Last link of the chain; the tool point is expressed in its frame.
    #[arg(long, value_name = "LINK")]
    pub tip: String,
    /// First link of the chain (default: the URDF's root link).
    #[arg(long, value_name = "LINK")]
    pub base_link: Option<String>,
    /// Tool point in the tip link's frame, mm (default 0,0,0).
    #[arg(long, value_name = "X,Y,Z", value_delimiter = ',')]
    pub tool_mm: Option<Vec<f64>>,
    /// Widen every joint's limits by PCT percent of its range at both ends (real readings may
    /// pass the URDF limits slightly; pose files outside the limits are refused).
    #[arg(long, value_name = "PCT", default_value_t = 0.0)]
    pub limit_margin_pct: f64,
    /// Output model file (TOML).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: PathBuf,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--urdf", Some(&args.urdf))
        .output("--out", Some(&args.out))
        .check()?;
    let tool_mm = match args.tool_mm.as_deref() {
        None => [0.0; 3],
        Some(&[x, y, z]) if [x, y, z].iter().all(|v| v.is_finite()) => [x, y, z],
        Some(other) => {
            return Err(CliError::bad_input(format!(
                "--tool-mm {other:?}: expected three finite numbers X,Y,Z (mm)"
            )))
        }
    };
    let urdf = Urdf::from_file(&args.urdf)?;
    if !(args.limit_margin_pct.is_finite() && args.limit_margin_pct >= 0.0) {
        return Err(CliError::bad_input(format!(
            "--limit-margin-pct {}: expected a percentage >= 0",
            args.limit_margin_pct
        )));
    }
    let mut imported = import_chain_with_masses(
        &urdf,
        &ImportOptions {
            base_link: args.base_link.as_deref(),
            tip_link: &args.tip,
            tool_mm,
        },
    )?;
    widen_limits(&mut imported.model, args.limit_margin_pct / 100.0);
    imported.model.write_file(&args.out)?;
    let kg: f64 = imported.model.masses().iter().map(|m| m.mass_kg).sum();
    errln!(
        "{}: {} joints ({}), {kg:.3} kg of link masses on them -> {}",
        args.urdf.display(),
        imported.joint_names.len(),
        imported.joint_names.join(", "),
        args.out.display()
    );
    Ok(())
}
