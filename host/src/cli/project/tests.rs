use std::path::Path;

use super::{merge_args, Project};

fn write(dir: &Path, text: &str) -> std::path::PathBuf {
    let p = dir.join("rigctl.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn load_err(text: &str) -> (u8, String) {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), text);
    let e = Project::load(&p).unwrap_err();
    (
        e.exit_code(),
        e.message.replace(&p.display().to_string(), "F"),
    )
}

#[test]
fn unknown_key_names_file_line_and_key() {
    let (code, msg) = load_err("[robot]\npreset = \"ur5\"\n\n[units]\njoint = \"deg\"\n");
    assert_eq!(code, 2);
    assert!(msg.starts_with("F:5: "), "{msg}");
    assert!(msg.contains("`joint`"), "{msg}");
}

#[test]
fn wrong_type_names_file_line_and_key() {
    let (code, msg) = load_err("[instrument]\nsigma_mm = \"fine\"\n");
    assert_eq!(code, 2);
    assert!(msg.starts_with("F:2: key `sigma_mm`"), "{msg}");
    let (_, msg) = load_err("[units]\njoints = \"degrees\"\n");
    assert!(msg.starts_with("F:2: key `joints`"), "{msg}");
}

#[test]
fn preset_and_model_together_is_bad_input() {
    let (code, msg) = load_err("[robot]\npreset = \"ur5\"\nmodel = \"m.toml\"\n");
    assert_eq!(code, 2, "{msg}");
}

/// Every flag the file stands for exists on every subcommand it is given to, as a switch when it
/// has no value.
#[test]
fn every_entry_is_a_flag_of_its_commands() {
    let text = "[robot]\nmodel = \"m.toml\"\nurdf = \"r.urdf\"\ntip_link = \"t\"\nbase_link = \"b\"\n\
        tool_mm = 3.0\npackage_path = [\"p\"]\n[robot.set]\ntool_dz = 31.0\n\
        [units]\njoints = \"rad\"\npoints = \"m\"\nsep = \";\"\ndecimal = \",\"\n\
        [instrument]\nsigma_mm = 0.01\n[frames]\nbase = true\nmarkers = [1, 2]\n\
        [data]\nposes = \"c.csv\"\nvalidate = \"v.csv\"\njoint_log = \"j\"\ninstrument_log = \"i\"\n\
        [plan]\ntable_z_mm = -5.0\nno_table = true\nkeep_out = [[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]]\n\
        limit_margin_deg = 3.0\nclearance_mm = 5.0\nsrdf = \"s.srdf\"\n";
    let p: Project = toml::from_str(text).unwrap();
    let cli = <super::super::Cli as clap::CommandFactory>::command();
    let entries = p.entries(Path::new("proj"));
    assert_eq!(entries.len(), 25);
    for e in &entries {
        for c in e.commands {
            let sub = cli.find_subcommand(c).unwrap_or_else(|| panic!("{c}"));
            let arg = sub
                .get_arguments()
                .find(|a| a.get_long() == Some(e.flag))
                .unwrap_or_else(|| panic!("{c} has no --{}", e.flag));
            assert_eq!(
                e.values.is_empty(),
                !arg.get_action().takes_values(),
                "{c} --{}",
                e.flag
            );
        }
    }
    let model = entries.iter().find(|e| e.flag == "model").unwrap();
    assert_eq!(
        model.values,
        vec![Path::new("proj").join("m.toml").display().to_string()]
    );
    let units = entries.iter().find(|e| e.flag == "units").unwrap();
    assert_eq!(units.values, vec!["m,rad".to_string()]);
}

fn merged(dir: &Path, args: &[&str]) -> Vec<String> {
    let argv = std::iter::once("rigctl")
        .chain(args.iter().copied())
        .map(Into::into)
        .collect();
    merge_args(argv, &dir.join("rigctl.toml"))
        .unwrap()
        .into_iter()
        .map(|a| a.to_string_lossy().into_owned())
        .collect()
}

#[test]
fn command_line_wins_and_only_the_commands_flags_are_added() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "[robot]\nmodel = \"m.toml\"\n[robot.set]\ntool_dz = 31.0\ntool_dx = 1.0\n\
         [frames]\nbase = true\n[data]\nposes = \"c.csv\"\n[instrument]\nsigma_mm = 0.02\n",
    );
    let d = dir.path().display().to_string();
    let a = merged(
        dir.path(),
        &["calibrate", "--poses", "x.csv", "--set", "tool_dz=5"],
    );
    assert!(a.contains(&format!("--model={d}/m.toml")), "{a:?}");
    assert!(a.contains(&"--set=tool_dx=1".to_string()), "{a:?}");
    assert!(!a.iter().any(|x| x.starts_with("--set=tool_dz")), "{a:?}");
    assert!(!a.iter().any(|x| x.starts_with("--poses=")), "{a:?}");
    assert!(a.contains(&"--base".to_string()), "{a:?}");
    assert!(!a.iter().any(|x| x.starts_with("--instrument-mm")), "{a:?}");
    // a robot on the command line: none of the file's model flags
    let a = merged(dir.path(), &["diagnose", "--robot", "ur5"]);
    assert!(
        !a.iter()
            .any(|x| x.starts_with("--model") || x.starts_with("--set")),
        "{a:?}"
    );
    assert!(a.contains(&"--instrument-mm=0.02".to_string()), "{a:?}");
    // --project before the subcommand
    let other = tempfile::tempdir().unwrap();
    let file = dir.path().join("rigctl.toml");
    let f = file.display().to_string();
    let a = merged(
        other.path(),
        &["--project", &f, "diagnose", "--validate", "v.csv"],
    );
    assert_eq!(a[3], "diagnose", "{a:?}");
    assert!(a.contains(&format!("--poses={d}/c.csv")), "{a:?}");
    assert!(!a.iter().any(|x| x.starts_with("--validate=")), "{a:?}");
    // init never reads it
    assert_eq!(merged(dir.path(), &["init", "--robot", "ur5"]).len(), 4);
}

#[test]
fn the_file_init_writes_loads_back() {
    let model = rigctl::model::choose_model(&rigctl::model::ModelChoice {
        robot: Some("ur5"),
        ..Default::default()
    })
    .unwrap();
    let text = super::super::init::project_text("# robot\npreset = \"ur5\"\n", &model, &[]);
    let p: Project = toml::from_str(&text).unwrap();
    assert_eq!(p.robot.preset.as_deref(), Some("ur5"));
    assert_eq!(p.plan.table_z_mm, Some(0.0));
    assert_eq!(text.matches("#   q").count(), 6);
    // every key written has a comment line above it
    let lines: Vec<&str> = text.lines().collect();
    for (k, l) in lines.iter().enumerate() {
        if l.contains(" = ") && !l.starts_with('#') {
            assert!(lines[k - 1].starts_with('#'), "no comment above `{l}`");
        }
    }
}
