//! `rigctl plan --robot NAME | --model FILE --n N --out PLAN.csv [--seed S] [--json PLAN.json]
//! [--plot PLAN.svg] [--noise-mm 0.01] [--candidates 5000] [--box X0,Y0,Z0,X1,Y1,Z1]
//! [--visible-from X,Y,Z [--cone-deg 60]] [--min-z-mm Z] [--poses CAL.csv] [--candidates-from POSES.csv] [--base]
//! [--from-diagnose D.json] [--criterion a|g|i|d] [--restarts 1] [--refine-sweeps 3|0] [--no-structured]
//! [--sheets [--sheet-rows fused|trace|plane]]`: chooses the N calibration poses that identify the model best
//! (`rigctl::plan`) and prints their expected parameter sigmas against random poses.

use std::path::PathBuf;

use nalgebra::Vector3;
use rigctl::io::atomic::{write_bytes_atomic, write_text_atomic};
use rigctl::io::finite::TextFormat;
use rigctl::io::pose_csv::read_poses;
use rigctl::plan::output::{plan_csv, plan_json, summary_table};
use rigctl::plan::sheets::{candidate_specs, rank_sheets, SheetRows};
use rigctl::plan::sheets_output::{sheets_json, sheets_table};
use rigctl::plan::{plan, Criterion, FromDiagnose, PlanConfig, Workspace};
use rigctl::plot::plan::poses_svg;

use super::model_args::ModelArgs;
use super::out::out;
use super::plan_safety::SafetyArgs;
use super::pose_args::PoseArgs;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub model: ModelArgs,
    // table, keep-out boxes, limit margin, collision geometry, segments, trajectory
    #[command(flatten)]
    pub safety: SafetyArgs,
    // --units LENGTH,ANGLE of --poses.
    #[command(flatten)]
    pub pose: PoseArgs,
    /// Number of poses to choose.
    #[arg(long, value_name = "N")]
    pub n: usize,
    /// The plan (CSV q1..qN,nom_x,nom_y,nom_z: joints in deg, nominal tool point in mm).
    #[arg(long, value_name = "PLAN.csv")]
    pub out: PathBuf,
    /// Seed of the candidate set and of the random baseline.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the plan's expected sigmas, condition number and baseline (JSON).
    #[arg(long, value_name = "PLAN.json")]
    pub json: Option<PathBuf>,
    /// Plot the planned tool points over the candidates (top and side views, .svg or .png).
    #[arg(long, value_name = "PLAN.svg")]
    pub plot: Option<PathBuf>,
    /// Measurement noise per coordinate (mm) for the expected sigmas.
    #[arg(long, value_name = "MM", default_value_t = 0.01)]
    pub noise_mm: f64,
    /// Number of random candidate configurations (default 5000; 2000 on a tree model).
    #[arg(long, value_name = "COUNT")]
    pub candidates: Option<usize>,
    /// Choose among these configurations only (a pose file: q1..qN, measured x,y,z optional;
    /// e.g. the poses the robot reaches safely, or a measured set to subsample): no random or
    /// structured candidates, no refinement.
    #[arg(long, value_name = "POSES.csv", conflicts_with_all = ["candidates", "no_structured", "refine_sweeps"])]
    pub candidates_from: Option<PathBuf>,
    /// Plan for the base frame too (base_x, base_y, base_z, base_rx, base_ry), as `calibrate
    /// --base` identifies it.
    #[arg(long)]
    pub base: bool,
    /// Optimality criterion: a (sum of the squared sigmas relative to random designs, the
    /// default), g (geometric mean of the sigmas), i (mean prediction variance over the
    /// candidates) or d (determinant); with --from-diagnose restricted to the effects to separate.
    #[arg(
        long,
        value_name = "a|g|i|d",
        value_enum,
        ignore_case = true,
        default_value = "a"
    )]
    pub criterion: Criterion,
    /// Exchange runs from random starts besides the greedy one (more: slower, slightly better).
    #[arg(long, value_name = "COUNT", default_value_t = 1)]
    pub restarts: usize,
    /// Sweeps of the continuous refinement of the chosen poses' joint values (0: keep the
    /// candidates as chosen); default 3 (with --from-diagnose, moves that fail the linearity
    /// test of the effects to separate are not taken).
    #[arg(long, value_name = "COUNT")]
    pub refine_sweeps: Option<usize>,
    /// Leave the structured candidates (joint limits and mid-range combinations) out of the pool
    /// (with --from-diagnose they are kept only where the effects to separate are linear).
    #[arg(long)]
    pub no_structured: bool,
    /// Random designs of N poses drawn for the baseline.
    #[arg(long, value_name = "COUNT", default_value_t = rigctl::plan::DEFAULT_RANDOM_DRAWS)]
    pub random_draws: usize,
    /// Workspace box the tool point must lie in (mm, frame R).
    #[arg(
        long = "box",
        value_name = "X0,Y0,Z0,X1,Y1,Z1",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub box_mm: Option<Vec<f64>>,
    /// A tracker at this point (mm, R) must see the tool: the direction to it lies within
    /// --cone-deg of the tool's z axis.
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub visible_from: Option<Vec<f64>>,
    /// Acceptance half-angle of the tracker target, deg.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 60.0,
        requires = "visible_from"
    )]
    pub cone_deg: f64,
    /// Lowest tool-point height (z in R, mm); default 40 for the Katana, the table plane's
    /// (--table-z-mm) otherwise.
    #[arg(long, value_name = "MM")]
    pub min_z_mm: Option<f64>,
    /// Poses already measured (pose CSV; only the joints are used): the plan adds to them.
    #[arg(long, value_name = "CAL.csv")]
    pub poses: Option<PathBuf>,
    /// Also rank candidate pencil sheets and paths (plane placements and orientations, circle or
    /// line) by what each sheet and each pair identifies, naming the parameters a sheet leaves
    /// blind (table on stdout, `sheets` in --json).
    #[arg(long)]
    pub sheets: bool,
    /// What a sheet sample measures for --sheets: fused (across the path + out of the sheet,
    /// what `rigctl fuse` gives), trace (across the path only) or plane (both in-plane
    /// directions).
    #[arg(
        long,
        value_name = "fused|trace|plane",
        value_enum,
        default_value = "fused",
        requires = "sheets"
    )]
    pub sheet_rows: SheetRows,
    /// A diagnose JSON: choose poses that separate its `aliased` pairs (and pin down its
    /// effects with large sigmas), given --poses.
    #[arg(long, value_name = "D.json")]
    pub from_diagnose: Option<PathBuf>,
    /// On a tree model: the smallest distance between points of two branches (the joint frame
    /// origins beyond the shared joints and the tips), mm.
    #[arg(long, value_name = "MM", default_value_t = rigctl::plan::tree::DEFAULT_BRANCH_CLEARANCE_MM)]
    pub branch_clearance_mm: f64,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--model", args.model.model.as_deref())
        .input("--poses", args.poses.as_deref())
        .input("--candidates-from", args.candidates_from.as_deref())
        .input("--from-diagnose", args.from_diagnose.as_deref())
        .output("--out", Some(&args.out))
        .output("--json", args.json.as_deref())
        .output("--plot", args.plot.as_deref())
        .output("--trajectory", args.safety.trajectory.as_deref())
        .input("--urdf", args.safety.urdf.as_deref())
        .input("--srdf", args.safety.srdf.as_deref())
        .check()?;
    if let Some(tree) = super::calibrate_tree::tree_model(&args.model)? {
        return super::plan_tree::run(&args, tree);
    }
    let model = match args.safety.urdf_model()? {
        Some(m) if args.model.model.is_none() && args.model.robot.is_none() => m,
        _ => args.model.choose()?,
    };
    let mut cfg = PlanConfig::new(&model, args.n);
    let safety_lines = args.safety.apply(&model, &mut cfg)?;
    cfg.seed = args.seed;
    cfg.noise_mm = args.noise_mm;
    if let Some(c) = args.candidates {
        cfg.candidates = c;
    }
    cfg.random_draws = args.random_draws;
    cfg.criterion = args.criterion;
    cfg.restarts = args.restarts;
    cfg.base = args.base;
    cfg.refine_sweeps = args.refine_sweeps;
    if args.no_structured {
        cfg.structured = Some(false);
    }
    tool_constraints(&args, &mut cfg.workspace)?;
    if let Some(p) = &args.candidates_from {
        let file = read_poses(p, &args.pose.spec(&model, false, 0))?;
        cfg.pool_q = Some(file.joints());
    }
    if let Some(p) = &args.poses {
        let file = read_poses(p, &args.pose.spec(&model, false, 0))?;
        cfg.existing_q = file.joints();
    }
    let from = match &args.from_diagnose {
        Some(p) => Some(FromDiagnose::read(p)?),
        None => None,
    };
    let result = plan(&model, &cfg, from.as_ref())?;
    let sheets = if args.sheets {
        let ws = rigctl::plan::Workspace {
            visible_from_mm: None,
            ..cfg.workspace.clone()
        };
        Some(rank_sheets(
            &model,
            &candidate_specs(),
            &ws,
            &result.parameters,
            &result.scale,
            cfg.noise_mm,
            args.sheet_rows,
        )?)
    } else {
        None
    };
    if let Some(path) = &args.plot {
        let planned: Vec<[f64; 3]> = result.poses.iter().map(|p| p.nominal_mm.into()).collect();
        // the candidates are not kept in the plan: the file's configurations, or a light
        // background redrawn with the same seed
        let cands = match &cfg.pool_q {
            Some(pool) => {
                let every = pool.len().div_ceil(1500).max(1);
                let light: Vec<Vec<f64>> = pool.iter().step_by(every).cloned().collect();
                rigctl::plan::candidates::pool_candidates(&model, &light, &cfg.workspace)?.0
            }
            None => {
                let mut rng =
                    <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(cfg.seed);
                rigctl::plan::draw_candidates(
                    &model,
                    1500.min(cfg.candidates),
                    &cfg.workspace,
                    &mut rng,
                )?
            }
        };
        let background: Vec<[f64; 3]> = cands.iter().map(|c| c.nominal_mm.into()).collect();
        let title = format!("{} planned poses, {}", result.poses.len(), result.robot);
        // the robot at 4 poses spread over the order
        let n_pose = result.poses.len();
        let mut robots = Vec::new();
        for k in 0..4.min(n_pose) {
            let q = &result.poses[k * (n_pose - 1) / 3].q_deg;
            robots.push(SafetyArgs::stick(&cfg, &model, q)?);
        }
        let bytes = if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
        {
            let svg = poses_svg(&title, &planned, &background, &robots)?;
            rigctl::io::atomic::check_text_for(path, TextFormat::Xml, &svg)?;
            svg.into_bytes()
        } else {
            rigctl::plot::png_bytes(&rigctl::plot::plan::PlanPoses {
                title,
                planned_mm: planned,
                candidates_mm: background,
                robots_mm: robots,
            })?
        };
        write_bytes_atomic(path, &bytes)?;
    }
    if let Some(path) = &args.json {
        let sheets_doc = sheets.as_ref().map(|r| sheets_json(r, cfg.noise_mm));
        let doc = plan_json(&result, cfg.noise_mm, cfg.seed, sheets_doc);
        let text = serde_json::to_string_pretty(&doc)
            .map_err(|e| CliError::failure(format!("JSON: {e}")))?;
        write_bytes_atomic(path, format!("{text}\n").as_bytes())?;
    }
    if let Some(path) = &args.safety.trajectory {
        let names: Vec<String> = if model.joint_names().is_empty() {
            (1..=model.n_joints()).map(|k| format!("q{k}")).collect()
        } else {
            model.joint_names().to_vec()
        };
        let prismatic: Vec<bool> = model.joints().iter().map(|j| j.prismatic).collect();
        let mut q: Vec<(Vec<f64>, bool)> = Vec::new();
        for (k, p) in result.poses.iter().enumerate() {
            if let (Some(true), Some(v)) = (result.order.via_before.get(k), &result.order.via_q) {
                q.push((v.clone(), false));
            }
            q.push((p.q_deg.clone(), true));
        }
        let yaml = rigctl::plan::trajectory::joint_trajectory_yaml(
            &names,
            &prismatic,
            &q,
            rigctl::plan::trajectory::TrajectoryTiming {
                max_speed_deg_s: args.safety.max_joint_speed_deg_s,
                dwell_s: args.safety.dwell_s,
            },
        );
        write_bytes_atomic(path, yaml.as_bytes())?;
    }
    write_text_atomic(&args.out, TextFormat::Csv, &plan_csv(&result))?;
    out!("{}", summary_table(&result, cfg.noise_mm))?;
    for line in &safety_lines {
        out!("{line}\n")?;
    }
    let o = &result.order;
    out!(
        "order: joint travel {:.0} deg (random order {:.0} deg); {} segments checked at most {} deg apart ({} configurations), {} unsafe ones avoided ({} through the via configuration), {} left\n",
        o.travel_deg,
        o.random_travel_deg,
        o.segments_checked,
        o.step_deg,
        o.configurations_checked,
        o.segments_unsafe,
        o.via_before.iter().filter(|v| **v).count(),
        if o.unsafe_left.is_empty() { "none".to_string() } else { o.unsafe_left.len().to_string() }
    )?;
    if let Some((a, b, why)) = o.unsafe_left.first() {
        out!(
            "WARNING: {} move(s) between consecutive poses leave the safe space on the straight way (first: poses {} -> {}, {why}); without collision geometry the joint frames' origins stand in for the links, so these moves are not verified: drive them with a motion planner, or give --urdf FILE --tip-link LINK (plan.json order.moves_verified = false)\n",
            o.unsafe_left.len(),
            a + 1,
            b + 1
        )?;
    }
    if let Some(v) = &o.via_q {
        let deg: Vec<String> = v.iter().map(|x| format!("{x:.1}")).collect();
        out!(
            "via configuration (home or mid-range): {}\n",
            deg.join(", ")
        )?;
    }
    if let Some(r) = &sheets {
        out!("{}", sheets_table(r))?;
    }
    Ok(())
}

/// The constraints on the tool point (tips on a tree): `--box`, `--visible-from` within
/// `--cone-deg`, `--min-z-mm`, checked finite.
pub(super) fn tool_constraints(args: &Args, ws: &mut Workspace) -> Result<(), CliError> {
    let finite = |flag: &str, v: &[f64]| {
        if v.iter()
            .all(|x| x.is_finite() && x.abs() <= rigctl::io::ranges::MAX_POSITION_MM)
        {
            Ok(())
        } else {
            Err(CliError::bad_input(format!(
                "{flag} {v:?}: finite positions within +-100 m (mm)"
            )))
        }
    };
    finite("--box", args.box_mm.as_deref().unwrap_or(&[]))?;
    finite(
        "--visible-from",
        args.visible_from.as_deref().unwrap_or(&[]),
    )?;
    finite("--min-z-mm", args.min_z_mm.as_slice())?;
    if !(args.cone_deg.is_finite() && args.cone_deg > 0.0 && args.cone_deg <= 180.0) {
        return Err(CliError::bad_input(format!(
            "--cone-deg {}: a half angle in (0, 180] deg",
            args.cone_deg
        )));
    }
    if let Some(b) = &args.box_mm {
        let b: [f64; 6] = b
            .as_slice()
            .try_into()
            .map_err(|_| CliError::bad_input("--box needs 6 numbers X0,Y0,Z0,X1,Y1,Z1"))?;
        ws.box_mm = Some(b);
    }
    if let Some(v) = &args.visible_from {
        if v.len() != 3 {
            return Err(CliError::bad_input("--visible-from needs 3 numbers X,Y,Z"));
        }
        ws.visible_from_mm = Some(Vector3::new(v[0], v[1], v[2]));
        ws.cone_half_angle_deg = args.cone_deg;
    }
    if let Some(z) = args.min_z_mm {
        ws.min_z_mm = Some(z);
    }
    Ok(())
}
