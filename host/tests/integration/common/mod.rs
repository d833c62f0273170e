//! Shared by the integration tests: the files of `../shared`, which CI requires.
#![allow(dead_code)]

use std::path::PathBuf;

pub mod fake_board;
pub mod long_urdf;
pub mod poses;
pub mod record;
pub mod spawn;
pub mod spawn_rule;

/// `rel` (a file or folder) under the shared directory (`rigctl::shared_dir()`: `$RIG_SHARED_DIR`
/// or `../shared`), or `None` after a `SKIPPED` message when it is absent. With `CI=true` its
/// absence fails the test instead: CI runs with `../shared` beside the clone, so a missing file
/// there is a broken setup, never a reason to pass.
pub fn shared_file(test: &str, rel: &str) -> Option<PathBuf> {
    let path = rigctl::shared_dir().map(|d| d.join(rel));
    if let Some(p) = path.filter(|p| p.exists()) {
        return Some(p);
    }
    let msg = format!("{test}: ../shared/{rel} is absent (or set RIG_SHARED_DIR)");
    if rigctl::in_ci() {
        panic!("{msg}; with CI=true the shared data is required");
    }
    eprintln!("SKIPPED {msg}");
    None
}

/// The `ur5` preset with the laser tracker's SMR as its tool point (`UR5_SMR_TOOL_MM`), the
/// model the UR5 data sets of `../shared` are calibrated with.
pub fn ur5_with_smr_tool() -> rigctl::model::Model {
    let mut model = rigctl::model::ur5().expect("the ur5 preset builds");
    for (name, v) in ["tool_dx", "tool_dy", "tool_dz"]
        .iter()
        .zip(rigctl::model::UR5_SMR_TOOL_MM)
    {
        model
            .set_param(name, v)
            .expect("the ur5 preset has a tool point");
    }
    model
}

/// The real UR5 laser-tracker set (`../shared/data/real/ur5_laser_tracker`): the model of
/// [`ur5_with_smr_tool`], the 1000 grid poses and the 20 random test poses; `None` after the
/// [`shared_file`] message when it is absent.
pub fn ur5_tracker(
    test: &str,
) -> Option<(
    rigctl::model::Model,
    rigctl::calib::MeasuredSet,
    rigctl::calib::MeasuredSet,
)> {
    let dir = shared_file(test, "data/real/ur5_laser_tracker")?;
    let model = ur5_with_smr_tool();
    let read = |name: &str| {
        rigctl::calib::MeasuredSet::read(&dir.join(name), &model)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let (grid, random) = (read("grid.csv"), read("random.csv"));
    Some((model, grid, random))
}

/// One row `t,x,y,z,ax,ay,az` of a `compensate --path` file (s, mm, unit tool axis).
pub fn path_row(t_s: f64, x: &nalgebra::Vector3<f64>, a: &nalgebra::Vector3<f64>) -> String {
    format!(
        "{t_s:.3},{:.12},{:.12},{:.12},{:.15},{:.15},{:.15}\n",
        x.x, x.y, x.z, a.x, a.y, a.z
    )
}

/// Packages of the Python consumers the ROS-ecosystem tests run (PyPI names and versions).
pub const PY_PACKAGES: [&str; 2] = ["pin==4.1.0", "rosbags==0.11.9"];

/// The robot descriptions package (the Panda's URDF, SRDF and STL collision meshes), installed
/// in the same venv by `.ci/run` (and by the tests that need it when absent).
pub const PY_ROBOTS: &str = "example-robot-data==6.0.0";

/// The `share` folder of [`PY_ROBOTS`] in the venv of `py` when `file` (relative to it) is there,
/// the package installed first when absent; `None` after a `SKIPPED test` message when it cannot
/// be had (never in CI: there it is a failure).
pub fn robots_share(py: &std::path::Path, file: &str, test: &str) -> Option<std::path::PathBuf> {
    let find = || {
        let o = std::process::Command::new(py)
            .args([
                "-c",
                "import sysconfig, pathlib; print(pathlib.Path(sysconfig.get_paths()['purelib']) / 'cmeel.prefix' / 'share')",
            ])
            .output()
            .ok()?;
        let share = std::path::PathBuf::from(String::from_utf8_lossy(&o.stdout).trim());
        share.join(file).is_file().then_some(share)
    };
    if let Some(s) = find() {
        return Some(s);
    }
    let _ = std::process::Command::new(py)
        .args(["-m", "pip", "install", "-q", PY_ROBOTS])
        .output();
    let found = find();
    if found.is_none() {
        assert!(
            !rigctl::in_ci(),
            "example-robot-data cannot be installed in the venv"
        );
        eprintln!("SKIPPED {test}: example-robot-data ({file}) not installed");
    }
    found
}

/// The Python interpreter of a virtual environment with [`PY_PACKAGES`] (pinocchio, rosbags),
/// `target/pyenv` (`.ci/run` makes it; made here when absent: `python3 -m venv` and `pip
/// install` into a temporary folder, renamed into place). `None` after a `SKIPPED` message when
/// it cannot be made; with `CI=true` that fails the test instead.
pub fn python_env(test: &str) -> Option<PathBuf> {
    use std::process::Command;
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target"));
    let dir = target.join("pyenv");
    let python = dir.join("bin/python");
    let works = |py: &std::path::Path| {
        Command::new(py)
            .args(["-c", "import pinocchio, rosbags"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if works(&python) {
        return Some(python);
    }
    // the tests of this binary run on several threads: one of them makes the venv
    static MAKING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = MAKING.lock().unwrap_or_else(|e| e.into_inner());
    if works(&python) {
        return Some(python);
    }
    let fail = |msg: String| {
        if rigctl::in_ci() {
            panic!("{test}: {msg}; with CI=true the Python consumers are required");
        }
        eprintln!("SKIPPED {test}: {msg}");
    };
    let _ = std::fs::create_dir_all(&target);
    let tmp = target.join(format!("pyenv.tmp{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let made = Command::new("python3")
        .args(["-m", "venv"])
        .arg(&tmp)
        .output();
    if !made.as_ref().is_ok_and(|o| o.status.success()) {
        fail(format!("python3 -m venv failed: {made:?}"));
        return None;
    }
    let pip = Command::new(tmp.join("bin/python"))
        .args(["-m", "pip", "install", "-q"])
        .args(PY_PACKAGES)
        .output();
    if !pip.as_ref().is_ok_and(|o| o.status.success()) {
        let _ = std::fs::remove_dir_all(&tmp);
        fail(format!(
            "pip install {} failed: {pip:?}",
            PY_PACKAGES.join(" ")
        ));
        return None;
    }
    // Another test may have made it meanwhile: then use that one. (A venv's scripts name their
    // folder, so the renamed one is used through `bin/python`, which does not.)
    if std::fs::rename(&tmp, &dir).is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    if works(&python) {
        Some(python)
    } else {
        fail(format!(
            "{} cannot import pinocchio and rosbags",
            python.display()
        ));
        None
    }
}

/// A helper script of `host/tests/py/`.
pub fn py_script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/py")
        .join(name)
}

/// The chain of the URDF `text` from its root link to `tip_link`, tool point at the tip's origin.
pub fn import_to(
    text: &str,
    tip_link: &str,
) -> Result<rigctl::urdf::Imported, rigctl::urdf::UrdfError> {
    let urdf = rigctl::urdf::Urdf::parse(text, "test.urdf")?;
    rigctl::urdf::import_chain(
        &urdf,
        &rigctl::urdf::ImportOptions {
            base_link: None,
            tip_link,
            tool_mm: [0.0; 3],
        },
    )
}

/// The held-out noise floor of a simulation: the mean length of the noise on its held-out poses
/// (measured minus true position, the measurement drift taken out), mm.
pub fn held_out_noise_mm(out: &rigctl::sim::simulate::SimOutput) -> f64 {
    let drift = out.truth.time_terms();
    out.val
        .iter()
        .map(|p| (p.measured_mm - p.truth_mm - drift.drift_mm(p.t_s)).norm())
        .sum::<f64>()
        / out.val.len().max(1) as f64
}

/// `diagnose` on a simulation's calibration and held-out poses.
pub fn diagnose_sim(
    declared: &rigctl::model::Model,
    out: &rigctl::sim::simulate::SimOutput,
    opts: &rigctl::diagnose::DiagnoseOptions,
) -> rigctl::diagnose::Diagnosis {
    use rigctl::calib::MeasuredSet;
    rigctl::diagnose::diagnose(
        declared,
        &MeasuredSet::from_sim_poses(&out.cal),
        &MeasuredSet::from_sim_poses(&out.val),
        opts,
    )
    .expect("diagnose")
}
