//! The independent generator of the tree tests: a humanoid upper body (a torso of 2 joints, two
//! 6-joint arms, link masses) with this file's own kinematics and statics (not the product's),
//! joints compliant about their axes (`q + c tau`, `tau` the torque of every mass beyond the
//! joint at the readings, both arms on the torso) and across them (`Rx(c m_x) Ry(c m_y)` right
//! after the joint's rotation, `m` the moment of the unbent body at the turned joints), the
//! hands measured with noise; its tree model file, pose files and `calibrate` runs.

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::Rng;
use rand_distr::{Distribution, Normal};

use crate::common::spawn::{output, text};

/// One segment of the body: `Rx(al) Tx(a) Tz(d) Rz(q + off)` from its parent's joint frame.
#[derive(Clone)]
pub(crate) struct Seg {
    pub(crate) name: String,
    pub(crate) parent: Option<usize>,
    pub(crate) al_deg: f64,
    pub(crate) a_mm: f64,
    pub(crate) d_mm: f64,
    pub(crate) off_deg: f64,
    /// (kg, centre of mass in the joint frame, mm)
    pub(crate) mass: (f64, [f64; 3]),
    /// deg per kgf.m about the axis
    pub(crate) compliance: f64,
    /// deg per kgf.m across the axis: `Rx(c m_x) Ry(c m_y)` right after the joint's rotation,
    /// `m` the gravity moment in the joint frame (the unbent body at the deflected joints)
    pub(crate) lateral: f64,
}

#[derive(Clone)]
pub(crate) struct Body {
    pub(crate) segs: Vec<Seg>,
    /// (tip name, last joint, tool point in its frame, mm)
    pub(crate) tips: Vec<(String, usize, [f64; 3])>,
}

fn rot_x(deg: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::x_axis(), deg.to_radians()).matrix()
}

fn rot_y(deg: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::y_axis(), deg.to_radians()).matrix()
}

fn rot_z(deg: f64) -> Matrix3<f64> {
    *Rotation3::from_axis_angle(&Vector3::z_axis(), deg.to_radians()).matrix()
}

impl Body {
    pub(crate) fn nominal() -> Body {
        let seg = |name: &str, parent, al, a, d, kg, com: [f64; 3]| Seg {
            name: name.into(),
            parent,
            al_deg: al,
            a_mm: a,
            d_mm: d,
            off_deg: 0.0,
            mass: (kg, com),
            compliance: 0.0,
            lateral: 0.0,
        };
        // torso: t1 yaw about the vertical, t2 pitch (horizontal axis)
        let mut segs = vec![
            seg("t1", None, 0.0, 0.0, 400.0, 12.0, [0.0, 0.0, 80.0]),
            seg("t2", Some(0), -90.0, 40.0, 0.0, 10.0, [150.0, 0.0, 0.0]),
        ];
        let mut tips = Vec::new();
        for (side, sign) in [("l", 1.0), ("r", -1.0)] {
            let base = segs.len();
            let rows = [
                (90.0, 320.0, sign * 200.0, 3.0, [0.0, 0.0, sign * 40.0]),
                (-90.0, 0.0, 60.0, 2.5, [60.0, 0.0, 0.0]),
                (90.0, 20.0, 260.0, 2.0, [0.0, 0.0, -120.0]),
                (-90.0, -20.0, 0.0, 1.5, [0.0, 60.0, 0.0]),
                (90.0, 0.0, 240.0, 1.0, [0.0, 0.0, -100.0]),
                (-90.0, 0.0, 0.0, 0.5, [0.0, 0.0, 20.0]),
            ];
            for (k, (al, a, d, kg, com)) in rows.into_iter().enumerate() {
                let parent = if k == 0 { 1 } else { base + k - 1 };
                segs.push(seg(
                    &format!("{side}{}", k + 1),
                    Some(parent),
                    al,
                    a,
                    d,
                    kg,
                    com,
                ));
            }
            let tool = [sign * 15.0, 10.0, 110.0];
            tips.push((format!("{side}_hand"), segs.len() - 1, tool));
        }
        Body { segs, tips }
    }

    /// Joint frames (rotation, origin mm) in R at joint angles `q` (deg), each joint bent by
    /// `bends` (deg about its frame's x, then y; empty: unbent).
    fn frames(&self, q: &[f64], bends: &[(f64, f64)]) -> Vec<(Matrix3<f64>, Vector3<f64>)> {
        let mut out: Vec<(Matrix3<f64>, Vector3<f64>)> = Vec::new();
        for (i, (s, q)) in self.segs.iter().zip(q).enumerate() {
            let (r0, p0) = s
                .parent
                .map_or((Matrix3::identity(), Vector3::zeros()), |p| out[p]);
            let r = r0 * rot_x(s.al_deg);
            let p = p0 + r * Vector3::new(s.a_mm, 0.0, s.d_mm);
            let bend = bends
                .get(i)
                .map_or(Matrix3::identity(), |(a, b)| rot_x(*a) * rot_y(*b));
            out.push((r * rot_z(q + s.off_deg) * bend, p));
        }
        out
    }

    /// The joint frames' origins (mm, R) of the unbent body at the readings `q`.
    pub(crate) fn origins_mm(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        self.frames(q, &[]).into_iter().map(|(_, o)| o).collect()
    }

    /// The hands' points (mm, R) of the rigid body at the readings `q`.
    pub(crate) fn rigid_hands_mm(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        let f = self.frames(q, &[]);
        self.tips
            .iter()
            .map(|(_, j, tool)| f[*j].0 * Vector3::from(*tool) + f[*j].1)
            .collect()
    }

    /// Gravity torque about every joint's axis (kgf.m): the z component of
    /// [`Body::moments_kgfm`].
    pub(crate) fn torques_kgfm(&self, q: &[f64]) -> Vec<f64> {
        self.moments_kgfm(q).iter().map(|m| m.z).collect()
    }

    /// Gravity moment at every joint (kgf.m, its frame, the unbent body): the moment about its
    /// origin of the weight (1 kgf per kg, -z of R) of every segment whose chain passes through
    /// it. Brute force over (joint, segment) pairs.
    pub(crate) fn moments_kgfm(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        let f = self.frames(q, &[]);
        (0..self.segs.len())
            .map(|i| {
                let (ri, oi) = f[i];
                let mut m = Vector3::zeros();
                for (j, s) in self.segs.iter().enumerate() {
                    let mut at = Some(j);
                    while let Some(k) = at.filter(|&k| k != i) {
                        at = self.segs[k].parent;
                    }
                    if at.is_none() {
                        continue;
                    }
                    let (rj, oj) = f[j];
                    let c = rj * Vector3::from(s.mass.1) + oj;
                    m += ((c - oi) * 1e-3).cross(&Vector3::new(0.0, 0.0, -s.mass.0));
                }
                ri.transpose() * m
            })
            .collect()
    }

    /// The hands' points (mm) at the readings `q`: the joints turned by their compliances
    /// under the torques at the readings, then bent across their axes by the moments of the
    /// unbent body at the turned joints.
    pub(crate) fn hands_mm(&self, q: &[f64]) -> Vec<Vector3<f64>> {
        let tau = self.torques_kgfm(q);
        let q_eff: Vec<f64> = q
            .iter()
            .zip(&self.segs)
            .zip(&tau)
            .map(|((q, s), t)| q + s.compliance * t)
            .collect();
        let bends: Vec<(f64, f64)> = self
            .moments_kgfm(&q_eff)
            .iter()
            .zip(&self.segs)
            .map(|(m, s)| (s.lateral * m.x, s.lateral * m.y))
            .collect();
        let f = self.frames(&q_eff, &bends);
        self.tips
            .iter()
            .map(|(_, j, tool)| f[*j].0 * Vector3::from(*tool) + f[*j].1)
            .collect()
    }

    /// The body as a tree model file (docs/model-files.md "Tree models").
    pub(crate) fn model_toml(&self) -> String {
        self.model_file(true)
    }

    /// The body as a tree model file, with its link masses or (`masses` false) without.
    pub(crate) fn model_file(&self, masses: bool) -> String {
        let mut s = String::from("name = \"upper_body\"\n");
        for (i, g) in self.segs.iter().enumerate() {
            let n = &g.name;
            for (op, name, v) in [
                ("rx", format!("al_{n}"), g.al_deg),
                ("tx", format!("a_{n}"), g.a_mm),
                ("tz", format!("d_{n}"), g.d_mm),
            ] {
                s += &format!("\n[[chain]]\nop = \"{op}\"\nname = \"{name}\"\nvalue = {v:?}\n");
            }
            s += &format!(
                "\n[[chain]]\nop = \"rz\"\njoint = {}\nname = \"off_{n}\"\nvalue = {:?}\n",
                i + 1,
                g.off_deg
            );
        }
        for g in &self.segs {
            s += &format!(
                "\n[[joint]]\nname = \"{}\"\nparent = {}\nmin = -170.0\nmax = 170.0\n",
                g.name,
                g.parent.map_or(0, |p| p + 1)
            );
        }
        for (i, g) in self.segs.iter().enumerate().filter(|_| masses) {
            let [x, y, z] = g.mass.1;
            s += &format!(
                "\n[[mass]]\njoint = {}\nkg = {:?}\ncom_mm = [{x:?}, {y:?}, {z:?}]\n",
                i + 1,
                g.mass.0
            );
        }
        for (name, j, [x, y, z]) in &self.tips {
            s += &format!(
                "\n[[tip]]\nname = \"{name}\"\njoint = {}\ntool_mm = [{x:?}, {y:?}, {z:?}]\n",
                j + 1
            );
        }
        s
    }
}

/// Poses over the joints' ranges, the hands measured with noise: (joints, points per tip).
pub(crate) fn measure(
    body: &Body,
    n: usize,
    noise_mm: f64,
    rng: &mut rand::rngs::StdRng,
) -> Vec<(Vec<f64>, Vec<Vector3<f64>>)> {
    let noise = Normal::new(0.0, noise_mm).unwrap();
    (0..n)
        .map(|_| {
            let q: Vec<f64> = body
                .segs
                .iter()
                .map(|_| rng.gen_range(-110.0..110.0))
                .collect();
            let hands = body
                .hands_mm(&q)
                .into_iter()
                .map(|p| p.map(|v| v + noise.sample(rng)))
                .collect();
            (q, hands)
        })
        .collect()
}

/// A tree pose file: the joints by name, `x<k>,y<k>,z<k>` per tip (points scaled by `unit`).
pub(crate) fn tree_csv(body: &Body, poses: &[(Vec<f64>, Vec<Vector3<f64>>)], unit: f64) -> String {
    let mut header: Vec<String> = body.segs.iter().map(|s| s.name.clone()).collect();
    for k in 1..=body.tips.len() {
        header.extend([format!("x{k}"), format!("y{k}"), format!("z{k}")]);
    }
    let mut text = header.join(",") + "\n";
    for (q, hands) in poses {
        let mut cells: Vec<String> = q.iter().map(|v| format!("{v:e}")).collect();
        for p in hands {
            cells.extend(p.iter().map(|v| format!("{:e}", v * unit)));
        }
        text += &(cells.join(",") + "\n");
    }
    text
}

/// A chain pose file of tip `tip`: `q1..qn` along its path, `x,y,z`.
pub(crate) fn chain_csv(
    body: &Body,
    tip: usize,
    poses: &[(Vec<f64>, Vec<Vector3<f64>>)],
) -> String {
    let mut path = Vec::new();
    let mut at = Some(body.tips[tip].1);
    while let Some(j) = at {
        path.push(j);
        at = body.segs[j].parent;
    }
    path.reverse();
    let mut header: Vec<String> = (1..=path.len()).map(|k| format!("q{k}")).collect();
    header.extend(["x", "y", "z"].map(String::from));
    let mut text = header.join(",") + "\n";
    for (q, hands) in poses {
        let mut cells: Vec<String> = path.iter().map(|&j| format!("{:e}", q[j])).collect();
        cells.extend(hands[tip].iter().map(|v| format!("{v:e}")));
        text += &(cells.join(",") + "\n");
    }
    text
}

/// Runs `calibrate` and returns the held-out RMS per coordinate after the fit (mm) and stdout:
/// `validation rms A -> B mm` (a tree, a chain's standard fit) or `validation RMS of point 1: B mm`
/// (a chain's fit with compliance).
pub(crate) fn calibrate(args: &[&str]) -> (f64, String) {
    let mut all = vec!["calibrate"];
    all.extend(args);
    let run = output(&all);
    let stdout = text(&run.stdout);
    assert!(
        run.status.success(),
        "rigctl {}: {stdout}\n{}",
        all.join(" "),
        text(&run.stderr)
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("validation rms") || l.starts_with("validation RMS of point 1:"))
        .unwrap_or_else(|| panic!("a validation line in {stdout}"));
    let rms = line
        .rsplit([' ', '>'])
        .nth(1)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("a number in {line}"));
    (rms, stdout)
}
