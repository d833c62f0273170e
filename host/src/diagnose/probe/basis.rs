//! The probe's smooth functions of the joint angles and of time: a constant, additive
//! one-variable terms and pairwise interaction terms, each a small block of trigonometric
//! functions that can follow a periodic dependence over the whole range of a joint.
//!
//! **Variables** ([`Var`]): every joint that moves, and the time `t` when the poses carry times
//! that differ. Variable `v` observed over `[lo, hi]`:
//! * a joint whose observed range is at least [`PERIODIC_MIN_RANGE_DEG`] gets its own Fourier
//!   terms `sin(k q), cos(k q)` (`q` in rad), `k = 1 ..= MAIN_HARMONICS`: the natural basis of a
//!   dependence that repeats with the turn of the joint;
//! * a joint with a narrower range, and the time, get the half-range cosine series
//!   `cos(k pi s)`, `s = (v - lo) / (hi - lo)` clamped to `[0, 1]` (a prediction outside the
//!   observed range is held at its edge), `k = 1 ..= 2 MAIN_HARMONICS`: complete on the
//!   interval, with no periodicity forced on its ends.
//!
//! Both give `2 MAIN_HARMONICS` functions per variable, ordered by frequency. A main term `q<i>`
//! (or `t`) uses all of them; a pair term `q<i>:q<j>` (or `t:q<j>`) the products of the first
//! `2 PAIR_HARMONICS` of each (the interaction alone: the main effects are separate terms). Every
//! basis function is vector-valued through its three coefficients (x, y, z of frame R, mm).

use std::f64::consts::PI;

use serde::Serialize;

use crate::calib::MeasuredSet;

/// Harmonics of a one-variable term (`2 x` this many functions).
pub const MAIN_HARMONICS: usize = 4;
/// Harmonics of each variable of a pair term (`(2 x` this`)^2` products).
pub const PAIR_HARMONICS: usize = 2;
/// A variable whose observed range is narrower than this (deg, s) gets no term.
pub const MIN_RANGE: f64 = 1e-3;
/// A joint observed over at least this range (deg) gets its own Fourier terms; a narrower one the
/// cosine series over its range.
pub const PERIODIC_MIN_RANGE_DEG: f64 = 270.0;

/// A variable of the probe: a joint (0-based) or the time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Var {
    /// Joint angle `q<j+1>` (deg).
    Joint(usize),
    /// The pose's time `t` (s).
    Time,
}

impl Var {
    /// `q2` or `t`.
    pub fn name(&self) -> String {
        match self {
            Var::Joint(j) => format!("q{}", j + 1),
            Var::Time => "t".to_string(),
        }
    }
}

/// One term of the probe's additive model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Term {
    /// A constant offset.
    Const,
    /// A smooth function of one variable.
    Main(Var),
    /// A smooth interaction of two variables (joints `i < j`; the time comes first).
    Pair(Var, Var),
}

impl Term {
    /// The FORMATS.md name: `q2`, `t`, `q1:q3`, `t:q2` (1-based joints); `const` for the offset.
    pub fn name(&self) -> String {
        match self {
            Term::Const => "const".to_string(),
            Term::Main(v) => v.name(),
            Term::Pair(a, b) => format!("{}:{}", a.name(), b.name()),
        }
    }

    /// The words of the sentence: `q2`, `q1 with q3`, `t with q2`.
    pub fn phrase(&self) -> String {
        match self {
            Term::Const => "a constant offset".to_string(),
            Term::Main(v) => v.name(),
            Term::Pair(a, b) => format!("{} with {}", a.name(), b.name()),
        }
    }

    /// Number of scalar basis functions.
    pub fn n_basis(&self) -> usize {
        match self {
            Term::Const => 1,
            Term::Main(_) => 2 * MAIN_HARMONICS,
            Term::Pair(..) => 4 * PAIR_HARMONICS * PAIR_HARMONICS,
        }
    }

    /// The variables it involves.
    pub fn vars(&self) -> Vec<Var> {
        match *self {
            Term::Const => Vec::new(),
            Term::Main(v) => vec![v],
            Term::Pair(a, b) => vec![a, b],
        }
    }
}

/// How one variable is expanded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Axis {
    /// The variable.
    pub var: Var,
    /// Observed range (deg for a joint, s for the time).
    pub lo: f64,
    /// Upper end of the observed range.
    pub hi: f64,
    /// Whether it gets its own Fourier terms (a joint over a wide range) rather than the cosine
    /// series over its range.
    pub periodic: bool,
}

impl Axis {
    /// Its `count` first functions at value `v` (ordered by frequency).
    fn values(&self, v: f64, count: usize, out: &mut Vec<f64>) {
        if self.periodic {
            let x = if v.is_finite() { v.to_radians() } else { 0.0 };
            for n in 0..count {
                let k = (n / 2 + 1) as f64;
                out.push(if n % 2 == 0 {
                    (k * x).sin()
                } else {
                    (k * x).cos()
                });
            }
        } else {
            let span = self.hi - self.lo;
            let s = if span >= MIN_RANGE && v.is_finite() {
                ((v - self.lo) / span).clamp(0.0, 1.0)
            } else {
                0.5
            };
            for n in 0..count {
                out.push(((n + 1) as f64 * PI * s).cos());
            }
        }
    }

    /// Names of its `count` first functions (`sin(2 q3)`, `cos(3 pi s_t)`).
    fn names(&self, count: usize) -> Vec<String> {
        let v = self.var.name();
        (0..count)
            .map(|n| {
                if self.periodic {
                    let k = n / 2 + 1;
                    format!("{}({k} {v})", if n % 2 == 0 { "sin" } else { "cos" })
                } else {
                    format!("cos({} pi s_{v})", n + 1)
                }
            })
            .collect()
    }
}

/// The variables of the probe and their ranges: joints first, then the time.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Domain {
    /// Number of joints of the poses (the time, when present, is value `n_joints` of a point).
    pub n_joints: usize,
    /// The variables that move, with how they are expanded.
    pub axes: Vec<Axis>,
}

impl Domain {
    /// The domain of the poses `points` ([`point`]); `with_time`: the last value of every point
    /// is the time.
    pub fn of(points: &[Vec<f64>], with_time: bool) -> Self {
        let width = points.first().map_or(0, Vec::len);
        let n_joints = if with_time {
            width.saturating_sub(1)
        } else {
            width
        };
        let mut axes = Vec::new();
        for i in 0..width {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for p in points {
                if let Some(v) = p.get(i).copied().filter(|v| v.is_finite()) {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            if !(lo.is_finite() && hi - lo >= MIN_RANGE) {
                continue;
            }
            let var = if i < n_joints {
                Var::Joint(i)
            } else {
                Var::Time
            };
            axes.push(Axis {
                var,
                lo,
                hi,
                periodic: var != Var::Time && hi - lo >= PERIODIC_MIN_RANGE_DEG,
            });
        }
        Self { n_joints, axes }
    }

    /// Whether the time is one of the variables.
    pub fn has_time(&self) -> bool {
        self.axes.iter().any(|a| a.var == Var::Time)
    }

    fn axis(&self, v: Var) -> Option<&Axis> {
        self.axes.iter().find(|a| a.var == v)
    }

    fn value(&self, v: Var, point: &[f64]) -> f64 {
        let i = match v {
            Var::Joint(j) => j,
            Var::Time => self.n_joints,
        };
        point.get(i).copied().unwrap_or(f64::NAN)
    }

    /// Every candidate term: the constant, one main term per variable, one pair term per two
    /// variables (the time first in its pairs).
    pub fn candidate_terms(&self) -> Vec<Term> {
        let mut vars: Vec<Var> = self.axes.iter().map(|a| a.var).collect();
        // the time first, so that its pairs read `t:q2`
        vars.sort_by_key(|v| match v {
            Var::Time => 0,
            Var::Joint(j) => j + 1,
        });
        let mut terms = vec![Term::Const];
        terms.extend(vars.iter().map(|&v| Term::Main(v)));
        for (a, &i) in vars.iter().enumerate() {
            for &j in &vars[a + 1..] {
                terms.push(Term::Pair(i, j));
            }
        }
        terms
    }

    /// Appends the values of `term`'s basis functions at `point` to `out` (zeros for a
    /// variable that does not move).
    pub fn push_values(&self, term: Term, point: &[f64], out: &mut Vec<f64>) {
        let one = |v: Var, count: usize, buf: &mut Vec<f64>| match self.axis(v) {
            Some(a) => a.values(self.value(v, point), count, buf),
            None => buf.extend(std::iter::repeat_n(0.0, count)),
        };
        match term {
            Term::Const => out.push(1.0),
            Term::Main(v) => one(v, 2 * MAIN_HARMONICS, out),
            Term::Pair(a, b) => {
                let (mut fa, mut fb) = (Vec::new(), Vec::new());
                one(a, 2 * PAIR_HARMONICS, &mut fa);
                one(b, 2 * PAIR_HARMONICS, &mut fb);
                for x in &fa {
                    for y in &fb {
                        out.push(x * y);
                    }
                }
            }
        }
    }

    /// Names of `term`'s basis functions, in the order of [`Domain::push_values`].
    pub fn basis_names(&self, term: Term) -> Vec<String> {
        let one = |v: Var, count: usize| match self.axis(v) {
            Some(a) => a.names(count),
            None => vec!["0".to_string(); count],
        };
        match term {
            Term::Const => vec!["1".to_string()],
            Term::Main(v) => one(v, 2 * MAIN_HARMONICS),
            Term::Pair(a, b) => {
                let fb = one(b, 2 * PAIR_HARMONICS);
                one(a, 2 * PAIR_HARMONICS)
                    .iter()
                    .flat_map(|x| fb.iter().map(move |y| format!("{x} {y}")))
                    .collect()
            }
        }
    }

    /// One line on how every variable is expanded, for the JSON.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self
            .axes
            .iter()
            .map(|a| {
                let unit = if a.var == Var::Time { "s" } else { "deg" };
                if a.periodic {
                    format!(
                        "{}: sin, cos(k {0}), k = 1..{MAIN_HARMONICS} (observed {:.1}..{:.1} {unit})",
                        a.var.name(),
                        a.lo,
                        a.hi
                    )
                } else {
                    format!(
                        "{}: cos(k pi s), s = ({0} - {:.1}) / ({:.1} - {:.1}) clamped to [0, 1], k = 1..{} ({unit})",
                        a.var.name(),
                        a.lo,
                        a.hi,
                        a.lo,
                        2 * MAIN_HARMONICS
                    )
                }
            })
            .collect();
        format!(
            "{}; a pair term: the products of the first {} functions of each variable; const: 1; \
             correction = sum of coefficient x basis (mm, frame R), subtracted from the physical model's error",
            parts.join("; "),
            2 * PAIR_HARMONICS
        )
    }
}

/// The probe's variables at pose `k` of `data`: its joint angles (deg), then its time (s) when
/// `with_time`.
pub fn point(data: &MeasuredSet, k: usize, with_time: bool) -> Vec<f64> {
    let mut p = data.poses.q_deg.get(k).cloned().unwrap_or_default();
    if with_time {
        p.push(data.t(k));
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wide joints get their own harmonics, narrow ones and the time the cosine series; terms
    /// are named and laid out as documented.
    #[test]
    fn axes_terms_and_layout() {
        let points = vec![
            vec![-170.0, 5.0, -10.0, 0.0],
            vec![170.0, 5.0, 20.0, 3600.0],
        ];
        let d = Domain::of(&points, true);
        assert_eq!(d.n_joints, 3);
        assert_eq!(d.axes.len(), 3, "{:?}", d.axes);
        assert!(d.axes[0].periodic && !d.axes[1].periodic && !d.axes[2].periodic);
        let terms = d.candidate_terms();
        let names: Vec<String> = terms.iter().map(Term::name).collect();
        assert_eq!(
            names,
            vec!["const", "t", "q1", "q3", "t:q1", "t:q3", "q1:q3"],
            "{names:?}"
        );
        let mut v = Vec::new();
        d.push_values(Term::Main(Var::Joint(0)), &[90.0, 5.0, 0.0, 0.0], &mut v);
        assert_eq!(v.len(), 2 * MAIN_HARMONICS);
        // sin(90) = 1, cos(90) = 0, sin(180) = 0, cos(180) = -1
        for (got, want) in v.iter().zip([1.0, 0.0, 0.0, -1.0]) {
            assert!((got - want).abs() < 1e-12, "{v:?}");
        }
        let mut w = Vec::new();
        // the time at its upper end: cos(k pi) = (-1)^k; beyond it, held at the edge
        d.push_values(Term::Main(Var::Time), &[0.0, 5.0, 0.0, 7200.0], &mut w);
        for (n, got) in w.iter().enumerate() {
            let want = if n % 2 == 0 { -1.0 } else { 1.0 };
            assert!((got - want).abs() < 1e-12, "{w:?}");
        }
        let pair = Term::Pair(Var::Time, Var::Joint(2));
        let mut p = Vec::new();
        d.push_values(pair, &[0.0, 5.0, -10.0, 0.0], &mut p);
        assert_eq!(p.len(), pair.n_basis());
        assert_eq!(d.basis_names(pair).len(), pair.n_basis());
        // at both lower ends every product is cos(a pi 0) cos(b pi 0) = 1
        assert!(p.iter().all(|x| (x - 1.0).abs() < 1e-12), "{p:?}");
        assert_eq!(Domain::of(&points[..1], true).axes.len(), 0);
    }
}
