//! Recursive Newton-Euler moments (thesis eq. 5.14, Craig 2005 ch. 6), evaluated in frame R.
//!
//! The recursion runs in frame R and the result for joint i is expressed in joint frame i at the
//! end. Internally SI units (m, kg, s, N); the output is kgf.m.
//!
//! Sign convention (MODEL.md): `eta_i` is the moment that the loads beyond joint i exert on it,
//! `sum_j (c_j - o_i) x (m_j g)` in the static case, with `g` pointing down. With motion the
//! d'Alembert loads `-m_j a_j` and `-(I_j alpha_j + w_j x I_j w_j)` are added, so
//! `eta_i = -n_i` where `n_i` is the moment joint i must supply in Craig's recursion.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// Standard gravity, m/s^2 (1 kgf = 9.80665 N).
pub const G_M_S2: f64 = 9.806_65;

/// A rigid part of a link: its mass, centre of gravity and inertia about the COG.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of gravity, mm in frame R.
    pub cog_mm: Vector3<f64>,
    /// Inertia tensor about the COG, kg.mm^2, axes of frame R.
    pub inertia_kg_mm2: Matrix3<f64>,
}

impl Body {
    /// A point mass.
    pub fn point(mass_kg: f64, cog_mm: Vector3<f64>) -> Self {
        Self {
            mass_kg,
            cog_mm,
            inertia_kg_mm2: Matrix3::zeros(),
        }
    }

    /// A uniform slender rod of mass `mass_kg` from `start_mm` to `end_mm` (COG at its middle,
    /// inertia `m L^2 / 12` about every axis normal to the rod, 0 along it).
    pub fn slender_rod(mass_kg: f64, start_mm: Vector3<f64>, end_mm: Vector3<f64>) -> Self {
        let d = end_mm - start_mm;
        let len = d.norm();
        let inertia = if len > 0.0 {
            let e = d / len;
            (Matrix3::identity() - e * e.transpose()) * (mass_kg * len * len / 12.0)
        } else {
            Matrix3::zeros()
        };
        Self {
            mass_kg,
            cog_mm: (start_mm + end_mm) * 0.5,
            inertia_kg_mm2: inertia,
        }
    }
}

/// The state of one moving link for the recursion: its joint frame and the bodies it carries.
#[derive(Debug, Clone, PartialEq)]
pub struct RneaLink {
    /// Origin of joint frame i, mm in frame R.
    pub origin_mm: Vector3<f64>,
    /// Orientation of joint frame i in R (its z axis is joint axis i).
    pub rotation: Rotation3<f64>,
    /// Bodies rigidly attached to link i (the link itself, a payload on the last link...).
    pub bodies: Vec<Body>,
}

/// Joint moments `eta_i` (kgf.m, joint frame i) for joint rates `qd_rad_s` and accelerations
/// `qdd_rad_s2` (one per link, revolute about each joint frame's z axis), with gravity along
/// `gravity_dir` (a unit vector in frame R; `-z` for a level table). The base is at rest.
///
/// The slices must all have `links.len()` entries (shorter rate slices are read as zeros).
pub fn joint_moments_kgfm(
    links: &[RneaLink],
    qd_rad_s: &[f64],
    qdd_rad_s2: &[f64],
    gravity_dir: Vector3<f64>,
) -> Vec<Vector3<f64>> {
    let n = links.len();
    let mm = 1e-3;
    let rate = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
    // Forward pass: angular velocity/acceleration of each link, linear acceleration of its
    // joint origin; the base accelerates upwards with g (gravity as a fictitious acceleration).
    let mut w = Vector3::zeros();
    let mut wd = Vector3::zeros();
    let mut a_origin = -gravity_dir * G_M_S2;
    let mut prev_origin_m = links.first().map_or(Vector3::zeros(), |l| l.origin_mm * mm);
    let mut force = vec![Vector3::zeros(); n]; // total d'Alembert-free force F_i = m a (N)
    let mut torque = vec![Vector3::zeros(); n]; // moment of F_i and N_i about o_i (N.m)
    for (i, link) in links.iter().enumerate() {
        let o = link.origin_mm * mm;
        let z = link.rotation * Vector3::z();
        let r = o - prev_origin_m;
        // the origin of link i moves with link i-1
        a_origin += wd.cross(&r) + w.cross(&w.cross(&r));
        let w_new = w + z * rate(qd_rad_s, i);
        wd = wd + z * rate(qdd_rad_s2, i) + w.cross(&(z * rate(qd_rad_s, i)));
        w = w_new;
        for b in &link.bodies {
            let s = b.cog_mm * mm - o;
            let a_c = a_origin + wd.cross(&s) + w.cross(&w.cross(&s));
            let f = a_c * b.mass_kg;
            let inertia = b.inertia_kg_mm2 * (mm * mm);
            let nn = inertia * wd + w.cross(&(inertia * w));
            force[i] += f;
            torque[i] += nn + s.cross(&f);
        }
        prev_origin_m = o;
    }
    // Backward pass: f_i = F_i + f_{i+1}, n_i = N_i + s_i x F_i + n_{i+1} + r x f_{i+1}.
    let mut out = vec![Vector3::zeros(); n];
    let mut f_next = Vector3::zeros();
    let mut n_next = Vector3::zeros();
    let mut next_origin_m = Vector3::zeros();
    for i in (0..n).rev() {
        let o = links[i].origin_mm * mm;
        let n_i = torque[i] + n_next + (next_origin_m - o).cross(&f_next);
        let f_i = force[i] + f_next;
        out[i] = links[i].rotation.inverse() * (-n_i / G_M_S2);
        f_next = f_i;
        n_next = n_i;
        next_origin_m = o;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn down() -> Vector3<f64> {
        -Vector3::z()
    }

    /// Two links on parallel horizontal axes (a planar double pendulum in the x-z plane).
    fn pendulum(th1: f64, th2: f64, l1_mm: f64) -> Vec<RneaLink> {
        // joint axes along -y so that positive angles lift the links (like Katana joint 2)
        let r1 = Rotation3::from_euler_angles(std::f64::consts::FRAC_PI_2, 0.0, 0.0)
            * Rotation3::from_axis_angle(&Vector3::z_axis(), th1);
        let o2 = r1 * Vector3::new(l1_mm, 0.0, 0.0);
        let r2 = r1 * Rotation3::from_axis_angle(&Vector3::z_axis(), th2);
        vec![
            RneaLink {
                origin_mm: Vector3::zeros(),
                rotation: r1,
                bodies: vec![Body::point(2.0, r1 * Vector3::new(l1_mm, 0.0, 0.0))],
            },
            RneaLink {
                origin_mm: o2,
                rotation: r2,
                bodies: vec![Body::point(1.0, o2 + r2 * Vector3::new(100.0, 0.0, 0.0))],
            },
        ]
    }

    #[test]
    fn static_moment_is_the_gravity_lever() {
        // horizontal links: link 1 mass 2 kg at 200 mm, link 2 mass 1 kg at 300 mm
        let links = pendulum(0.0, 0.0, 200.0);
        let eta = joint_moments_kgfm(&links, &[0.0; 2], &[0.0; 2], down());
        // joint frame z = -y of R: moment of a weight at +x about -y is -(x * m) about z
        assert!(
            (eta[0].z - (-(0.2 * 2.0 + 0.3 * 1.0))).abs() < 1e-12,
            "{}",
            eta[0]
        );
        assert!((eta[1].z - (-0.1)).abs() < 1e-12, "{}", eta[1]);
        assert!(eta[0].x.abs() < 1e-12 && eta[0].y.abs() < 1e-12);
    }

    #[test]
    fn angular_acceleration_of_one_point_mass_gives_m_r2_alpha() {
        // joint 1 alone accelerates, both links hanging straight out; no gravity component about
        // the axis because gravity is set along the axis itself.
        let links = pendulum(0.0, 0.0, 200.0);
        let axis = links[0].rotation * Vector3::z();
        let alpha = 3.0; // rad/s^2
        let eta = joint_moments_kgfm(&links, &[0.0, 0.0], &[alpha, 0.0], axis);
        let inertia = 2.0 * 0.2f64.powi(2) + 1.0 * 0.3f64.powi(2); // kg m^2
        assert!(
            (eta[0].z - (-inertia * alpha / G_M_S2)).abs() < 1e-12,
            "{}",
            eta[0]
        );
        // joint 2 reacts to the acceleration of its own point: m r (r alpha) about its axis
        let want2 = -(1.0 * 0.1 * 0.3 * alpha) / G_M_S2;
        assert!((eta[1].z - want2).abs() < 1e-12, "{}", eta[1]);
    }

    #[test]
    fn centripetal_load_of_a_spinning_rod_is_zero_about_its_axis_and_balanced() {
        // A slender rod spinning about an axis through its middle: no moment about the axis,
        // no moment about the others (symmetric), any rate.
        let rot = Rotation3::identity();
        let rod = Body::slender_rod(
            1.0,
            Vector3::new(-100.0, 0.0, 0.0),
            Vector3::new(100.0, 0.0, 0.0),
        );
        let link = RneaLink {
            origin_mm: Vector3::zeros(),
            rotation: rot,
            bodies: vec![rod],
        };
        let eta = joint_moments_kgfm(std::slice::from_ref(&link), &[5.0], &[0.0], down());
        assert!(eta[0].norm() < 1e-12, "{}", eta[0]);
        // and with angular acceleration: I alpha = m L^2 / 12 alpha
        let eta = joint_moments_kgfm(&[link], &[0.0], &[2.0], down());
        let want = -(1.0 * 0.2f64.powi(2) / 12.0 * 2.0) / G_M_S2;
        assert!((eta[0].z - want).abs() < 1e-12, "{}", eta[0]);
    }
}
