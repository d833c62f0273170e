//! The project file (`rigctl.toml` in the working directory, or `--project FILE`): the robot,
//! units, instrument, free frames, data files and the environment of `plan`, written once and
//! read by every subcommand (docs/project.md).
//!
//! The merge is in one place, before clap parses the command line: every value of the file that
//! the subcommand takes (see [`entries`]) and the command line does not give becomes the flag it
//! stands for, so that clap checks it, a flag given on the command line wins, and every command
//! behaves as the long command line it abbreviates.

use std::collections::BTreeMap;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use serde::Deserialize;

use super::CliError;

/// The file read when present in the working directory and no `--project` is given.
pub const DEFAULT_FILE: &str = "rigctl.toml";

/// The model flags that choose the robot (given on the command line: none of the file's).
const MODEL_FLAGS: [&str; 4] = ["robot", "model", "tool-mm", "set"];

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Project {
    #[serde(default)]
    pub robot: RobotSection,
    #[serde(default)]
    pub units: UnitsSection,
    #[serde(default)]
    pub instrument: InstrumentSection,
    #[serde(default)]
    pub frames: FramesSection,
    #[serde(default)]
    pub data: DataSection,
    #[serde(default)]
    pub plan: PlanSection,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSection {
    pub preset: Option<String>,
    pub model: Option<PathBuf>,
    pub urdf: Option<PathBuf>,
    pub base_link: Option<String>,
    pub tip_link: Option<String>,
    pub tool_mm: Option<f64>,
    #[serde(default)]
    pub set: BTreeMap<String, f64>,
    #[serde(default)]
    pub package_path: Vec<PathBuf>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnitsSection {
    pub joints: Option<AngleUnit>,
    pub points: Option<LengthUnit>,
    pub sep: Option<String>,
    pub decimal: Option<String>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(rename_all = "lowercase")]
pub enum AngleUnit {
    Deg,
    Rad,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    Mm,
    M,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstrumentSection {
    pub sigma_mm: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FramesSection {
    pub base: Option<bool>,
    pub markers: Option<Vec<u32>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataSection {
    pub poses: Option<PathBuf>,
    pub validate: Option<PathBuf>,
    pub joint_log: Option<PathBuf>,
    pub instrument_log: Option<PathBuf>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanSection {
    pub table_z_mm: Option<f64>,
    pub no_table: Option<bool>,
    #[serde(default)]
    pub keep_out: Vec<[f64; 6]>,
    pub limit_margin_deg: Option<f64>,
    pub clearance_mm: Option<f64>,
    pub srdf: Option<PathBuf>,
    /// `false`: plan checks no collision geometry (the URDF's meshes are not at hand).
    pub collision: Option<bool>,
}

/// One value of the file as the flag it stands for, and the subcommands that take it.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// Long flag without the dashes.
    pub flag: &'static str,
    /// Its values (one occurrence of the flag each); empty for a switch.
    pub values: Vec<String>,
    pub commands: &'static [&'static str],
}

const MODEL_CMDS: &[&str] = &[
    "fk",
    "simulate",
    "calibrate",
    "diagnose",
    "plan",
    "poses",
    "compensate",
    "model2urdf",
    "report",
];
const POSE_CMDS: &[&str] = &["fk", "calibrate", "diagnose", "plan", "poses", "report"];

/// A path of the file, relative to the file's folder.
fn rel(dir: &Path, p: &Path) -> String {
    if p.is_absolute() || dir.as_os_str().is_empty() {
        p.display().to_string()
    } else {
        dir.join(p).display().to_string()
    }
}

impl Project {
    /// Reads and checks `path` (exit 2 naming the file, line and key on an unknown key, a value
    /// of the wrong type or contradicting keys).
    pub fn load(path: &Path) -> Result<Self, CliError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::bad_input(format!("project file {}: {e}", path.display())))?;
        let p: Project = toml::from_str(&text).map_err(|e| {
            let at = e.span().map(|s| s.start).unwrap_or(0);
            let line_no = text.get(..at).map_or(1, |t| t.matches('\n').count() + 1);
            let line = text.lines().nth(line_no - 1).unwrap_or("");
            let key = line
                .split_once('=')
                .map(|(k, _)| k.trim().to_string())
                .filter(|k| !k.is_empty() && !e.message().contains(&format!("`{k}`")))
                .map_or_else(String::new, |k| format!("key `{k}`: "));
            CliError::bad_input(format!(
                "{}:{line_no}: {key}{}",
                path.display(),
                e.message().trim()
            ))
        })?;
        let r = &p.robot;
        let chosen = [r.preset.is_some(), r.model.is_some()];
        if chosen.iter().all(|&c| c) {
            return Err(CliError::bad_input(format!(
                "{}: [robot] preset and model both given: one robot",
                path.display()
            )));
        }
        if r.urdf.is_some() != r.tip_link.is_some() {
            return Err(CliError::bad_input(format!(
                "{}: [robot] urdf and tip_link go together (the chain's last link)",
                path.display()
            )));
        }
        Ok(p)
    }

    /// The file's values as flags (paths relative to `dir`, the file's folder).
    pub fn entries(&self, dir: &Path) -> Vec<Entry> {
        let mut out = Vec::new();
        let mut add = |flag, values: Vec<String>, commands| {
            out.push(Entry {
                flag,
                values,
                commands,
            })
        };
        let r = &self.robot;
        let collision = self.plan.collision != Some(false);
        let urdf_cmds: &'static [&'static str] = if collision {
            &["plan", "model2urdf"]
        } else {
            &["model2urdf"]
        };
        let plan_only: &'static [&'static str] = if collision { &["plan"] } else { &[] };
        if let Some(v) = &r.preset {
            add("robot", vec![v.clone()], MODEL_CMDS);
        }
        if let Some(v) = &r.model {
            add("model", vec![rel(dir, v)], MODEL_CMDS);
        }
        if let Some(v) = r.tool_mm {
            add("tool-mm", vec![v.to_string()], MODEL_CMDS);
        }
        if !r.set.is_empty() {
            let sets = r.set.iter().map(|(k, v)| format!("{k}={v}")).collect();
            add("set", sets, MODEL_CMDS);
        }
        if let Some(v) = &r.urdf {
            add("urdf", vec![rel(dir, v)], urdf_cmds);
        }
        if let Some(v) = &r.tip_link {
            add("tip-link", vec![v.clone()], plan_only);
        }
        if let Some(v) = &r.base_link {
            add("base-link", vec![v.clone()], urdf_cmds);
        }
        if !r.package_path.is_empty() {
            let dirs = r.package_path.iter().map(|p| rel(dir, p)).collect();
            add("package-path", dirs, plan_only);
        }
        let u = &self.units;
        if u.joints.is_some() || u.points.is_some() {
            let length = match u.points.unwrap_or(LengthUnit::Mm) {
                LengthUnit::Mm => "mm",
                LengthUnit::M => "m",
            };
            let angle = match u.joints.unwrap_or(AngleUnit::Deg) {
                AngleUnit::Deg => "deg",
                AngleUnit::Rad => "rad",
            };
            add("units", vec![format!("{length},{angle}")], POSE_CMDS);
        }
        if let Some(v) = &u.sep {
            add("sep", vec![v.clone()], POSE_CMDS);
        }
        if let Some(v) = &u.decimal {
            add("decimal", vec![v.clone()], POSE_CMDS);
        }
        if let Some(v) = self.instrument.sigma_mm {
            add("instrument-mm", vec![v.to_string()], &["diagnose"]);
            add("noise-mm", vec![v.to_string()], &["plan"]);
        }
        let f = &self.frames;
        if f.base == Some(true) {
            add("base", Vec::new(), &["calibrate", "plan"]);
        }
        if let Some(m) = f.markers.as_ref().filter(|m| !m.is_empty()) {
            let list: Vec<String> = m.iter().map(u32::to_string).collect();
            add("markers", vec![list.join(",")], &["calibrate"]);
            add("marker", vec![list[0].clone()], &["diagnose"]);
        }
        let d = &self.data;
        if let Some(v) = &d.poses {
            add("poses", vec![rel(dir, v)], &["calibrate", "diagnose"]);
        }
        if let Some(v) = &d.validate {
            add("validate", vec![rel(dir, v)], &["calibrate", "diagnose"]);
        }
        if let Some(v) = &d.joint_log {
            add("joints", vec![rel(dir, v)], &["poses"]);
        }
        if let Some(v) = &d.instrument_log {
            add("points", vec![rel(dir, v)], &["poses"]);
        }
        let p = &self.plan;
        if let Some(v) = p.table_z_mm {
            add("table-z-mm", vec![v.to_string()], &["plan"]);
        }
        if p.no_table == Some(true) {
            add("no-table", Vec::new(), &["plan"]);
        }
        if !p.keep_out.is_empty() {
            let boxes = p
                .keep_out
                .iter()
                .map(|b| b.map(|x| x.to_string()).join(","))
                .collect();
            add("keep-out", boxes, &["plan"]);
        }
        if let Some(v) = p.limit_margin_deg {
            add("limit-margin-deg", vec![v.to_string()], &["plan"]);
        }
        if let Some(v) = p.clearance_mm {
            add("clearance-mm", vec![v.to_string()], &["plan"]);
        }
        if let Some(v) = &p.srdf {
            add("srdf", vec![rel(dir, v)], plan_only);
        }
        out
    }
}

/// The project in effect for this run: its file and the flags it supplied.
#[derive(Debug, Clone)]
pub struct InEffect {
    pub file: PathBuf,
    /// The file came from `--project` (not found in the working directory).
    pub explicit: bool,
    pub supplied: Vec<&'static str>,
}

static IN_EFFECT: OnceLock<InEffect> = OnceLock::new();

/// The project file this run read, if any, and what it supplied.
pub fn in_effect() -> Option<&'static InEffect> {
    IN_EFFECT.get()
}

/// The long flags (without dashes) given in `args` (the subcommand's arguments).
fn given_flags(args: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for a in args {
        if a == "--" {
            break;
        }
        if let Some(f) = a.strip_prefix("--") {
            out.push(f.split('=').next().unwrap_or(f).to_string());
        }
    }
    out
}

/// The value of `--project` in `args`, if given.
fn project_flag(args: &[String]) -> Result<Option<PathBuf>, CliError> {
    for (k, a) in args.iter().enumerate() {
        if a == "--" {
            break;
        }
        if let Some(v) = a.strip_prefix("--project=") {
            return Ok(Some(PathBuf::from(v)));
        }
        if a == "--project" {
            return match args.get(k + 1) {
                Some(v) => Ok(Some(PathBuf::from(v))),
                None => Err(CliError::bad_input("--project: give the project file")),
            };
        }
    }
    Ok(None)
}

/// The command line with the project file's values inserted (after the subcommand) where the
/// subcommand takes them and the command line does not give them. Without a project file (none
/// in the working directory, no `--project`) the command line as it is.
pub fn merge_args(argv: Vec<OsString>, cwd_file: &Path) -> Result<Vec<OsString>, CliError> {
    let text: Vec<String> = argv
        .iter()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    // the subcommand: the first word, after a `--project FILE` given before it
    let mut at = 1;
    while let Some(a) = text.get(at) {
        match a.as_str() {
            "--project" => at += 2,
            a if a.starts_with("--project=") => at += 1,
            _ => break,
        }
    }
    let Some(cmd) = text.get(at).filter(|c| !c.starts_with('-')).cloned() else {
        return Ok(argv);
    };
    if cmd == "init" || cmd == "help" {
        return Ok(argv);
    }
    let rest = &text[at + 1..];
    let before = &text[1..at];
    let (file, explicit) = match project_flag(before)?.or(project_flag(rest)?) {
        Some(f) => {
            if !f.is_file() {
                return Err(CliError::bad_input(format!(
                    "--project {}: no such file",
                    f.display()
                )));
            }
            (f, true)
        }
        None if cwd_file.is_file() => (cwd_file.to_path_buf(), false),
        None => return Ok(argv),
    };
    let project = Project::load(&file)?;
    let dir = file.parent().unwrap_or(Path::new("")).to_path_buf();
    let given = given_flags(rest);
    let user_model = given.iter().any(|g| MODEL_FLAGS[..2].contains(&g.as_str()));
    let user_sets = user_set_names(rest);
    let mut extra: Vec<OsString> = Vec::new();
    let mut supplied = Vec::new();
    for e in project.entries(&dir) {
        if !e.commands.contains(&cmd.as_str()) {
            continue;
        }
        if user_model && MODEL_FLAGS.contains(&e.flag) {
            continue;
        }
        let values: Vec<&String> = if e.flag == "set" {
            // a --set on the command line replaces the file's value of that parameter only
            e.values
                .iter()
                .filter(|v| !user_sets.iter().any(|n| v.split('=').next() == Some(n)))
                .collect()
        } else if given.iter().any(|g| g == e.flag) {
            continue;
        } else {
            e.values.iter().collect()
        };
        if e.values.is_empty() {
            extra.push(format!("--{}", e.flag).into());
        }
        for v in &values {
            extra.push(format!("--{}={v}", e.flag).into());
        }
        if e.values.is_empty() || !values.is_empty() {
            supplied.push(e.flag);
        }
    }
    super::out::errln!(
        "rigctl: project file {} read{}",
        file.display(),
        if supplied.is_empty() {
            String::new()
        } else {
            format!(
                " ({})",
                supplied
                    .iter()
                    .map(|f| format!("--{f}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            )
        }
    );
    let _ = IN_EFFECT.set(InEffect {
        file,
        explicit,
        supplied,
    });
    let mut out: Vec<OsString> = argv[..=at].to_vec();
    out.extend(extra);
    out.extend(argv[at + 1..].iter().cloned());
    Ok(out)
}

/// The parameter names of the command line's `--set NAME=VALUE`s.
fn user_set_names(args: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    for (k, a) in args.iter().enumerate() {
        let v = match a.strip_prefix("--set=") {
            Some(v) => Some(v),
            None if a == "--set" => args.get(k + 1).map(String::as_str),
            None => None,
        };
        if let Some(v) = v {
            out.push(v.split('=').next().unwrap_or(v).trim().to_string());
        }
    }
    out
}

#[cfg(test)]
mod tests;
