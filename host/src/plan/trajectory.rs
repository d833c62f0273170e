//! The ordered poses as a ROS `trajectory_msgs/JointTrajectory` in YAML (`rostopic pub` /
//! `ros2 topic pub` and the controllers' action goals take this form): joint names, positions
//! in rad (m for prismatic joints), zero velocities at every point, and `time_from_start` from
//! the largest joint move of each segment at `max_speed_deg_s`, with a dwell at every pose (an
//! arrival and a departure point with the same positions).

use std::fmt::Write as _;

/// Settings of the trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectoryTiming {
    /// Largest joint speed, deg/s (mm/s for prismatic joints).
    pub max_speed_deg_s: f64,
    /// Standstill at each pose, s (0: one point per pose).
    pub dwell_s: f64,
}

/// Default largest joint speed, deg/s.
pub const DEFAULT_MAX_SPEED_DEG_S: f64 = 10.0;
/// Default standstill at each pose, s.
pub const DEFAULT_DWELL_S: f64 = 2.0;

fn stamp(out: &mut String, t_s: f64) {
    let sec = t_s.floor();
    let nanosec = ((t_s - sec) * 1e9).round().min(999_999_999.0);
    let _ = writeln!(
        out,
        "    time_from_start: {{sec: {}, nanosec: {}}}",
        sec as i64, nanosec as i64
    );
}

/// The YAML of a JointTrajectory through `points` (deg; mm where `prismatic`), in order; a
/// point marked `true` is a pose (a standstill of the dwell), `false` a via point.
pub fn joint_trajectory_yaml(
    joint_names: &[String],
    prismatic: &[bool],
    points: &[(Vec<f64>, bool)],
    timing: TrajectoryTiming,
) -> String {
    let si = |k: usize, v: f64| {
        if prismatic.get(k).copied().unwrap_or(false) {
            v * 1e-3
        } else {
            v.to_radians()
        }
    };
    let mut out = String::from("header:\n  frame_id: \"\"\njoint_names:\n");
    for n in joint_names {
        let _ = writeln!(out, "  - \"{}\"", n.replace('"', "\\\""));
    }
    out.push_str("points:\n");
    let zeros = vec!["0.0"; joint_names.len()].join(", ");
    let mut t = 0.0;
    let mut prev: Option<&Vec<f64>> = None;
    for (q, pose) in points {
        if let Some(p) = prev {
            let span = p
                .iter()
                .zip(q)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            t += span / timing.max_speed_deg_s;
        }
        let positions: Vec<String> = q
            .iter()
            .enumerate()
            .map(|(k, v)| format!("{:.9}", si(k, *v)))
            .collect();
        let reps = if *pose && timing.dwell_s > 0.0 { 2 } else { 1 };
        for r in 0..reps {
            if r == 1 {
                t += timing.dwell_s;
            }
            let _ = writeln!(out, "  - positions: [{}]", positions.join(", "));
            let _ = writeln!(out, "    velocities: [{zeros}]");
            stamp(&mut out, t);
        }
        prev = Some(q);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_follow_the_largest_move() {
        let names = vec!["a".to_string(), "b".to_string()];
        let q = vec![(vec![0.0, 0.0], true), (vec![90.0, 10.0], true)];
        let y = joint_trajectory_yaml(
            &names,
            &[false, true],
            &q,
            TrajectoryTiming {
                max_speed_deg_s: 20.0,
                dwell_s: 1.5,
            },
        );
        // 0, dwell 1.5, +90/20 = 6.0, dwell 7.5
        assert!(y.contains("{sec: 1, nanosec: 500000000}"));
        assert!(y.contains("{sec: 6, nanosec: 0}"));
        assert!(y.contains("{sec: 7, nanosec: 500000000}"));
        assert!(y.contains("[1.570796327, 0.010000000]"));
        assert_eq!(y.matches("positions").count(), 4);
    }
}
