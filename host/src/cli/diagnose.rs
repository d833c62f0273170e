//! `rigctl diagnose --poses CAL.csv --validate VAL.csv [--json OUT.json] [--out MODEL.toml]
//! [--plots DIR] [--residual-model] [--robot NAME | --model FILE.toml] [--tool-mm L]
//! [--set NAME=VALUE ...] [--units m,rad] [--marker K]`:
//! fits the declared model, adds the missing effects the data establish (see
//! `rigctl::diagnose`), prints a table, and writes the JSON report, the extended model and plots.
//!
//! The low-cost rig's partial measurements work the same way: `--samples FUSED.csv`
//! (repeatable; `rigctl fuse` output, with or without `--poses`) for the calibration set, and
//! `--validate` takes a pose file or a fused file (recognised by its `# rigctl-fused/1` line).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rigctl::calib::MeasuredSet;
use rigctl::diagnose::plots::write_plots;
use rigctl::diagnose::probe::plot::write_probe_plots;
use rigctl::diagnose::probe::{hybrid_report, jacobians};
use rigctl::diagnose::{diagnose, DiagnoseOptions};
use rigctl::io::atomic::write_text_atomic;
use rigctl::io::finite::TextFormat;
use rigctl::model::KATANA_PENCIL_TOOL_MM;

use super::model_args::ModelArgs;
use super::out::{out, outln};
use super::pose_args::PoseArgs;
use super::CliError;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Calibration poses (q1..qN, x, y, z [, t]).
    #[arg(long, value_name = "CAL.csv", required_unless_present = "samples")]
    pub poses: Option<PathBuf>,
    /// Calibration samples of the low-cost rig (`rigctl fuse` output: only the components
    /// across the path and out of the sheet are measured); repeatable, one file per sheet.
    /// Without --model the Katana's tool length defaults to 330 mm (the pencil holder).
    #[arg(long = "samples", value_name = "FUSED.csv")]
    pub samples: Vec<PathBuf>,
    /// Held-out set (reported before/after every effect): a pose file, or a fused file of
    /// another sheet (repeatable).
    #[arg(long, value_name = "VAL.csv", required = true)]
    pub validate: Vec<PathBuf>,
    /// Write the JSON report (FORMATS.md "diagnose --json").
    #[arg(long, value_name = "OUT.json")]
    pub json: Option<PathBuf>,
    /// Write the extended model (loadable by fk / calibrate --model).
    #[arg(long, value_name = "MODEL.toml")]
    pub out: Option<PathBuf>,
    /// Write SVG plots of the residual against the regressor of every added effect.
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    // The model choice: --robot NAME | --model FILE.toml, --tool-mm L, --set NAME=VALUE.
    #[command(flatten)]
    pub model: ModelArgs,
    /// One-sigma accuracy per coordinate of the measuring instrument (mm; a laser tracker ~0.01,
    /// a mocap system ~0.2): the floor the final residual is judged against (with the
    /// repeatability of poses measured more than once).
    #[arg(long = "instrument-mm", value_name = "SIGMA")]
    pub instrument_mm: Option<f64>,
    /// Keep the probe's smooth function of the joint angles as a correction (a hybrid model):
    /// its held-out statistics are reported apart (JSON key `residual_model`, table line
    /// `hybrid`), never as a physical effect.
    #[arg(long)]
    pub residual_model: bool,
    /// Seed of the cross-validation folds.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Keep every pose: no gross-error rule (poses whose error is inconsistent with the others
    /// are otherwise left out of every fit and of the floor's test, and listed as `outliers`).
    #[arg(long)]
    pub keep_outliers: bool,
    // --units LENGTH,ANGLE of the pose files.
    #[command(flatten)]
    pub pose: PoseArgs,
    /// In pose files with several measured points per pose (x1,y1,z1,..): the point diagnosed
    /// (1-based; the others are ignored).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub marker: u64,
    /// A model without link masses: assume them (one per joint, mid-segment, in proportion to
    /// the segment lengths, 20 kg per metre in total) so that joint compliance is offered; said
    /// in the output (JSON `assumed_masses`).
    #[arg(long)]
    pub assume_masses: bool,
    /// The robot's mass for `--assume-masses` (kg; implies it).
    #[arg(long, value_name = "KG")]
    pub robot_mass_kg: Option<f64>,
}

pub fn run(args: Args) -> Result<(), CliError> {
    super::files()
        .input("--poses", args.poses.as_deref())
        .inputs("--samples", &args.samples)
        .inputs("--validate", &args.validate)
        .input("--model", args.model.model.as_deref())
        .output("--json", args.json.as_deref())
        .output("--out", args.out.as_deref())
        .output_dir("--plots", args.plots.as_deref(), |n| n.ends_with(".svg"))
        .apart("--poses", "--validate")
        .apart("--samples", "--validate")
        .check()?;
    if let Some(tree) = super::calibrate_tree::tree_model(&args.model)? {
        return super::diagnose_tree::run(&args, tree);
    }
    // the pencil holder is on the arm when the rig's samples are measured
    let default_tool_mm = (!args.samples.is_empty()).then_some(KATANA_PENCIL_TOOL_MM);
    let model = args.model.choose_with_default_tool(default_tool_mm)?;
    let model = assumed_masses(model, &args)?;
    let marker = usize::try_from(args.marker - 1).unwrap_or(usize::MAX);
    let spec = args.pose.spec(&model, true, marker);
    let mut cal: Option<MeasuredSet> = args
        .poses
        .as_deref()
        .map(|p| {
            let set = MeasuredSet::read_with(p, &spec)?;
            super::pose_args::check_plausible(&model, &set, p)?;
            Ok::<_, CliError>(set)
        })
        .transpose()?;
    for path in &args.samples {
        let d = read_samples(path, &model)?;
        cal = Some(match cal {
            Some(c) => c.concat(d),
            None => d,
        });
    }
    let cal = cal.ok_or_else(|| CliError::bad_input("--poses or --samples is required"))?;
    let mut val: Option<MeasuredSet> = None;
    for path in &args.validate {
        let d = if is_fused(path) {
            read_samples(path, &model)?
        } else {
            let set = MeasuredSet::read_with(path, &spec)?;
            super::pose_args::check_plausible(&model, &set, path)?;
            if let Some(p) = args.poses.as_deref() {
                super::pose_args::check_apart(&cal, &set, p, path)?;
            }
            set
        };
        val = Some(match val {
            Some(v) => v.concat(d),
            None => d,
        });
    }
    let val = val.ok_or_else(|| CliError::bad_input("--validate is required"))?;
    let mut opts = DiagnoseOptions::default();
    opts.decide.seed = args.seed;
    opts.keep_outliers = args.keep_outliers;
    opts.instrument_mm = instrument_mm(&args)?;
    let spinner = spinner(format!(
        "diagnose: declared fit, candidate effects, cross-validation on {} + {} measurements",
        cal.len(),
        val.len()
    ));
    let diag = diagnose(&model, &cal, &val, &opts);
    spinner.finish_and_clear();
    let mut diag = diag?;
    if args.residual_model {
        let physical = diag.model.errors(&val)?;
        let fitted = &diag.selection.last.fitted;
        let jac = jacobians(&diag.model, &val, fitted)?;
        let names: Vec<String> = fitted.iter().map(|u| u.name(&diag.model.model)).collect();
        diag.report.residual_model = Some(hybrid_report(
            &diag.probe.model,
            &val,
            &physical,
            &jac,
            &names,
        ));
    }
    // The plots are written first and committed last: a plot that cannot be written (a full
    // disk) leaves the JSON and the model as they were, and the old plots.
    let plots = match &args.plots {
        Some(dir) => {
            let lock = rigctl::io::atomic::lock_dir(dir)?;
            // every plot as one commit; the plots of an earlier run that this one lacks go
            let set = rigctl::io::file_set::begin(dir, is_diagnose_plot)?;
            write_plots(dir, &diag)?;
            write_probe_plots(dir, &diag.probe)?;
            Some((lock, set))
        }
        None => None,
    };
    if let Some(path) = &args.json {
        diag.report.assumed_masses = assumed_masses_json(&model);
        rigctl::io::atomic::write_json_atomic(path, &diag.report)?;
    }
    if let Some(path) = &args.out {
        let mut text = String::new();
        let ext = &diag.model;
        let _ = writeln!(
            text,
            "# Written by rigctl diagnose; evaluate with{} tilting.",
            if ext.tilt { "" } else { "out" }
        );
        // The joint map and the time terms (thermal growth, drifts) are model-file keys.
        text.push_str(&ext.to_model().to_toml_string());
        write_text_atomic(path, TextFormat::Toml, &text)?;
    }
    if let Some((_lock, set)) = plots {
        set.commit()?;
    }
    out!("{}", diag.report.table())?;
    if !diag.report.converged {
        return Err(CliError::failure(format!(
            "{}; outputs written with \"converged\": false",
            rigctl::diagnose::NOT_CONVERGED_NOTE
        )));
    }
    Ok(())
}

/// `model` with assumed link masses when asked (`--assume-masses`, `--robot-mass-kg`), said on
/// stdout; a note when it has none and no tilting (no compliance candidate is offered).
fn assumed_masses(
    model: rigctl::model::Model,
    args: &Args,
) -> Result<rigctl::model::Model, CliError> {
    let asked = args.assume_masses || args.robot_mass_kg.is_some();
    if !model.masses().is_empty() {
        if asked {
            return Err(CliError::bad_input(
                "--assume-masses / --robot-mass-kg: the model declares its link masses (remove the flag, or its [[mass]] rows)",
            ));
        }
        return Ok(model);
    }
    if !asked {
        if model.tilt_params().is_none() {
            outln!("note: the model has no link masses: no joint compliance is offered (--assume-masses, or --robot-mass-kg KG, to offer it with assumed masses; [[mass]] rows for the robot's own)")?;
        }
        return Ok(model);
    }
    let m = model
        .with_assumed_masses(args.robot_mass_kg)
        .map_err(|e| CliError::bad_input(format!("--robot-mass-kg: {e}")))?;
    let per: Vec<String> = m
        .masses()
        .iter()
        .map(|p| format!("{:.2}", p.mass_kg))
        .collect();
    outln!(
        "link masses ASSUMED (none declared): {:.2} kg in total, {} kg on joints 1..{}, mid-segment; compliance values are per kgf.m of these assumed torques",
        m.masses().iter().map(|p| p.mass_kg).sum::<f64>(),
        per.join(", "),
        per.len()
    )?;
    Ok(m)
}

/// The JSON `assumed_masses` of a model whose masses are assumed.
fn assumed_masses_json(model: &rigctl::model::Model) -> Option<serde_json::Value> {
    model.masses_assumed().then(|| {
        let kg: Vec<f64> = model.masses().iter().map(|p| p.mass_kg).collect();
        serde_json::json!({
            "total_kg": kg.iter().sum::<f64>(),
            "per_joint_kg": kg,
            "rule": "one point mass per joint, mid-segment, in proportion to the segment lengths",
        })
    })
}

/// A plot `diagnose --plots` writes: `NN_ID.svg` or `probe_NAME.svg`.
fn is_diagnose_plot(name: &str) -> bool {
    let b = name.as_bytes();
    name.ends_with(".svg")
        && (name.starts_with("probe_")
            || (b.len() > 3 && b[0].is_ascii_digit() && b[1].is_ascii_digit() && b[2] == b'_'))
}

/// Whether `path` is a fused-samples file (its first line names the format).
fn is_fused(path: &Path) -> bool {
    use std::io::Read as _;
    // the first line only, and at most 4 KiB of it (a device or FIFO may never end a line)
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(4096).read_to_end(&mut head))
        .map(|_| {
            let first = head.split(|&b| b == b'\n').next().unwrap_or(&[]);
            String::from_utf8_lossy(first).contains(rigctl::fusion::fused_file::FUSED_FORMAT)
        })
        .unwrap_or(false)
}

/// One sheet's fused samples as partial measurements (moments in motion of `model`).
fn read_samples(path: &Path, model: &rigctl::model::Model) -> Result<MeasuredSet, CliError> {
    let fused = rigctl::fusion::read_fused(path, model.n_joints())?;
    Ok(MeasuredSet::from_fused(&fused)?.with_inertial_moments(model)?)
}

/// `--instrument-mm`, checked: a finite figure above zero, or none.
pub(super) fn instrument_mm(args: &Args) -> Result<Option<f64>, CliError> {
    match args.instrument_mm {
        Some(s) if !(s.is_finite() && s > 0.0) => Err(CliError::bad_input(format!(
            "--instrument-mm {s}: must be a finite number > 0"
        ))),
        s => Ok(s),
    }
}

/// Progress on stderr while the candidates are fitted (drawn only when stderr is a terminal).
pub(super) fn spinner(message: String) -> indicatif::ProgressBar {
    let spinner =
        indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
        spinner.set_style(style);
    }
    spinner.set_message(message);
    spinner.enable_steady_tick(std::time::Duration::from_millis(200));
    spinner
}
