//! Built-in robots: the Katana 450 of the thesis (MODEL.md) and the UR5 of the laser-tracker data.

use super::builder::ModelBuilder;
use super::chain::{Axis, Model, Motion, TiltValues};
use super::error::ModelError;

/// Tool length d5 of the bare Katana 450 (mm).
pub const KATANA_TOOL_MM: f64 = 200.0;
/// Tool length d5 with the pencil holder of thesis chapter 5 (mm, table 5.1 "200 + 130").
pub const KATANA_PENCIL_TOOL_MM: f64 = 330.0;

/// The 12 geometric parameters the thesis identifies (eq. 5.11).
pub const KATANA_GEOMETRIC_PARAMS: [&str; 12] = [
    "dth1", "dth2", "dth3", "dth4", "dth5", "al2", "al3", "al4", "al5", "be3", "be4", "be5",
];

/// Katana joint limits, table 3.1 (deg).
const KATANA_LIMITS_DEG: [[f64; 2]; 5] = [
    [-169.5, 169.5],
    [-30.0, 102.0],
    [-122.5, 122.5],
    [-112.0, 112.0],
    [-168.0, 168.0],
];

/// Katana tilting values, table 5.2: clearance (deg), backlash (deg), stiffness (kgf.m/deg).
const KATANA_TILT: [(f64, f64, f64); 5] = [
    (0.022, 0.063, 122.0),
    (0.024, 0.061, 90.0),
    (0.017, 0.057, 75.0),
    (0.015, 0.046, 78.0),
    (0.018, 0.051, 80.0),
];

/// The SMR centre of the UR5 laser-tracker data in the flange frame (mm), see
/// shared/data/real/ur5_laser_tracker/README.md. Not part of the `ur5` preset (whose tool point
/// is the flange); apply with `--set tool_dy=0.07 --set tool_dz=31.0`.
pub const UR5_SMR_TOOL_MM: [f64; 3] = [0.0, 0.07, 31.0];

/// The Katana 450 chain of MODEL.md with tool length `tool_mm` (d5):
///
/// `Tx(base_x) Ty(base_y) Tz(base_z) Rx(base_rx) Ry(base_ry) . Tx(mount_x=55) Ty(mount_y=55)
/// Tz(mount_z=201.5) . Rz(q1+dth1) | . Rx(al2) Rz(q2+dth2) | Tx(a2) . Rx(al3) Ry(be3) Rz(q3+dth3) |
/// Tx(a3) . Rz(q4+dth4) | Ry(be4) Rx(al4) Tz(d4) . Rz(q5+dth5) | Ry(be5) Rx(al5) Tz(d5) .
/// Tx(tool_dx) Ty(tool_dy) Tz(tool_dz)`
///
/// with limits (table 3.1), link masses (table 4.2) and tilting values (table 5.2).
pub fn katana450(tool_mm: f64) -> Result<Model, ModelError> {
    use Axis::{X, Y, Z};
    use Motion::{Rot, Trans};
    let tilt = |j: usize| {
        let (c, b, k) = KATANA_TILT[j];
        Some(TiltValues {
            clearance_deg: c,
            backlash_deg: b,
            stiffness_kgfm_per_deg: k,
        })
    };
    let mut b = ModelBuilder::new("katana450");
    b.constant(Trans, X, "mount_x", 55.0)?;
    b.constant(Trans, Y, "mount_y", 55.0)?;
    b.constant(Trans, Z, "mount_z", 201.5)?;
    b.joint(false, "dth1", 0.0, KATANA_LIMITS_DEG[0], tilt(0))?;
    b.constant(Rot, X, "al2", 90.0)?;
    b.joint(false, "dth2", 0.0, KATANA_LIMITS_DEG[1], tilt(1))?;
    b.constant(Trans, X, "a2", 190.0)?;
    b.constant(Rot, X, "al3", 0.0)?;
    b.constant(Rot, Y, "be3", 0.0)?;
    b.joint(false, "dth3", 0.0, KATANA_LIMITS_DEG[2], tilt(2))?;
    b.constant(Trans, X, "a3", 139.0)?;
    b.joint(false, "dth4", 0.0, KATANA_LIMITS_DEG[3], tilt(3))?;
    b.constant(Rot, Y, "be4", 0.0)?;
    b.constant(Rot, X, "al4", -90.0)?;
    b.constant(Trans, Z, "d4", 147.3)?;
    b.joint(false, "dth5", 0.0, KATANA_LIMITS_DEG[4], tilt(4))?;
    b.constant(Rot, Y, "be5", 0.0)?;
    b.constant(Rot, X, "al5", 90.0)?;
    b.constant(Trans, Z, "d5", tool_mm)?;
    // Table 4.2: link 2 and 3 along +x of their joint frame, 4 and 5 along +z after Ry.Rx.
    b.mass(2, 0, 1.03, [100.0, 0.0, 0.0])?;
    b.mass(3, 0, 0.90, [104.0, 0.0, 0.0])?;
    b.mass(4, 2, 1.00, [0.0, 0.0, 80.0])?;
    b.mass(5, 2, 0.80, [0.0, 0.0, 70.0])?;
    b.build()
}

/// The UR5 (standard DH, Universal Robots' published table): row i is
/// `Rz(qi + dthi) | Tz(di) Tx(ai) Rx(ali)` with
/// `a = 0, -425, -392.25, 0, 0, 0` mm, `al = 90, 0, 0, 90, -90, 0` deg,
/// `d = 89.159, 0, 0, 109.15, 94.65, 82.3` mm, limits +-360 deg. The tool point is the flange
/// (`tool_d* = 0`, see [`UR5_SMR_TOOL_MM`]); the published link masses, no tilting data.
pub fn ur5() -> Result<Model, ModelError> {
    const A_MM: [f64; 6] = [0.0, -425.0, -392.25, 0.0, 0.0, 0.0];
    const AL_DEG: [f64; 6] = [90.0, 0.0, 0.0, 90.0, -90.0, 0.0];
    const D_MM: [f64; 6] = [89.159, 0.0, 0.0, 109.15, 94.65, 82.3];
    let mut b = ModelBuilder::new("ur5");
    for i in 0..6 {
        b.dh_row(
            i + 1,
            0.0,
            D_MM[i],
            A_MM[i],
            AL_DEG[i],
            [-360.0, 360.0],
            None,
        )?;
    }
    // DH row i is Rz Tz Tx Rx: DH frame i is 3 elements past the joint's element
    for (j, (kg, com)) in UR5_LINK_MASS_KG.iter().zip(UR5_LINK_COM_MM).enumerate() {
        b.mass(j + 1, 3, *kg, com)?;
    }
    b.build()
}

/// UR5 (CB3) link masses, kg, published by Universal Robots ("Parameters for calculations of
/// kinematics and dynamics", support article 45257).
pub const UR5_LINK_MASS_KG: [f64; 6] = [3.7, 8.393, 2.33, 1.219, 1.219, 0.1879];
/// UR5 (CB3) centres of mass in DH frame i (after row i), mm (same source).
pub const UR5_LINK_COM_MM: [[f64; 3]; 6] = [
    [0.0, -25.61, 1.93],
    [212.5, 0.0, 113.36],
    [150.0, 0.0, 26.5],
    [0.0, -1.8, 16.34],
    [0.0, 1.8, 16.34],
    [0.0, 0.0, -1.159],
];

/// A preset by name: `katana450` (with `tool_mm`, default 200) or `ur5` (`tool_mm` ignored).
pub fn preset(name: &str, tool_mm: Option<f64>) -> Result<Model, ModelError> {
    match name {
        "katana450" => katana450(tool_mm.unwrap_or(KATANA_TOOL_MM)),
        "ur5" => ur5(),
        _ => Err(ModelError::UnknownPreset {
            name: name.to_string(),
        }),
    }
}

impl ModelBuilder {
    /// Standard DH row of joint `i` (1-based, the next joint): `Rz(qi + dthi) Tz(di) Tx(ai)
    /// Rx(ali)` with parameters `dth<i>, d<i>, a<i>, al<i>`; joint frame i is right after Rz
    /// (masses: `after` 0..3 = after Rz, Tz, Tx, Rx).
    #[allow(clippy::too_many_arguments)]
    pub fn dh_row(
        &mut self,
        i: usize,
        theta_deg: f64,
        d_mm: f64,
        a_mm: f64,
        alpha_deg: f64,
        limits: [f64; 2],
        tilt: Option<TiltValues>,
    ) -> Result<&mut Self, ModelError> {
        self.check_row_joint(i)?;
        self.joint(false, &format!("dth{i}"), theta_deg, limits, tilt)?;
        self.constant(Motion::Trans, Axis::Z, &format!("d{i}"), d_mm)?;
        self.constant(Motion::Trans, Axis::X, &format!("a{i}"), a_mm)?;
        self.constant(Motion::Rot, Axis::X, &format!("al{i}"), alpha_deg)
    }

    /// Modified DH row (Craig) of joint `i`: `Rx(ali) Tx(ai) Rz(qi + dthi) Tz(di)`, and with
    /// `beta_deg` = Some (Hayati's parallel-axis form) `Rx(ali) Tx(ai) Ry(bei) Rz(qi + dthi)
    /// Tz(di)`. Joint frame i is right after Rz (masses: `after` 0 = after Rz, 1 = after Tz).
    #[allow(clippy::too_many_arguments)]
    pub fn mdh_row(
        &mut self,
        i: usize,
        alpha_deg: f64,
        a_mm: f64,
        beta_deg: Option<f64>,
        theta_deg: f64,
        d_mm: f64,
        limits: [f64; 2],
        tilt: Option<TiltValues>,
    ) -> Result<&mut Self, ModelError> {
        self.check_row_joint(i)?;
        self.constant(Motion::Rot, Axis::X, &format!("al{i}"), alpha_deg)?;
        self.constant(Motion::Trans, Axis::X, &format!("a{i}"), a_mm)?;
        if let Some(be) = beta_deg {
            self.constant(Motion::Rot, Axis::Y, &format!("be{i}"), be)?;
        }
        self.joint(false, &format!("dth{i}"), theta_deg, limits, tilt)?;
        self.constant(Motion::Trans, Axis::Z, &format!("d{i}"), d_mm)
    }

    fn check_row_joint(&self, i: usize) -> Result<(), ModelError> {
        if i != self.n_joints() + 1 {
            return Err(ModelError::Invalid(format!(
                "row for joint {i}: joints must come in order, expected joint {}",
                self.n_joints() + 1
            )));
        }
        Ok(())
    }
}

/// How a command picks its model (FORMATS.md): a preset (`--robot`, default `katana450`) or a
/// model file (`--model`), then `--tool-mm` (Katana preset only: d5) and `--set NAME=VALUE`
/// overrides, applied in order.
#[derive(Debug, Clone, Copy, Default)]
pub struct ModelChoice<'a> {
    /// `--robot NAME`.
    pub robot: Option<&'a str>,
    /// `--model FILE.toml`.
    pub model_file: Option<&'a std::path::Path>,
    /// `--tool-mm L`.
    pub tool_mm: Option<f64>,
    /// `--set NAME=VALUE` arguments.
    pub sets: &'a [String],
}

/// Parses one `NAME=VALUE` override.
pub fn parse_set(arg: &str) -> Result<(&str, f64), ModelError> {
    let bad = || ModelError::BadSet {
        arg: arg.to_string(),
    };
    let (name, value) = arg.split_once('=').ok_or_else(bad)?;
    let value: f64 = value.trim().parse().map_err(|_| bad())?;
    if !value.is_finite() {
        return Err(bad());
    }
    Ok((name.trim(), value))
}

/// Builds the model a command asked for (see [`ModelChoice`]).
pub fn choose_model(choice: &ModelChoice<'_>) -> Result<Model, ModelError> {
    let mut model = match (choice.robot, choice.model_file) {
        (Some(_), Some(_)) => {
            return Err(ModelError::Usage(
                "give --robot or --model, not both".into(),
            ))
        }
        (_, Some(path)) => {
            if choice.tool_mm.is_some() {
                return Err(ModelError::Usage(
                    "--tool-mm applies to the katana450 preset; with --model use --set d5=L".into(),
                ));
            }
            Model::from_file(path)?
        }
        (robot, None) => {
            let name = robot.unwrap_or("katana450");
            if name != "katana450" && choice.tool_mm.is_some() {
                return Err(ModelError::Usage(format!(
                    "--tool-mm applies to the katana450 preset, not {name}"
                )));
            }
            if let Some(l) = choice.tool_mm {
                if !l.is_finite() {
                    return Err(ModelError::Usage(format!(
                        "--tool-mm {l}: not a finite length"
                    )));
                }
            }
            preset(name, choice.tool_mm)?
        }
    };
    for arg in choice.sets {
        let (name, value) = parse_set(arg)?;
        model.set_param(name, value)?;
    }
    Ok(model)
}
