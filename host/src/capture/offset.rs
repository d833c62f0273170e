//! The clock offset between the joint log and the instrument log: the shift that best lines up
//! the tool's speed computed from the joints (forward kinematics) with the speed of the
//! measured point. A speed does not depend on the instrument's frame, so the two signals can be
//! compared before anything is registered. The correlation of the two is maximised over every
//! shift that leaves half the shorter log overlapping (a coarse grid), then around the best on
//! a fine grid, refined between grid points by a parabola.

/// Step of the coarse search (s).
pub const COARSE_STEP_S: f64 = 0.05;
/// The fine search's step is the instrument's median sample period over this (at most 10 ms).
pub const FINE_DIVISOR: f64 = 4.0;

/// A speed signal on a uniform grid: `v[i]` at `t0 + i * step`, NaN where unknown.
#[derive(Debug, Clone)]
pub struct Signal {
    pub t0: f64,
    pub step: f64,
    pub v: Vec<f64>,
}

impl Signal {
    /// The speed (mm/s) of points `p` at times `t_s` (increasing; `None` = no point), on a grid
    /// of `step`: positions interpolated linearly (not across a gap longer than `max_gap_s`),
    /// speed the central difference over `span_steps` grid steps either side.
    pub fn speed(
        t_s: &[f64],
        p: &[Option<[f64; 3]>],
        step: f64,
        span_steps: usize,
        max_gap_s: f64,
    ) -> Self {
        let (Some(&t0), Some(&t1)) = (t_s.first(), t_s.last()) else {
            return Self {
                t0: 0.0,
                step,
                v: Vec::new(),
            };
        };
        let n = ((t1 - t0) / step).floor() as usize + 1;
        let mut pos = vec![[f64::NAN; 3]; n];
        let mut k = 0usize;
        for (i, slot) in pos.iter_mut().enumerate() {
            let t = t0 + i as f64 * step;
            while k + 1 < t_s.len() && t_s[k + 1] < t {
                k += 1;
            }
            let j = (k + 1).min(t_s.len() - 1);
            let (Some(a), Some(b)) = (p[k], p[j]) else {
                continue;
            };
            let dt = t_s[j] - t_s[k];
            if dt > max_gap_s {
                continue;
            }
            let w = if dt > 0.0 {
                ((t - t_s[k]) / dt).clamp(0.0, 1.0)
            } else {
                0.0
            };
            *slot = [0, 1, 2].map(|c| a[c] + w * (b[c] - a[c]));
        }
        let m = span_steps.max(1);
        let v = (0..n)
            .map(|i| {
                if i < m || i + m >= n {
                    return f64::NAN;
                }
                let (a, b) = (pos[i - m], pos[i + m]);
                let d2: f64 = (0..3).map(|c| (b[c] - a[c]).powi(2)).sum();
                d2.sqrt() / (2.0 * m as f64 * step)
            })
            .collect();
        Self { t0, step, v }
    }

    /// The value at time `t` (linear between grid points; NaN outside or next to NaN).
    pub fn at(&self, t: f64) -> f64 {
        let x = (t - self.t0) / self.step;
        if x.is_nan() || x < 0.0 {
            return f64::NAN;
        }
        let i = x.floor() as usize;
        if i + 1 >= self.v.len() {
            return if i + 1 == self.v.len() && x == i as f64 {
                self.v[i]
            } else {
                f64::NAN
            };
        }
        let w = x - i as f64;
        self.v[i] + w * (self.v[i + 1] - self.v[i])
    }

    fn end(&self) -> f64 {
        self.t0 + self.step * self.v.len().saturating_sub(1) as f64
    }
}

/// Pearson correlation of `inst(tau)` with `joint(tau + offset)` over the instrument grid, and
/// the number of pairs (only pairs where both are known).
pub fn correlation(inst: &Signal, joint: &Signal, offset_s: f64) -> (f64, usize) {
    let (mut n, mut sa, mut sb, mut saa, mut sbb, mut sab) = (0usize, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, &a) in inst.v.iter().enumerate() {
        if !a.is_finite() {
            continue;
        }
        let b = joint.at(inst.t0 + i as f64 * inst.step + offset_s);
        if !b.is_finite() {
            continue;
        }
        n += 1;
        sa += a;
        sb += b;
        saa += a * a;
        sbb += b * b;
        sab += a * b;
    }
    if n < 3 {
        return (f64::NAN, n);
    }
    let nf = n as f64;
    let va = saa - sa * sa / nf;
    let vb = sbb - sb * sb / nf;
    if va <= 0.0 || vb <= 0.0 {
        return (f64::NAN, n);
    }
    ((sab - sa * sb / nf) / (va * vb).sqrt(), n)
}

/// The estimated offset: `t_joint = t_instrument + offset_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetEstimate {
    pub offset_s: f64,
    /// Correlation of the two speed signals at the offset (1 = identical shape).
    pub correlation: f64,
}

/// The offset in `[lo, hi]` (s) that maximises [`correlation`]: coarse signals searched at
/// `coarse.step`, then the fine signals around the best, refined by a parabola. `None` when no
/// shift overlaps enough motion to compare.
pub fn estimate(
    coarse: (&Signal, &Signal),
    fine: (&Signal, &Signal),
    range_s: Option<(f64, f64)>,
) -> Option<OffsetEstimate> {
    let (ci, cj) = coarse;
    // every shift that overlaps half of the shorter log
    let len_i = ci.end() - ci.t0;
    let len_j = cj.end() - cj.t0;
    let need = 0.5 * len_i.min(len_j);
    let (mut lo, mut hi) = (cj.t0 - ci.end() + need, cj.end() - ci.t0 - need);
    if let Some((a, b)) = range_s {
        lo = lo.max(a);
        hi = hi.min(b);
    }
    if hi.is_nan() || lo.is_nan() || hi < lo {
        return None;
    }
    let n_coarse = ((hi - lo) / ci.step).ceil() as usize + 1;
    let min_pairs = (ci.v.iter().filter(|v| v.is_finite()).count() / 4).max(3);
    let best_coarse = (0..n_coarse)
        .map(|k| lo + k as f64 * ci.step)
        .map(|o| (o, correlation(ci, cj, o)))
        .filter(|(_, (c, n))| c.is_finite() && *n >= min_pairs)
        .max_by(|a, b| a.1 .0.total_cmp(&b.1 .0))?;
    let (fi, fj) = fine;
    let step = fi.step;
    let half = 2.0 * ci.step;
    let n_fine = (2.0 * half / step).ceil() as usize + 1;
    let offsets: Vec<f64> = (0..n_fine)
        .map(|k| best_coarse.0 - half + k as f64 * step)
        .collect();
    let values: Vec<f64> = offsets.iter().map(|&o| correlation(fi, fj, o).0).collect();
    let (k, &c) = values
        .iter()
        .enumerate()
        .filter(|(_, c)| c.is_finite())
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    let mut offset_s = offsets[k];
    if k > 0 && k + 1 < values.len() {
        let (a, b) = (values[k - 1], values[k + 1]);
        let denom = a - 2.0 * c + b;
        if a.is_finite() && b.is_finite() && denom < 0.0 {
            offset_s += 0.5 * step * (a - b) / denom;
        }
    }
    Some(OffsetEstimate {
        offset_s,
        correlation: c,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point moving between dwells; the same motion seen with a clock 7.3 s behind.
    #[test]
    fn a_shifted_speed_signal_gives_its_shift() {
        let motion = |t: f64| -> [f64; 3] {
            let seg = (t / 3.0).floor();
            let u = (t / 3.0 - seg).clamp(0.0, 0.5) * 2.0;
            let s = 0.5 - 0.5 * (u * std::f64::consts::PI).cos();
            let a = 37.0 * seg.sin();
            let b = 37.0 * (seg + 1.0).sin();
            [a + s * (b - a), 2.0 * (a + s * (b - a)), 0.0]
        };
        let tj: Vec<f64> = (0..6000).map(|k| f64::from(k) * 0.01).collect();
        let pj: Vec<_> = tj.iter().map(|&t| Some(motion(t))).collect();
        let true_offset = 7.3;
        let ti: Vec<f64> = (0..2500).map(|k| f64::from(k) * 0.02 + 0.004).collect();
        let pi: Vec<_> = ti.iter().map(|&t| Some(motion(t + true_offset))).collect();
        let sig = |t: &[f64], p: &[Option<[f64; 3]>], step: f64, m: usize| {
            Signal::speed(t, p, step, m, 1.0)
        };
        let e = estimate(
            (
                &sig(&ti, &pi, COARSE_STEP_S, 1),
                &sig(&tj, &pj, COARSE_STEP_S, 1),
            ),
            (&sig(&ti, &pi, 0.005, 10), &sig(&tj, &pj, 0.005, 10)),
            None,
        )
        .unwrap();
        assert!((e.offset_s - true_offset).abs() < 0.005, "{e:?}");
        assert!(e.correlation > 0.99, "{e:?}");
    }
}
