//! A sheet that does not lie flat, for the photo renderer: a developable bend, the height a
//! function of the distance across an axis in the sheet plane (a cylinder), so the paper is
//! unrolled exactly by measuring along that direction. A bow lifts both edges (the middle on
//! the desk, as printer paper lies); a lifted edge raises one edge from a fold line on.

/// The shape of the bend across its axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BendShape {
    /// `z = h (u / W)^2`: both edges up by `h` at `|u| = W`.
    Bow,
    /// `z = h ((u - u0) / (W - u0))^2` for `u > u0 = W / 3`: one edge up by `h`.
    LiftedEdge,
}

/// A developable bend of the sheet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bend {
    pub shape: BendShape,
    /// Height at the lifted edge(s), mm.
    pub height_mm: f64,
    /// Direction of the bend's axis in the sheet plane, degrees from the sheet's +x.
    pub axis_deg: f64,
    /// Half width across the axis at which the height is `height_mm`, mm.
    pub half_width_mm: f64,
}

impl Bend {
    /// Unit vectors along the axis and across it (sheet frame).
    fn frame(&self) -> ([f64; 2], [f64; 2]) {
        let a = self.axis_deg.to_radians();
        ([a.cos(), a.sin()], [-a.sin(), a.cos()])
    }

    /// The height profile and its slope at `u` (mm across the axis).
    fn profile(&self, u: f64) -> (f64, f64) {
        let (h, w) = (self.height_mm, self.half_width_mm.max(1.0));
        match self.shape {
            BendShape::Bow => (h * (u / w).powi(2), 2.0 * h * u / (w * w)),
            BendShape::LiftedEdge => {
                let u0 = w / 3.0;
                if u <= u0 {
                    (0.0, 0.0)
                } else {
                    let t = (u - u0) / (w - u0);
                    (h * t * t, 2.0 * h * t / (w - u0))
                }
            }
        }
    }

    /// Height of the surface above the desk plane point `p` (sheet frame, mm).
    pub fn height_at(&self, p: [f64; 2]) -> f64 {
        let (_, across) = self.frame();
        self.profile(p[0] * across[0] + p[1] * across[1]).0
    }

    /// The paper's own coordinates (as printed and drawn, flat) of the surface point above the
    /// desk plane point `p`: the distance across the axis replaced by the arc length along the
    /// surface from the axis (Simpson's rule on the slope).
    pub fn unroll(&self, p: [f64; 2]) -> [f64; 2] {
        let (along, across) = self.frame();
        let v = p[0] * along[0] + p[1] * along[1];
        let u = p[0] * across[0] + p[1] * across[1];
        let n = 16;
        let f = |t: f64| self.profile(t).1.hypot(1.0);
        let h = u / n as f64;
        let mut s = f(0.0) + f(u);
        for i in 1..n {
            s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(i as f64 * h);
        }
        let arc = s * h / 3.0;
        [
            v * along[0] + arc * across[0],
            v * along[1] + arc * across[1],
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unrolled_arc_is_longer_by_the_bow() {
        let b = Bend {
            shape: BendShape::Bow,
            height_mm: 5.0,
            axis_deg: 90.0,
            half_width_mm: 100.0,
        };
        // Across a 90-degree axis is -x; at x = -100 the arc exceeds 100 by 2 h^2 / (3 W).
        let q = b.unroll([-100.0, 3.0]);
        let want = 100.0 + 2.0 * 25.0 / 300.0;
        assert!(
            (q[0] + want).abs() < 2e-3 && (q[1] - 3.0).abs() < 1e-12,
            "{q:?}"
        );
        assert!((b.height_at([-100.0, 0.0]) - 5.0).abs() < 1e-12);
    }
}
