//! `rigctl plan --model TREE.toml --n N --out PLAN.csv [--json PLAN.json] [--seed S]
//! [--noise-mm 0.01] [--candidates 2000] [--criterion a|g|i|d] [--base] [--table-z-mm Z |
//! --no-table] [--keep-out ..] [--limit-margin-deg 2] [--min-z-mm Z] [--box ..]
//! [--branch-clearance-mm 100] [--urdf FILE [--srdf FILE] [--package-path DIR] [--clearance-mm
//! C]]`: the poses of a tree model (`rigctl::plan::tree`), with the links of the whole tree
//! checked when its URDF is given. The chain-only options (the ordered trajectory,
//! `--from-diagnose`, sheets, poses already measured, the plot, the refinement, `--tip-link`)
//! are refused.

use rigctl::io::atomic::{write_bytes_atomic, write_text_atomic};
use rigctl::io::finite::TextFormat;
use rigctl::model::Tree;
use rigctl::plan::tree::{plan_tree, TreePlanConfig};
use rigctl::plan::tree_output::{tree_plan_csv, tree_plan_json, tree_summary};

use super::out::out;
use super::plan::Args;
use super::CliError;

/// Plans the poses of `tree` with `args`.
pub fn run(args: &Args, tree: Tree) -> Result<(), CliError> {
    refuse_chain_only(args)?;
    let mut cfg = TreePlanConfig::new(args.n);
    args.safety.workspace(&mut cfg.workspace)?;
    super::plan::tool_constraints(args, &mut cfg.workspace)?;
    cfg.seed = args.seed;
    cfg.noise_mm = args.noise_mm;
    if let Some(c) = args.candidates {
        cfg.candidates = c;
    }
    cfg.random_draws = args.random_draws;
    cfg.criterion = args.criterion;
    cfg.base = args.base;
    cfg.branch_clearance_mm = args.branch_clearance_mm;
    let (collider, collision_lines) = args.safety.tree_collider(&tree, cfg.workspace.table_z_mm)?;
    cfg.collider = collider;
    let spinner = super::diagnose::spinner(format!(
        "plan: planning {} poses of the tree {} on {} candidates",
        cfg.n, tree.name, cfg.candidates
    ));
    let plan = plan_tree(&tree, &cfg);
    spinner.finish_and_clear();
    let plan = plan?;
    if let Some(path) = &args.json {
        let doc = tree_plan_json(&plan, cfg.noise_mm, cfg.seed);
        let text = serde_json::to_string_pretty(&doc)
            .map_err(|e| CliError::failure(format!("JSON: {e}")))?;
        write_bytes_atomic(path, format!("{text}\n").as_bytes())?;
    }
    write_text_atomic(&args.out, TextFormat::Csv, &tree_plan_csv(&plan))?;
    out!("{}", tree_summary(&plan, cfg.noise_mm))?;
    let ws = &cfg.workspace;
    out!(
        "safety: joints >= {} deg inside their limits; table plane {}; every tip z >= {}; {} keep-out box(es); points of two branches (frame origins beyond the shared joints, tips) >= {} mm apart\n",
        ws.limit_margin_deg,
        ws.table_z_mm.map_or("none".to_string(), |z| format!("z = {z} mm (R)")),
        ws.tool_min_z_mm().map_or("any".to_string(), |z| format!("{z} mm")),
        ws.keep_out_mm.len(),
        cfg.branch_clearance_mm
    )?;
    for l in &collision_lines {
        out!("{l}\n")?;
    }
    if plan.collisions_verified {
        out!(
            "WARNING: NO CHECK OF THE MOVES between poses on a tree (plan.json order.moves_verified = false): every pose's links are checked, the way between two poses is not; drive the poses with a motion planner\n"
        )?;
    } else {
        out!(
            "WARNING: NO COLLISION CHECK OF THE LINKS AND NO CHECK OF THE MOVES between poses on a tree (plan.json collisions_verified = false, order.moves_verified = false): only the joint frames' origins and the tips are kept above the table, out of the keep-out boxes and the branches apart; give --urdf FILE [--srdf FILE] to check the links; drive the poses with a motion planner\n"
        )?;
    }
    Ok(())
}

/// The options a tree plan does not take, named.
fn refuse_chain_only(args: &Args) -> Result<(), CliError> {
    let s = &args.safety;
    let given: Vec<&str> = [
        ("--trajectory", s.trajectory.is_some()),
        ("--from-diagnose", args.from_diagnose.is_some()),
        ("--sheets", args.sheets),
        ("--poses", args.poses.is_some()),
        ("--candidates-from", args.candidates_from.is_some()),
        ("--visible-from", args.visible_from.is_some()),
        ("--plot", args.plot.is_some()),
        ("--refine-sweeps", args.refine_sweeps.is_some()),
        ("--no-structured", args.no_structured),
        ("--restarts", args.restarts != 1),
    ]
    .into_iter()
    .filter_map(|(flag, on)| on.then_some(flag))
    .collect();
    if given.is_empty() {
        Ok(())
    } else {
        Err(CliError::bad_input(format!(
            "{}: not taken by plan on a tree model (one chain only); a tree plan takes --n, --out, --json, --seed, --noise-mm, --candidates, --random-draws, --criterion, --base, --table-z-mm / --no-table, --keep-out, --limit-margin-deg, --min-z-mm, --box, --branch-clearance-mm, --urdf, --srdf, --package-path, --clearance-mm",
            given.join(", ")
        )))
    }
}
