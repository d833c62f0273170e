//! The pose file `rigctl poses` writes (FORMATS.md "Pose files"): `id,t,q1..qN,x,y,z` (or
//! `x1,y1,z1,...` for several markers) and the extra columns `spread_mm` (one-sigma scatter per
//! coordinate of the averaged samples), `n_samples` and `rejected`, with `#` comment lines
//! naming the inputs and what was estimated.

use std::fmt::Write as _;

use super::Capture;

/// The pose file's text; `comments` are written first as `# ` lines.
pub fn pose_csv(c: &Capture, n_joints: usize, n_markers: usize, comments: &[String]) -> String {
    let mut s = String::new();
    for l in comments {
        let _ = writeln!(s, "# {l}");
    }
    s.push_str("id,t");
    for j in 1..=n_joints {
        let _ = write!(s, ",q{j}");
    }
    if n_markers == 1 {
        s.push_str(",x,y,z");
    } else {
        for m in 1..=n_markers {
            let _ = write!(s, ",x{m},y{m},z{m}");
        }
    }
    s.push_str(",spread_mm,n_samples,rejected\n");
    for p in &c.poses {
        let _ = write!(s, "{},{:.4}", p.id, p.t_s);
        for q in &p.q {
            let _ = write!(s, ",{q:.9}");
        }
        for pt in &p.points_mm {
            let _ = write!(s, ",{:.6},{:.6},{:.6}", pt[0], pt[1], pt[2]);
        }
        let _ = writeln!(s, ",{:.6},{},{}", p.spread_mm, p.n_samples, p.rejected);
    }
    s
}
