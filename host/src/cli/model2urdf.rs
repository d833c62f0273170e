//! `rigctl model2urdf --model M.toml [--urdf ORIGINAL.urdf [--base-link LINK]] --out M.urdf`:
//! the model as a URDF chain from link `world` (frame R) to link `tool0` (the tool point),
//! calibrated geometry and joint offsets in the joint origins (m, rad); with `--urdf`, the
//! original is kept whole and only the chain's joint origins change
//! (`rigctl::urdf::export`). What a URDF cannot hold is named on stderr; the joint origins
//! before and after are printed on stdout.
//!
//! A tree model file (`[[tip]]` tables) becomes a new URDF with every joint once and a link per
//! tip at its tool point (`rigctl::urdf::export_tree`); `--urdf` is for chains.

use std::path::PathBuf;

use rigctl::io::atomic::write_text_atomic;
use rigctl::io::finite::TextFormat;
use rigctl::model::tree_file::is_tree_text;
use rigctl::model::{ModelError, Tree};
use rigctl::urdf::{model_into_urdf, model_to_urdf, tree_to_urdf, Origin, UrdfError};

use super::model_args::ModelArgs;
use super::out::{errln, outln};
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// The URDF the model was imported from (`urdf2model`): kept whole, only the origins of the
    /// chain's joints (found by name) change.
    #[arg(long, value_name = "ORIGINAL.urdf")]
    pub urdf: Option<PathBuf>,
    /// With --urdf: the chain's first link, as given to `urdf2model --base-link` (default: the
    /// root link).
    #[arg(long, value_name = "LINK", requires = "urdf")]
    pub base_link: Option<String>,
    /// Output URDF.
    #[arg(long, value_name = "M.urdf")]
    pub out: PathBuf,
}

fn show(o: &Origin) -> String {
    let [x, y, z] = o.xyz_m;
    let [r, p, w] = o.rpy_rad;
    format!("xyz {x:+.9} {y:+.9} {z:+.9} m, rpy {r:+.12} {p:+.12} {w:+.12} rad")
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--model", args.model.model.as_deref())
        .input("--urdf", args.urdf.as_deref())
        .output("--out", Some(&args.out))
        .check()?;
    let tree = match &args.model.model {
        Some(path) => {
            let text = rigctl::io::read::read_text_capped(path, rigctl::io::read::CAP_SMALL_TEXT)
                .map_err(|source| ModelError::Read {
                path: path.clone(),
                source,
            })?;
            if is_tree_text(&text) {
                Some(Tree::from_toml_str(&text, &path.display().to_string())?)
            } else {
                None
            }
        }
        None => None,
    };
    let exported = match tree {
        Some(tree) => {
            if args.urdf.is_some() || args.model.tool_mm.is_some() || !args.model.sets.is_empty() {
                return Err(CliError::bad_input(
                    "a tree model is written as a new URDF: --urdf, --tool-mm and --set are for \
                     chains",
                ));
            }
            tree_to_urdf(&tree)?
        }
        None => chain_urdf(&args)?,
    };
    finish(&args, &exported)
}

fn chain_urdf(args: &Args) -> Result<rigctl::urdf::Exported, CliError> {
    let model = args.model.choose()?;
    Ok(match &args.urdf {
        None => model_to_urdf(&model),
        Some(path) => {
            let text = rigctl::io::read::read_text_capped(path, rigctl::io::read::CAP_URDF)
                .map_err(|source| UrdfError::Read {
                    path: path.clone(),
                    source,
                })?;
            model_into_urdf(
                &model,
                &text,
                &path.display().to_string(),
                args.base_link.as_deref(),
            )?
        }
    })
}

fn finish(args: &Args, exported: &rigctl::urdf::Exported) -> Result<(), CliError> {
    write_text_atomic(&args.out, TextFormat::Xml, &exported.text)?;
    for line in &exported.not_representable {
        errln!("rigctl model2urdf: not in the URDF: {line}");
    }
    for c in &exported.origins {
        outln!("{}", c.joint)?;
        match &c.before {
            Some(b) => outln!("  before {}", show(b))?,
            None => outln!("  before (none: added)")?,
        }
        outln!("  after  {}", show(&c.after))?;
    }
    outln!(
        "{} joint origins written -> {}",
        exported.origins.len(),
        args.out.display()
    )?;
    Ok(())
}
