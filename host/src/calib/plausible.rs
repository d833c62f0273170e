//! Plausibility of a measured set against its model, before any fit: the similarity transform
//! (scale, rotation, translation; Umeyama 1991) that brings the model's tool points at the joint
//! readings onto the measured points, with the measured point's offset in the last frame free (a
//! marker, a tool not declared), tells whether the two are in the same units and describe the
//! same motion. A calibration absorbs a wrong unit into every length (a model 1000 x short
//! fits points in metres read as millimetres to the noise), so these are refused before it runs:
//!
//! - a best scale outside `1 / MAX_SCALE_RATIO ..= MAX_SCALE_RATIO`: named as the length unit it
//!   looks like (metres, centimetres, inches read as millimetres, or the other way round);
//! - a registration residual over [`MAX_RESIDUAL_SHARE`] of the points' spread: the points do
//!   not follow the model's motion; when they do with the revolute readings in the other angle
//!   unit, that is named with the `--units` that reads them, otherwise the joint order or
//!   another robot's file may be the cause.
//!
//! Partial measurements (`--samples`) have no point to register and are not checked here.

use nalgebra::{Matrix3, Vector3};

use super::error::CalibError;
use super::measured::MeasuredSet;
use crate::model::{Model, Tilt};

/// The largest plausible ratio of the measured points' size to the model's (either way): a
/// real arm is within a few per cent of its nominal geometry, and an undeclared tool or marker
/// offset changes the apparent size by far less than this.
pub const MAX_SCALE_RATIO: f64 = 1.25;

/// The largest plausible RMS registration residual, as a share of the RMS spread of the model's
/// points about their centroid.
pub const MAX_RESIDUAL_SHARE: f64 = 0.2;

/// Fewest poses, and the spread (mm) under which the measured and the model's points both
/// are too small a set to tell a unit.
const MIN_POSES: usize = 4;
const MIN_SPREAD_MM: f64 = 10.0;

/// Length units a scale can point to: (measured / model size, what that looks like, the
/// `--units` length that reads it, or what to do).
const UNIT_RATIOS: [(f64, &str, &str); 6] = [
    (
        1e-3,
        "metres read as millimetres (give --units m,ANGLE)",
        "m",
    ),
    (
        1e-2,
        "centimetres read as millimetres (convert the points to mm)",
        "cm: convert to mm",
    ),
    (
        1.0 / 25.4,
        "inches read as millimetres (convert the points to mm)",
        "in: convert to mm",
    ),
    (
        1e3,
        "micrometres, or a model in metres",
        "um: convert to mm",
    ),
    (
        1e2,
        "hundredths of a millimetre, or a model in centimetres",
        "?",
    ),
    (25.4, "a model in inches", "?"),
];

/// The similarity that brings the model's points onto the measured ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Registration {
    /// Measured size over model size.
    pub scale: f64,
    /// RMS of the measured points about the registered model points, mm.
    pub rms_mm: f64,
    /// RMS distance of the model's points from their centroid, mm.
    pub spread_mm: f64,
    /// Poses used.
    pub n_poses: usize,
    /// Whether both the measured and the model's points span less than [`MIN_SPREAD_MM`]: a set
    /// that cannot tell a unit (or both in the wrong units).
    pub degenerate: bool,
}

/// Registers `model`'s untilted tool points at the readings of `data` onto its first measured
/// point per pose; `None` for partial measurements, too few poses or too small a spread.
pub fn register(model: &Model, data: &MeasuredSet) -> Result<Option<Registration>, CalibError> {
    register_scaled(model, data, 1.0, 1.0)
}

/// [`register`] with every revolute joint reading multiplied by `angle_factor` and every
/// prismatic one by `length_factor` (readings in other units).
fn register_scaled(
    model: &Model,
    data: &MeasuredSet,
    angle_factor: f64,
    length_factor: f64,
) -> Result<Option<Registration>, CalibError> {
    if data.directions.is_some() || data.len() < MIN_POSES {
        return Ok(None);
    }
    let factor: Vec<f64> = model
        .joints()
        .iter()
        .map(|j| {
            if j.prismatic {
                length_factor
            } else {
                angle_factor
            }
        })
        .collect();
    let mut q = Vec::new();
    let mut tool = Vec::with_capacity(data.len());
    for reading in &data.poses.q_deg {
        q.clear();
        q.extend(reading.iter().zip(&factor).map(|(v, f)| v * f));
        let fk = model.fk(&q, Tilt::Off)?;
        tool.push((fk.position_mm, fk.rotation));
    }
    Ok(with_point_offset(&tool, &data.poses.xyz_mm))
}

/// Alternations of the registration and the point offset.
const OFFSET_ROUNDS: usize = 50;

/// The registration of the tool points `tool` (position, last frame's rotation) onto `to`, with
/// the measured point's offset from the tool point in the last frame free (a marker or a tool
/// not declared): alternating least squares, the similarity for a given offset (Umeyama), then
/// the offset for that similarity (linear), from no offset.
fn with_point_offset(
    tool: &[(Vector3<f64>, Matrix3<f64>)],
    to: &[Vector3<f64>],
) -> Option<Registration> {
    let n = tool.len().min(to.len());
    let mut offset = Vector3::zeros();
    let mut best: Option<Registration> = None;
    for _ in 0..OFFSET_ROUNDS {
        let from: Vec<Vector3<f64>> = tool[..n].iter().map(|(p, r)| p + r * offset).collect();
        let (reg, rot, shift) = similarity_transform(&from, &to[..n])?;
        let done = best.is_some_and(|b| b.rms_mm - reg.rms_mm <= 1e-9 * b.rms_mm.max(1e-12));
        best = Some(reg);
        if done || !(reg.scale.is_finite() && reg.scale > 0.0) {
            break;
        }
        // the offset that best maps every tool frame onto its measured point
        let sum: Vector3<f64> = tool[..n]
            .iter()
            .zip(&to[..n])
            .map(|((p, r), m)| r.transpose() * (rot.transpose() * (m - shift) / reg.scale - p))
            .sum();
        offset = sum / n as f64;
    }
    best
}

/// Registration without an offset (the tool points as they are).
#[cfg(test)]
fn similarity(from: &[Vector3<f64>], to: &[Vector3<f64>]) -> Option<Registration> {
    similarity_transform(from, to).map(|(reg, ..)| reg)
}

/// Umeyama's least-squares similarity from `from` onto `to`: the registration, the rotation and
/// the translation.
fn similarity_transform(
    from: &[Vector3<f64>],
    to: &[Vector3<f64>],
) -> Option<(Registration, Matrix3<f64>, Vector3<f64>)> {
    let n = from.len().min(to.len());
    if n < MIN_POSES {
        return None;
    }
    let mean = |v: &[Vector3<f64>]| v[..n].iter().sum::<Vector3<f64>>() / n as f64;
    let (mf, mt) = (mean(from), mean(to));
    let var = |v: &[Vector3<f64>], m: Vector3<f64>| {
        v[..n].iter().map(|p| (p - m).norm_squared()).sum::<f64>() / n as f64
    };
    let (var_from, var_to) = (var(from, mf), var(to, mt));
    let spread_mm = var_from.sqrt();
    // one of the two must span something to be registered at all
    if var_to.is_nan() || var_from.is_nan() || (var_to <= 0.0 && var_from <= 0.0) {
        return None;
    }
    if var_from.is_nan() || var_from <= 0.0 {
        let reg = Registration {
            scale: f64::INFINITY,
            rms_mm: var_to.sqrt(),
            spread_mm,
            n_poses: n,
            degenerate: var_to.sqrt() < MIN_SPREAD_MM,
        };
        return Some((reg, Matrix3::identity(), mt));
    }
    let mut cov = Matrix3::zeros();
    for (a, b) in from[..n].iter().zip(&to[..n]) {
        cov += (b - mt) * (a - mf).transpose();
    }
    cov /= n as f64;
    let svd = cov.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let d = if (u.determinant() * v_t.determinant()) < 0.0 {
        -1.0
    } else {
        1.0
    };
    let s = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d));
    let rot = u * s * v_t;
    let scale = (svd
        .singular_values
        .component_mul(&Vector3::new(1.0, 1.0, d)))
    .sum()
        / var_from;
    let shift = mt - scale * rot * mf;
    let rss: f64 = from[..n]
        .iter()
        .zip(&to[..n])
        .map(|(a, b)| (b - (scale * rot * a + shift)).norm_squared())
        .sum();
    let rms_mm = (rss / n as f64).sqrt();
    let reg = Registration {
        scale,
        rms_mm,
        spread_mm,
        n_poses: n,
        degenerate: spread_mm < MIN_SPREAD_MM && var_to.sqrt() < MIN_SPREAD_MM,
    };
    (scale.is_finite() && rms_mm.is_finite()).then_some((reg, rot, shift))
}

/// What a registration says of the units: `Plausible` (or too small a set to tell), a length
/// unit mixed up, or `None` when no length unit explains it (a scale of no unit, or points that
/// do not follow the motion).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reading {
    Plausible,
    Length(&'static str, &'static str),
}

fn reading(reg: &Registration) -> Option<Reading> {
    if reg.degenerate {
        return Some(Reading::Plausible);
    }
    let s = reg.scale;
    // the residual against the registered model's spread, in the measured points' unit
    if !(s > 0.0 && s.is_finite() && reg.rms_mm <= MAX_RESIDUAL_SHARE * s * reg.spread_mm) {
        return None;
    }
    if (1.0 / MAX_SCALE_RATIO..=MAX_SCALE_RATIO).contains(&s) {
        return Some(Reading::Plausible);
    }
    UNIT_RATIOS
        .iter()
        .filter(|(r, ..)| (s / r).ln().abs() < 0.25)
        .min_by(|a, b| (s / a.0).ln().abs().total_cmp(&(s / b.0).ln().abs()))
        .map(|(_, what, length)| Reading::Length(what, length))
}

/// The sentence of a registration that no unit explains.
fn unexplained(reg: &Registration) -> String {
    format!(
        "the measured points do not follow the model's motion: the best registration of {} \
         poses scales the model by {:.4} and leaves {:.3} mm RMS ({:.0} % of the points' \
         spread); check the units, the joint order and the robot the poses came from",
        reg.n_poses,
        reg.scale,
        reg.rms_mm,
        100.0 * reg.rms_mm / (reg.scale.abs() * reg.spread_mm).max(f64::MIN_POSITIVE)
    )
}

/// Other units the joint readings may be in: (factor on the revolute readings, factor on the
/// prismatic ones, what that is, the `--units` angle that reads it). Prismatic readings are in
/// the points' length unit, so a set in metres read as millimetres has both wrong.
const READING_MIXUPS: [(f64, f64, &str, &str); 5] = [
    (
        R2D,
        1.0,
        "the revolute joint readings are taken as radians",
        "rad",
    ),
    (
        D2R,
        1.0,
        "the revolute joint readings are taken as degrees",
        "deg",
    ),
    (
        1.0,
        1e3,
        "the prismatic joint readings are taken as metres",
        "deg",
    ),
    (
        R2D,
        1e3,
        "the joint readings are taken as radians and metres",
        "rad",
    ),
    (
        D2R,
        1e-3,
        "the joint readings are taken as degrees and millimetres",
        "deg",
    ),
];
const R2D: f64 = 180.0 / std::f64::consts::PI;
const D2R: f64 = std::f64::consts::PI / 180.0;

/// Refuses (`CalibError::Implausible`, exit 2) a set whose registration onto `model` is
/// implausible (see the module documentation), naming what it looks like: a length unit, or
/// revolute readings in the other angle unit when the registration with them converted is
/// plausible; the registration otherwise. The check before every chain identification: a tree's
/// set is refused first ([`MeasuredSet::chain_only`]).
pub fn check_set(
    model: &Model,
    data: &MeasuredSet,
    what: &str,
) -> Result<Option<Registration>, CalibError> {
    data.chain_only(what)?;
    let Some(reg) = register(model, data)? else {
        return Ok(None);
    };
    let scale = format!("{:.4}", reg.scale);
    match reading(&reg) {
        Some(Reading::Plausible) if !reg.degenerate => return Ok(Some(reg)),
        Some(Reading::Plausible) => {}
        Some(Reading::Length(looks, _)) => {
            return Err(CalibError::Implausible(format!(
                "{what}: the measured points are {scale} x the size of the model's (best \
                 registration of {} poses): they look like {looks}",
                reg.n_poses
            )))
        }
        None => {}
    }
    let prismatic = model.joints().iter().any(|j| j.prismatic);
    for (angle_factor, length_factor, mixup, angle) in READING_MIXUPS {
        if length_factor != 1.0 && !prismatic {
            continue;
        }
        let Some(alt) = register_scaled(model, data, angle_factor, length_factor)? else {
            continue;
        };
        let length = match reading(&alt) {
            _ if alt.degenerate => continue,
            Some(Reading::Plausible) => "mm",
            Some(Reading::Length(_, length)) => length,
            None => continue,
        };
        return Err(CalibError::Implausible(format!(
            "{what}: the measured points do not follow the model's motion as the readings are \
             given ({:.3} mm RMS after registration), and do when {mixup} ({:.3} mm RMS, scale \
             {:.4}): give --units {length},{angle}",
            reg.rms_mm, alt.rms_mm, alt.scale
        )));
    }
    if reg.degenerate {
        // too small a set to tell, in any unit
        return Ok(Some(reg));
    }
    Err(CalibError::Implausible(format!(
        "{what}: {}",
        unexplained(&reg)
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    fn cloud() -> Vec<Vector3<f64>> {
        (0..30)
            .map(|k| {
                let t = k as f64;
                Vector3::new(
                    300.0 * (0.7 * t).cos(),
                    250.0 * (1.3 * t).sin(),
                    100.0 + 5.0 * t,
                )
            })
            .collect()
    }

    #[test]
    fn a_similarity_is_recovered_exactly() {
        let from = cloud();
        let rot = Rotation3::from_euler_angles(0.3, -0.2, 1.1);
        let to: Vec<_> = from
            .iter()
            .map(|p| 0.001 * (rot * p) + Vector3::new(0.5, -0.2, 0.1))
            .collect();
        let r = similarity(&from, &to).unwrap();
        assert!((r.scale - 0.001).abs() < 1e-12, "{r:?}");
        assert!(r.rms_mm < 1e-9, "{r:?}");
        assert!(matches!(reading(&r), Some(Reading::Length(w, "m")) if w.contains("metres")));
        let inches: Vec<_> = from.iter().map(|p| p / 25.4).collect();
        let r = similarity(&from, &inches).unwrap();
        assert!(matches!(reading(&r), Some(Reading::Length(w, _)) if w.contains("inches")));
        let same: Vec<_> = from.iter().map(|p| rot * p).collect();
        assert_eq!(
            reading(&similarity(&from, &same).unwrap()),
            Some(Reading::Plausible)
        );
    }

    #[test]
    fn points_that_do_not_follow_the_motion_are_named() {
        let from = cloud();
        let mut to = from.clone();
        to.reverse();
        let r = similarity(&from, &to).unwrap();
        assert_eq!(reading(&r), None, "{r:?}");
        assert!(unexplained(&r).contains("do not follow"));
    }

    #[test]
    fn a_reflection_is_not_taken_for_a_rotation() {
        let from = cloud();
        let mirrored: Vec<_> = from.iter().map(|p| Vector3::new(-p.x, p.y, p.z)).collect();
        let r = similarity(&from, &mirrored).unwrap();
        assert!(r.rms_mm > 1.0, "{r:?}");
    }
}
