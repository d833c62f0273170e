//! Cartesian paths of the thesis (section 5.5.1): the circle on the 45-degree plane and straight
//! lines, with the tool axis held normal to the path's plane, and a smooth time profile.

use nalgebra::Vector3;

use crate::model::ik::ToolTarget;

/// A path with a tool axis: `at(s)` for `s` in 0..1.
pub trait Path {
    /// The target at path parameter `s` (0 = start, 1 = end).
    fn at(&self, s: f64) -> ToolTarget;
}

/// A circle `centre + r (cos th u + sin th v)`, th = 2 pi s, tool axis `tool_axis` throughout.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// Centre, mm in frame R.
    pub centre_mm: Vector3<f64>,
    /// Radius, mm.
    pub radius_mm: f64,
    /// Unit vector to the start point.
    pub u: Vector3<f64>,
    /// Unit vector to the point a quarter turn later.
    pub v: Vector3<f64>,
    /// Tool axis (unit), normal to the circle's plane.
    pub tool_axis: Vector3<f64>,
}

/// The four points of the thesis's circle (section 5.5.1), mm, read as frame R (see
/// [`super::iso9283`] for why).
pub const THESIS_CIRCLE_POINTS_MM: [[f64; 3]; 4] = [
    [0.0, -370.710_7, 210.0],
    [-100.0, -300.0, 139.289_3],
    [0.0, -229.289_3, 68.578_6],
    [100.0, -300.0, 139.289_3],
];

impl Circle {
    /// The thesis's circle through [`THESIS_CIRCLE_POINTS_MM`], shifted by `offset_mm` (zero for
    /// the thesis's placement). It starts at the point on the positive x side
    /// ([100 -300 139.2893], "starting from the left-most point on the positive X-axis", section
    /// 5.4) and runs through the points in the thesis's listed order, [0 -370.7107 210] next.
    /// The tool axis is the plane's normal pointing down into the plane (the pencil).
    pub fn thesis(offset_mm: Vector3<f64>) -> Self {
        let p = THESIS_CIRCLE_POINTS_MM.map(|c| Vector3::from(c) + offset_mm);
        let centre = (p[0] + p[1] + p[2] + p[3]) / 4.0;
        let radius = (p[3] - centre).norm();
        let u = (p[3] - centre).normalize();
        let v = (p[0] - centre).normalize();
        let mut n = u.cross(&v).normalize();
        if n.z > 0.0 {
            n = -n;
        }
        Self {
            centre_mm: centre,
            radius_mm: radius,
            u,
            v,
            tool_axis: n,
        }
    }
}

impl Path for Circle {
    fn at(&self, s: f64) -> ToolTarget {
        let th = std::f64::consts::TAU * s;
        ToolTarget {
            position_mm: self.centre_mm + (self.u * th.cos() + self.v * th.sin()) * self.radius_mm,
            axis: self.tool_axis,
        }
    }
}

/// A straight segment with a fixed tool axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Start point, mm in frame R.
    pub start_mm: Vector3<f64>,
    /// End point, mm in frame R.
    pub end_mm: Vector3<f64>,
    /// Tool axis (unit).
    pub tool_axis: Vector3<f64>,
}

impl Path for Line {
    fn at(&self, s: f64) -> ToolTarget {
        ToolTarget {
            position_mm: self.start_mm + (self.end_mm - self.start_mm) * s,
            axis: self.tool_axis,
        }
    }
}

/// Quintic rest-to-rest profile `s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5`, `tau = t / T`: zero
/// velocity and acceleration at both ends. Returns `(s, ds/dt, d2s/dt2)` for `t` in 0..T
/// (clamped outside).
pub fn quintic_profile(t_s: f64, duration_s: f64) -> (f64, f64, f64) {
    let tau = (t_s / duration_s).clamp(0.0, 1.0);
    let (t2, t3) = (tau * tau, tau * tau * tau);
    let s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
    let ds = 30.0 * t2 * (1.0 - tau) * (1.0 - tau) / duration_s;
    let dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (duration_s * duration_s);
    (s, ds, dds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_circle_passes_through_its_points_in_order() {
        let c = Circle::thesis(Vector3::zeros());
        assert!((c.radius_mm - 100.0).abs() < 1e-4);
        let order = [3, 0, 1, 2];
        for (k, &i) in order.iter().enumerate() {
            let p = c.at(k as f64 / 4.0).position_mm;
            let want = Vector3::from(THESIS_CIRCLE_POINTS_MM[i]);
            assert!((p - want).norm() < 1e-3, "quarter {k}: {p} vs {want}");
        }
        // normal to the plane, 45 degrees down, pointing in -y (towards the plane from the robot)
        let n = c.tool_axis;
        let h = 0.5f64.sqrt();
        assert!((n - Vector3::new(0.0, -h, -h)).norm() < 1e-6, "{n}");
        assert!(n.dot(&c.u).abs() < 1e-12 && n.dot(&c.v).abs() < 1e-12);
    }

    #[test]
    fn quintic_profile_is_rest_to_rest_and_consistent() {
        let t_end = 4.0;
        assert_eq!(quintic_profile(0.0, t_end), (0.0, 0.0, 0.0));
        let (s1, v1, a1) = quintic_profile(t_end, t_end);
        assert!((s1 - 1.0).abs() < 1e-15 && v1.abs() < 1e-15 && a1.abs() < 1e-15);
        // derivatives against central differences
        let h = 1e-5;
        for t in [0.3, 1.1, 2.0, 3.7] {
            let (sm, vm, _) = quintic_profile(t - h, t_end);
            let (sp, vp, _) = quintic_profile(t + h, t_end);
            let (_, v, a) = quintic_profile(t, t_end);
            assert!(((sp - sm) / (2.0 * h) - v).abs() < 1e-8);
            assert!(((vp - vm) / (2.0 * h) - a).abs() < 1e-8);
        }
        // peak speed of the quintic is 15/8 of the mean
        let (_, vmid, _) = quintic_profile(2.0, t_end);
        assert!((vmid - 15.0 / 8.0 / t_end).abs() < 1e-12);
    }
}
