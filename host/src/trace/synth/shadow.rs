//! A hard shadow on a photographed sheet: a phone or a hand held over it, lit by one small lamp,
//! casts a shadow with a sharp edge. Modelled as a rectangle (the phone) in sheet mm, its
//! corners rounded by nothing, its edge blurred over `blur_mm` (the penumbra): the light inside
//! is `1 - depth` of the light outside.

/// A rectangle's shadow on the sheet plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HardShadow {
    /// Centre of the rectangle, sheet mm.
    pub centre_mm: [f64; 2],
    /// Half its length and width, mm.
    pub half_size_mm: [f64; 2],
    /// Its long side's direction, degrees from the sheet's +x.
    pub angle_deg: f64,
    /// Share of the light the shadow takes, 0..1.
    pub depth: f64,
    /// Width of the penumbra (the edge's ramp from full light to full shadow), mm; 0: a step.
    pub blur_mm: f64,
}

impl HardShadow {
    /// Light factor (0..1) at sheet point `p_mm`, for a pixel `pixel_mm` across (a step edge is
    /// area-sampled over the pixel).
    pub fn light_at(&self, p_mm: [f64; 2], pixel_mm: f64) -> f64 {
        let (s, c) = self.angle_deg.to_radians().sin_cos();
        let d = [p_mm[0] - self.centre_mm[0], p_mm[1] - self.centre_mm[1]];
        let local = [c * d[0] + s * d[1], -s * d[0] + c * d[1]];
        // Signed distance to the rectangle (negative inside).
        let q = [
            local[0].abs() - self.half_size_mm[0],
            local[1].abs() - self.half_size_mm[1],
        ];
        let outside = q[0].max(0.0).hypot(q[1].max(0.0));
        let sd = outside + q[0].max(q[1]).min(0.0);
        let ramp = self.blur_mm.max(pixel_mm).max(1e-6);
        let t = (0.5 + sd / ramp).clamp(0.0, 1.0);
        let inside = 1.0 - t * t * (3.0 - 2.0 * t);
        1.0 - self.depth * inside
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_dark_outside_lit_edge_between() {
        let s = HardShadow {
            centre_mm: [0.0, 0.0],
            half_size_mm: [40.0, 20.0],
            angle_deg: 30.0,
            depth: 0.5,
            blur_mm: 1.0,
        };
        assert!((s.light_at([0.0, 0.0], 0.1) - 0.5).abs() < 1e-9);
        assert!((s.light_at([100.0, 0.0], 0.1) - 1.0).abs() < 1e-9);
        // On the long side's edge, half way.
        let (sn, cs) = 30f64.to_radians().sin_cos();
        let e = [-sn * 20.0, cs * 20.0];
        assert!((s.light_at(e, 0.1) - 0.75).abs() < 1e-9);
    }
}
