//! `rigctl urdf2model --urdf FILE --tip LINK [--base-link LINK] [--tool-mm X,Y,Z]
//! --out MODEL.toml`: writes the serial chain base link .. tip link of a URDF as a model file
//! (structure and parameter names: `rigctl::urdf::import`), for any command's `--model`.

use std::path::PathBuf;

use rigctl::urdf::{import_chain, ImportOptions, Urdf};

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
    /// Output model file (TOML).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: PathBuf,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::check_outputs([Some(args.out.as_path())])?;
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
    let imported = import_chain(
        &urdf,
        &ImportOptions {
            base_link: args.base_link.as_deref(),
            tip_link: &args.tip,
            tool_mm,
        },
    )?;
    imported.model.write_file(&args.out)?;
    errln!(
        "{}: {} joints ({}) -> {}",
        args.urdf.display(),
        imported.joint_names.len(),
        imported.joint_names.join(", "),
        args.out.display()
    );
    Ok(())
}
