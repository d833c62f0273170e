//! The model-choice arguments shared by every command that works on a robot model:
//! `[--robot NAME | --model FILE.toml] [--tool-mm L] [--set NAME=VALUE ...]`
//! (resolved by `rigctl::model::choose_model`).
//!
//! Flatten into a command's `Args` with `#[command(flatten)]`; the clap ids stay `robot`,
//! `model`, `tool_mm` and `sets`, so `conflicts_with`/`requires` elsewhere may name them.

use std::path::PathBuf;

use rigctl::model::{choose_model, Model, ModelChoice};

use super::CliError;

/// Which model a command works on: a built-in robot or a model file, plus overrides.
#[derive(clap::Args, Debug, Clone)]
pub struct ModelArgs {
    /// Built-in robot (declared model): katana450 (default) or ur5.
    #[arg(long, value_name = "NAME", conflicts_with = "model")]
    pub robot: Option<String>,
    /// Model file (TOML) instead of a built-in robot, e.g. one written by `calibrate --out`,
    /// `joints --out` or `urdf2model`.
    #[arg(long, value_name = "FILE.toml")]
    pub model: Option<PathBuf>,
    /// Katana tool length d5 in mm, katana450 preset only: 200 bare, 330 with the pencil holder
    /// (the default for the pencil rig's data).
    #[arg(long, value_name = "L")]
    pub tool_mm: Option<f64>,
    /// Override a model parameter (deg for angles, mm for lengths), e.g. tool_dz=31; repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub sets: Vec<String>,
}

impl ModelArgs {
    /// The model these arguments name (katana450 with its bare tool when none is given).
    pub fn choose(&self) -> Result<Model, CliError> {
        self.choose_with_default_tool(None)
    }

    /// As [`ModelArgs::choose`], but for the katana450 preset without `--tool-mm` the tool
    /// length is `default_tool_mm` (e.g. `Some(rigctl::model::KATANA_PENCIL_TOOL_MM)`); other
    /// robots and model files are unaffected.
    pub fn choose_with_default_tool(
        &self,
        default_tool_mm: Option<f64>,
    ) -> Result<Model, CliError> {
        let katana = self
            .robot
            .as_deref()
            .is_none_or(|r| r.eq_ignore_ascii_case("katana450"));
        let tool_mm = match (&self.model, self.tool_mm) {
            (None, None) if katana => default_tool_mm,
            (_, given) => given,
        };
        let model = choose_model(&ModelChoice {
            robot: self.robot.as_deref(),
            model_file: self.model.as_deref(),
            tool_mm,
            sets: &self.sets,
        })?;
        // --tool-mm and --set values: the physical ranges of a model file
        model
            .check_ranges()
            .map_err(|e| CliError::bad_input(format!("--tool-mm / --set: {e}")))?;
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    /// The pencil-holder default applies to the Katana only; `--robot ur5` keeps its own tool.
    #[test]
    fn pencil_default_is_for_the_katana_only() {
        let args = |robot: Option<&str>| super::ModelArgs {
            robot: robot.map(str::to_string),
            model: None,
            tool_mm: None,
            sets: Vec::new(),
        };
        let ur5 = args(Some("ur5")).choose_with_default_tool(Some(330.0));
        assert!(ur5.is_ok(), "{:?}", ur5.err());
        let k = args(None).choose_with_default_tool(Some(330.0)).unwrap();
        assert!((k.param("d5").unwrap() - 330.0).abs() < 1e-12);
    }
    use rigctl::model::{KATANA_PENCIL_TOOL_MM, KATANA_TOOL_MM};

    use super::ModelArgs;

    /// A command with nothing but the model choice.
    #[derive(clap::Parser, Debug)]
    struct Probe {
        #[command(flatten)]
        model: ModelArgs,
    }

    fn parse(args: &[&str]) -> Result<ModelArgs, clap::Error> {
        Probe::try_parse_from(std::iter::once("probe").chain(args.iter().copied())).map(|p| p.model)
    }

    /// The tool length d5 of the chosen model, if the choice succeeds.
    fn d5_mm(args: &[&str], default_tool_mm: Option<f64>) -> Option<f64> {
        let model = parse(args)
            .ok()?
            .choose_with_default_tool(default_tool_mm)
            .ok()?;
        model.param("d5")
    }

    #[test]
    fn default_tool_applies_only_without_tool_mm() {
        let pencil = Some(KATANA_PENCIL_TOOL_MM);
        assert_eq!(d5_mm(&[], None), Some(KATANA_TOOL_MM));
        assert_eq!(d5_mm(&[], pencil), pencil);
        assert_eq!(d5_mm(&["--tool-mm", "250"], pencil), Some(250.0));
        assert_eq!(d5_mm(&["--tool-mm", "250"], None), Some(250.0));
        // --set is applied after the preset's tool length
        assert_eq!(d5_mm(&["--set", "d5=260"], pencil), Some(260.0));
    }

    #[test]
    fn robot_conflicts_with_model() {
        let err = parse(&["--robot", "ur5", "--model", "m.toml"]).map(|_| ());
        assert_eq!(
            err.map_err(|e| e.kind()),
            Err(clap::error::ErrorKind::ArgumentConflict)
        );
    }

    #[test]
    fn tool_mm_with_a_model_file_is_bad_input() {
        let args = parse(&["--model", "m.toml", "--tool-mm", "330"]);
        match args.map(|a| a.choose().map(|_| ())) {
            Ok(Err(e)) => assert_eq!(e.exit_code(), 2, "{e}"),
            other => panic!("expected a usage error, got {other:?}"),
        }
    }
}
