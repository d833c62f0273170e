//! The commands the report's "What to do next" suggests, built to run as written from the
//! folder `report` ran in: the model flags the run used (none when a project file supplies them,
//! `ReportOptions::command_model`) and the run directory's files by their path from there.

use std::path::{Path, PathBuf};

use super::run_dir::RunDir;
use super::ReportOptions;

/// How the suggested commands name the model and the run's files.
#[derive(Debug, Clone, Default)]
pub struct Suggest {
    /// The model flags, each with a leading space (empty: the default robot or a project file).
    model: String,
    /// The run directory as given to `report`.
    dir: PathBuf,
    /// The run's calibration and held-out pose files, if it holds them.
    cal: Option<PathBuf>,
    val: Option<PathBuf>,
}

/// `s` as one shell word.
fn shell(s: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "/._-=,+:@%".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// The model flags of `opts` (a model file, else the robot named, with the tool and overrides).
pub fn model_flags(opts: &ReportOptions, robot: Option<&str>) -> String {
    if let Some(m) = &opts.command_model {
        return m.clone();
    }
    let mut out = String::new();
    match (&opts.model_file, robot) {
        (Some(f), _) => out.push_str(&format!(" --model {}", shell(&f.display().to_string()))),
        (None, Some(r)) if r != "katana450" => out.push_str(&format!(" --robot {}", shell(r))),
        _ => {}
    }
    if let (None, Some(l)) = (&opts.model_file, opts.tool_mm) {
        out.push_str(&format!(" --tool-mm {l}"));
    }
    for s in &opts.sets {
        out.push_str(&format!(" --set {}", shell(s)));
    }
    out
}

impl Suggest {
    pub fn new(dir: &Path, run: &RunDir, robot: Option<&str>, opts: &ReportOptions) -> Self {
        Self {
            model: model_flags(opts, robot),
            dir: dir.to_path_buf(),
            cal: run.cal_csv.clone(),
            val: run.val_csv.clone(),
        }
    }

    /// A file of the run directory, as a shell word.
    pub fn path(&self, name: &str) -> String {
        shell(&self.dir.join(name).display().to_string())
    }

    /// `rigctl plan` for 60 poses (with `extra` flags).
    pub fn plan(&self, extra: &str) -> String {
        format!("rigctl plan{} --n 60{extra} --out plan.csv", self.model)
    }

    /// `rigctl plan` separating what the diagnose document `name` (in the run) leaves open,
    /// adding to the run's calibration poses.
    pub fn plan_from_diagnose(&self, name: &str) -> String {
        let poses = self.cal.as_ref().map_or_else(String::new, |p| {
            format!(" --poses {}", shell(&p.display().to_string()))
        });
        self.plan(&format!(" --from-diagnose {}{poses}", self.path(name)))
    }

    /// `rigctl plan` adding 60 poses to the run's calibration poses (when it holds them).
    pub fn plan_more(&self) -> String {
        self.plan(&self.cal.as_ref().map_or_else(String::new, |p| {
            format!(" --poses {}", shell(&p.display().to_string()))
        }))
    }

    /// `rigctl diagnose` on the run's pose files, when it holds both.
    pub fn diagnose(&self) -> Option<String> {
        let (cal, val) = (self.cal.as_ref()?, self.val.as_ref()?);
        Some(format!(
            "rigctl diagnose{} --poses {} --validate {} --json {}",
            self.model,
            shell(&cal.display().to_string()),
            shell(&val.display().to_string()),
            self.path("diagnose.json")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_flags_name_what_the_run_used() {
        let mut o = ReportOptions::default();
        assert_eq!(model_flags(&o, None), "");
        assert_eq!(model_flags(&o, Some("katana450")), "");
        assert_eq!(model_flags(&o, Some("ur5")), " --robot ur5");
        o.model_file = Some(PathBuf::from("my arm.toml"));
        o.sets = vec!["tool_dz=31".into()];
        assert_eq!(
            model_flags(&o, Some("panda")),
            " --model 'my arm.toml' --set tool_dz=31"
        );
        o.command_model = Some(String::new());
        assert_eq!(model_flags(&o, Some("panda")), "");
    }
}
