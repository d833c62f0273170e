//! `rigctl urdf2model --urdf FILE --tip LINK [--base-link LINK] [--tool-mm X,Y,Z]
//! [--limit-margin-pct P] --out MODEL.toml`: writes the serial chain base link .. tip link of a URDF as a model file
//! (structure and parameter names: `rigctl::urdf::import`), for any command's `--model`. The
//! model carries the URDF's link masses (gravity torques: `compliance`) and joint names (pose
//! files may name their joint columns by them).
//!
//! With several `--tip`s, a tree model file (docs/model-files.md "Tree models"): the chains to
//! every tip joined at their shared joints (`rigctl::urdf::import_tree`). `--tree TREE.toml
//! --tip NAME` (instead of `--urdf`) writes one tip's chain of a tree model file as a chain
//! model file.

use std::path::{Path, PathBuf};

use rigctl::model::Tree;
use rigctl::urdf::{
    import_chain_with_masses, import_tree, widen_limits, ImportOptions, TipLink, Urdf,
};

use super::out::errln;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The URDF file.
    #[arg(long, value_name = "FILE.urdf", required_unless_present = "tree")]
    pub urdf: Option<PathBuf>,
    /// A tree model file (instead of --urdf): write the chain of its tip --tip.
    #[arg(long, value_name = "TREE.toml", conflicts_with_all = ["urdf", "base_link", "tool_mm"])]
    pub tree: Option<PathBuf>,
    /// Last link of the chain; the tool point is expressed in its frame. Repeated: a tree
    /// model with one tip per link (shared joints once).
    #[arg(long, value_name = "LINK", required = true)]
    pub tip: Vec<String>,
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
        .input("--urdf", args.urdf.as_deref())
        .input("--tree", args.tree.as_deref())
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
    if !(args.limit_margin_pct.is_finite() && args.limit_margin_pct >= 0.0) {
        return Err(CliError::bad_input(format!(
            "--limit-margin-pct {}: expected a percentage >= 0",
            args.limit_margin_pct
        )));
    }
    if let Some(tree) = &args.tree {
        return tree_tip(&args, tree);
    }
    let Some(urdf_path) = &args.urdf else {
        return Err(CliError::bad_input("give --urdf FILE or --tree FILE"));
    };
    let urdf = Urdf::from_file(urdf_path)?;
    if args.tip.len() > 1 {
        return write_tree(&args, &urdf, urdf_path, tool_mm);
    }
    let mut imported = import_chain_with_masses(
        &urdf,
        &ImportOptions {
            base_link: args.base_link.as_deref(),
            tip_link: &args.tip[0],
            tool_mm,
        },
    )?;
    widen_limits(&mut imported.model, args.limit_margin_pct / 100.0);
    imported.model.write_file(&args.out)?;
    let kg: f64 = imported.model.masses().iter().map(|m| m.mass_kg).sum();
    errln!(
        "{}: {} joints ({}), {kg:.3} kg of link masses on them -> {}",
        urdf_path.display(),
        imported.joint_names.len(),
        imported.joint_names.join(", "),
        args.out.display()
    );
    Ok(())
}

/// Several tips: the tree model file.
fn write_tree(
    args: &Args,
    urdf: &Urdf,
    urdf_path: &Path,
    tool_mm: [f64; 3],
) -> Result<(), CliError> {
    let tips: Vec<TipLink> = args
        .tip
        .iter()
        .map(|link| TipLink { link, tool_mm })
        .collect();
    let mut tree = import_tree(urdf, args.base_link.as_deref(), &tips)?;
    let fraction = args.limit_margin_pct / 100.0;
    if fraction > 0.0 {
        for j in &mut tree.joints {
            let margin = fraction * (j.limits[1] - j.limits[0]).abs();
            j.limits = [j.limits[0] - margin, j.limits[1] + margin];
        }
    }
    tree.write_file(&args.out)?;
    let kg: f64 = tree
        .joints
        .iter()
        .flat_map(|j| &j.masses)
        .map(|m| m.mass_kg)
        .sum();
    let shared = (0..tree.n_joints())
        .filter(|&j| (0..tree.tips.len()).all(|t| tree.path(t).contains(&j)))
        .map(|j| tree.joints[j].name.as_str())
        .collect::<Vec<_>>();
    errln!(
        "{}: a tree of {} joints and {} tips ({}), shared by every tip: {}; {kg:.3} kg of link \
         masses on them -> {}",
        urdf_path.display(),
        tree.n_joints(),
        tree.tips.len(),
        args.tip.join(", "),
        if shared.is_empty() {
            "none".to_string()
        } else {
            shared.join(", ")
        },
        args.out.display()
    );
    Ok(())
}

/// `--tree FILE --tip NAME`: one tip's chain of a tree model file.
fn tree_tip(args: &Args, path: &Path) -> Result<(), CliError> {
    let [tip] = args.tip.as_slice() else {
        return Err(CliError::bad_input(
            "--tree writes one tip's chain: give one --tip",
        ));
    };
    let tree = Tree::from_file(path)?;
    let mut model = tree.chain(tree.tip_index(tip)?)?;
    widen_limits(&mut model, args.limit_margin_pct / 100.0);
    model.write_file(&args.out)?;
    errln!(
        "{}: tip {tip}: {} joints ({}) -> {}",
        path.display(),
        model.n_joints(),
        model.joint_names().join(", "),
        args.out.display()
    );
    Ok(())
}
