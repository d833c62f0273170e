//! Hard shadows on a simulated sheet: a phone's or a hand's shadow across it (a sharp-edged
//! region of lowered light, [`HardShadow`]), and a scanner's page edge inside the scan with the
//! edge's shadow on the lid beyond it ([`PageEdge`]). Both act on the rendered reflectance
//! before the device's tone curve, in sheet mm.

use super::draw::{mul, Placement};
use image::{Rgb, RgbImage};

/// A hard shadow: the half-plane left of the directed line through `through_mm` at `dir_deg`
/// (sheet mm, degrees from +x), its light multiplied by `factor`, with an edge `edge_mm` wide
/// (a smoothstep across it; a phone's shadow a few tenths of a mm, 0.1-0.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HardShadow {
    pub through_mm: [f64; 2],
    pub dir_deg: f64,
    pub factor: f64,
    pub edge_mm: f64,
}

impl HardShadow {
    /// The light at sheet point `s` (1 outside the shadow, `factor` inside).
    pub fn light_at(&self, s: [f64; 2]) -> f64 {
        let (c, si) = (
            self.dir_deg.to_radians().cos(),
            self.dir_deg.to_radians().sin(),
        );
        // Signed distance to the left of the line.
        let d = -(s[0] - self.through_mm[0]) * si + (s[1] - self.through_mm[1]) * c;
        let u = (0.5 + d / self.edge_mm.max(1e-6)).clamp(0.0, 1.0);
        let inside = u * u * (3.0 - 2.0 * u);
        1.0 - (1.0 - self.factor) * inside
    }
}

/// The page's edge inside a scan: the print shifted sideways on the page, so that past sheet
/// x = `x_mm` (towards +x) there is no page but the scanner's lid at `lid_level` (0..1), with the
/// page edge's shadow on the lid: `shadow_mm` wide, down to `shadow_level` at the edge and back
/// up to the lid's level linearly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PageEdge {
    pub x_mm: f64,
    pub lid_level: f64,
    pub shadow_mm: f64,
    pub shadow_level: f64,
}

/// Darkens `img` under each of `shadows` and puts the lid beyond `edge`.
pub(super) fn shade(
    img: &mut RgbImage,
    place: &Placement,
    shadows: &[HardShadow],
    edge: Option<&PageEdge>,
) {
    if shadows.is_empty() && edge.is_none() {
        return;
    }
    let w = img.width();
    for (i, px) in img.pixels_mut().enumerate() {
        let (x, y) = ((i as u32 % w) as f64 + 0.5, (i as u32 / w) as f64 + 0.5);
        let s = place.sheet([x, y]);
        if let Some(e) = edge.filter(|e| s[0] > e.x_mm) {
            let d = s[0] - e.x_mm;
            let level = if d < e.shadow_mm {
                e.shadow_level + (e.lid_level - e.shadow_level) * d / e.shadow_mm.max(1e-6)
            } else {
                e.lid_level
            };
            let v = (255.0 * level).round().clamp(0.0, 255.0) as u8;
            *px = Rgb([v, v, v]);
        }
        let light: f64 = shadows.iter().map(|h| h.light_at(s)).product();
        if light < 1.0 {
            for c in px.0.iter_mut() {
                *c = mul(*c, light);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shadow_is_left_of_its_line_with_an_edge_of_its_width() {
        let h = HardShadow {
            through_mm: [10.0, 0.0],
            dir_deg: 90.0,
            factor: 0.55,
            edge_mm: 0.2,
        };
        // Heading +y through x = 10: left is -x.
        assert_eq!(h.light_at([5.0, 3.0]), 0.55);
        assert_eq!(h.light_at([15.0, -3.0]), 1.0);
        assert!((h.light_at([10.0, 7.0]) - 0.775).abs() < 1e-12);
        assert_eq!(h.light_at([10.11, 0.0]), 1.0);
        assert_eq!(h.light_at([9.89, 0.0]), 0.55);
    }
}
