//! Clock alignment: the board stamps potentiometer samples with its own clock (µs since boot),
//! the robot controller stamps joint readings with its clock (s since its start). The offset is
//! found from **markers**: moments where the pencil, on the paper, moves along the sheet normal
//! in a way the joint readings predict.
//!
//! # The marker protocol (what a session must do)
//! Before drawing (and, to measure drift, after drawing) the robot, with the pencil on the
//! paper, dips the tool point along the sheet normal: e.g. 1.5 mm down and back up in 0.5 s,
//! smoothly, with a short dwell on either side. The descent onto the paper serves as well. The
//! pencil's travel then follows the travel predicted from the nominal height of the tool point
//! above the paper, `h(t) = n . (p_nominal(q(t)) - origin)`, along the pencil axis `a`,
//! `-h / (n . a)` (the caller passes this prediction as `h_mm`), up to a constant: the geometric errors of the arm
//! shift the level by a fraction of a millimetre but hardly change over a 1.5 mm dip.
//!
//! # Estimation
//! Marker windows are the runs of joint samples where the pencil is predicted on the paper
//! (`h < stop - contact_margin`) and `|dh/dt|` exceeds `min_speed_mm_s`, merged across gaps up
//! to `2 pad_s` and padded by `pad_s`. For a trial offset `tau` (board time = robot time + tau)
//! the cost of a window is the variance of `travel(t_k + tau) - h_k` over its samples (the level
//! is the free constant). A grid search over the whole overlap of the two records (step
//! `coarse_step_s`, all windows together) finds the offset, then a golden-section search within
//! one grid step either side refines it for each window. With two or more windows at least 1 s
//! apart, a straight line `offset + drift * t` is fitted through the window offsets (drift in
//! ppm); with one window the drift is taken as 0.

use super::error::FusionError;
use super::pot::TravelSeries;

/// Settings of [`align`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignOptions {
    /// A joint sample counts as on the paper when its nominal height is this much below the
    /// pencil's stop, mm.
    pub contact_margin_mm: f64,
    /// Least normal speed of a marker sample, mm/s.
    pub min_speed_mm_s: f64,
    /// Padding of a marker window on either side, s.
    pub pad_s: f64,
    /// Least height range of a marker window, mm.
    pub min_span_mm: f64,
    /// Step of the coarse search, s.
    pub coarse_step_s: f64,
    /// Largest RMS misfit of an aligned marker, mm (beyond it the alignment is refused).
    pub max_rms_mm: f64,
}

impl Default for AlignOptions {
    fn default() -> Self {
        Self {
            contact_margin_mm: 0.5,
            min_speed_mm_s: 2.0,
            pad_s: 0.15,
            min_span_mm: 1.0,
            coarse_step_s: 1e-3,
            max_rms_mm: 0.1,
        }
    }
}

/// One aligned marker.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarkerFit {
    /// Window start on the robot clock, s.
    pub start_s: f64,
    /// Window end on the robot clock, s.
    pub end_s: f64,
    /// Offset board - robot found in this window, s.
    pub offset_s: f64,
    /// Travel minus nominal height in the window (the arm's error along the normal), mm.
    pub level_mm: f64,
    /// RMS misfit after alignment, mm.
    pub rms_mm: f64,
    /// Joint samples in the window.
    pub samples: usize,
}

/// The board clock as a function of the robot clock.
#[derive(Debug, Clone, PartialEq)]
pub struct ClockAlignment {
    /// Board time at robot time 0, s.
    pub offset_s: f64,
    /// Rate difference, ppm: board = robot (1 + drift 1e-6) + offset.
    pub drift_ppm: f64,
    /// The markers used.
    pub markers: Vec<MarkerFit>,
}

impl ClockAlignment {
    /// Board time (s) of robot time `robot_s`.
    pub fn board_s(&self, robot_s: f64) -> f64 {
        robot_s * (1.0 + self.drift_ppm * 1e-6) + self.offset_s
    }
}

/// Index ranges `[a, b)` of the marker windows (see the module documentation).
pub fn marker_windows(
    t_s: &[f64],
    h_mm: &[f64],
    stop_mm: f64,
    o: &AlignOptions,
) -> Vec<(usize, usize)> {
    let n = t_s.len().min(h_mm.len());
    if n < 3 {
        return Vec::new();
    }
    let contact = |k: usize| h_mm[k] < stop_mm - o.contact_margin_mm;
    let moving: Vec<usize> = (1..n - 1)
        .filter(|&k| {
            let v = (h_mm[k + 1] - h_mm[k - 1]) / (t_s[k + 1] - t_s[k - 1]);
            contact(k) && v.abs() > o.min_speed_mm_s
        })
        .collect();
    let mut runs: Vec<(f64, f64)> = Vec::new();
    for &k in &moving {
        match runs.last_mut() {
            Some(r) if t_s[k] - r.1 <= 2.0 * o.pad_s => r.1 = t_s[k],
            _ => runs.push((t_s[k], t_s[k])),
        }
    }
    runs.into_iter()
        .filter_map(|(a, b)| {
            let idx: Vec<usize> = (0..n)
                .filter(|&k| t_s[k] >= a - o.pad_s && t_s[k] <= b + o.pad_s && contact(k))
                .collect();
            let (&first, &last) = (idx.first()?, idx.last()?);
            let (lo, hi) = idx
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &k| {
                    (l.min(h_mm[k]), h.max(h_mm[k]))
                });
            (hi - lo >= o.min_span_mm && last - first + 1 == idx.len()).then_some((first, last + 1))
        })
        .collect()
}

/// Variance of `travel(t + tau) - h` over a window; infinite where the pot does not cover it.
fn window_cost(pot: &TravelSeries, t: &[f64], h: &[f64], tau: f64) -> (f64, f64) {
    let mut sum = 0.0;
    let mut sum2 = 0.0;
    for (tk, hk) in t.iter().zip(h) {
        let Some(v) = pot.at(tk + tau, 0.05) else {
            return (f64::INFINITY, 0.0);
        };
        let d = v - hk;
        sum += d;
        sum2 += d * d;
    }
    let n = t.len().max(1) as f64;
    let mean = sum / n;
    ((sum2 / n - mean * mean).max(0.0), mean)
}

/// Aligns the clocks: `t_s`, `h_mm` are the joint samples' robot times and nominal heights
/// above the paper, `pot` the pencil travel on the board clock, `stop_mm` its stop reading.
pub fn align(
    pot: &TravelSeries,
    t_s: &[f64],
    h_mm: &[f64],
    stop_mm: f64,
    o: &AlignOptions,
) -> Result<ClockAlignment, FusionError> {
    let wins = marker_windows(t_s, h_mm, stop_mm, o);
    if wins.is_empty() {
        return Err(FusionError::Alignment(
            "no marker: the joint readings show no motion along the sheet normal with the pencil \
             on the paper (start the session with a dip, see `rigctl::fusion::align`)"
                .into(),
        ));
    }
    let (Some(&p0), Some(&p1)) = (pot.t_s.first(), pot.t_s.last()) else {
        return Err(FusionError::Alignment("no potentiometer sample".into()));
    };
    let w_t0 = t_s[wins[0].0];
    let w_t1 = t_s[wins[wins.len() - 1].1 - 1];
    let (lo, hi) = (p0 - w_t0, p1 - w_t1);
    let ordered = hi.partial_cmp(&lo).is_some_and(|c| c.is_ge());
    if !ordered || o.coarse_step_s.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(FusionError::Alignment(format!(
            "the recording ({:.3} s) is shorter than the marked part of the joint readings \
             ({:.3} s)",
            p1 - p0,
            w_t1 - w_t0
        )));
    }
    let steps = ((hi - lo) / o.coarse_step_s).ceil() as usize;
    let mut best = (f64::INFINITY, lo);
    for i in 0..=steps {
        let tau = (lo + i as f64 * o.coarse_step_s).min(hi);
        let c: f64 = wins
            .iter()
            .map(|&(a, b)| window_cost(pot, &t_s[a..b], &h_mm[a..b], tau).0)
            .sum();
        if c < best.0 {
            best = (c, tau);
        }
    }
    if !best.0.is_finite() {
        return Err(FusionError::Alignment(
            "no offset puts the markers inside the recording".into(),
        ));
    }
    let mut markers = Vec::new();
    for &(a, b) in &wins {
        let (t, h) = (&t_s[a..b], &h_mm[a..b]);
        let f = |tau: f64| window_cost(pot, t, h, tau).0;
        let tau = golden_min(f, best.1 - o.coarse_step_s, best.1 + o.coarse_step_s, 1e-8);
        let (var, level) = window_cost(pot, t, h, tau);
        let rms = var.sqrt();
        if rms.is_nan() || rms > o.max_rms_mm {
            return Err(FusionError::Alignment(format!(
                "the marker at robot time {:.3}..{:.3} s does not match the potentiometer (RMS \
                 misfit {rms:.3} mm > {} mm)",
                t[0],
                t[t.len() - 1],
                o.max_rms_mm
            )));
        }
        markers.push(MarkerFit {
            start_s: t[0],
            end_s: t[t.len() - 1],
            offset_s: tau,
            level_mm: level,
            rms_mm: rms,
            samples: t.len(),
        });
    }
    let centres: Vec<f64> = markers
        .iter()
        .map(|m| 0.5 * (m.start_s + m.end_s))
        .collect();
    let span = centres.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - centres.iter().cloned().fold(f64::INFINITY, f64::min);
    let n = markers.len() as f64;
    let mean_c = centres.iter().sum::<f64>() / n;
    let mean_o = markers.iter().map(|m| m.offset_s).sum::<f64>() / n;
    let (offset_s, drift_ppm) = if markers.len() >= 2 && span >= 1.0 {
        let sxx: f64 = centres.iter().map(|c| (c - mean_c).powi(2)).sum();
        let sxy: f64 = centres
            .iter()
            .zip(&markers)
            .map(|(c, m)| (c - mean_c) * (m.offset_s - mean_o))
            .sum();
        let slope = sxy / sxx;
        (mean_o - slope * mean_c, slope * 1e6)
    } else {
        (mean_o, 0.0)
    };
    Ok(ClockAlignment {
        offset_s,
        drift_ppm,
        markers,
    })
}

/// Golden-section minimum of `f` on `[a, b]` to `tol`.
fn golden_min(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, tol: f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    while (b - a).abs() > tol {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dip of `depth` mm over `dur` s starting at `t0`, on a level of 0.
    fn dip(t: f64, t0: f64, dur: f64, depth: f64) -> f64 {
        if t <= t0 || t >= t0 + dur {
            0.0
        } else {
            -depth * (std::f64::consts::PI * (t - t0) / dur).sin().powi(2)
        }
    }

    /// Robot: 100 Hz, dips at 1 s and 9 s; pot: 1 kHz on a clock `offset` ahead, running
    /// `drift_ppm` fast, with a level error of 0.3 mm and +-0.005 mm of deterministic noise.
    fn case(offset: f64, drift_ppm: f64) -> (TravelSeries, Vec<f64>, Vec<f64>) {
        let h_of = |t: f64| dip(t, 1.0, 0.5, 1.5) + dip(t, 9.0, 0.5, 1.5);
        let t_r: Vec<f64> = (0..1100).map(|k| k as f64 * 0.01).collect();
        let h: Vec<f64> = t_r.iter().map(|&t| h_of(t)).collect();
        let n_pot = 11_500;
        let b0 = offset - 0.2;
        let mut pot = TravelSeries {
            t_s: Vec::new(),
            travel_mm: Vec::new(),
        };
        for j in 0..n_pot {
            let tb = b0 + j as f64 * 1e-3;
            let tr = (tb - offset) / (1.0 + drift_ppm * 1e-6);
            let noise = 0.005 * ((j * 7919 % 1000) as f64 / 500.0 - 1.0);
            pot.t_s.push(tb);
            pot.travel_mm.push(h_of(tr) + 0.3 + noise);
        }
        (pot, t_r, h)
    }

    #[test]
    fn known_offset_is_recovered_within_a_millisecond() {
        for offset in [1_234.567_891, -3.210_987, 0.4e-3] {
            let (pot, t, h) = case(offset, 0.0);
            let a = align(&pot, &t, &h, 2.0, &AlignOptions::default()).unwrap();
            assert_eq!(a.markers.len(), 2);
            let err = a.board_s(5.0) - (5.0 + offset);
            assert!(err.abs() < 1e-3, "offset {offset}: error {err} s");
            // in fact far better than the 1 ms of the acceptance bound
            assert!(err.abs() < 2e-4, "offset {offset}: error {err} s");
            for m in &a.markers {
                assert!((m.level_mm - 0.3).abs() < 0.01 && m.rms_mm < 0.01, "{m:?}");
            }
        }
    }

    #[test]
    fn drift_between_two_markers_is_measured() {
        let (pot, t, h) = case(42.0, 50.0);
        let a = align(&pot, &t, &h, 2.0, &AlignOptions::default()).unwrap();
        assert!((a.drift_ppm - 50.0).abs() < 20.0, "{}", a.drift_ppm);
        for tr in [1.0, 9.0] {
            let want = tr * (1.0 + 50e-6) + 42.0;
            assert!((a.board_s(tr) - want).abs() < 1e-3);
        }
    }

    #[test]
    fn no_marker_is_an_error() {
        let (pot, t, _) = case(1.0, 0.0);
        let flat = vec![0.0; t.len()];
        assert!(matches!(
            align(&pot, &t, &flat, 2.0, &AlignOptions::default()),
            Err(FusionError::Alignment(_))
        ));
    }
}
