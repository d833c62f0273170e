//! The device's tone curve: how a scanner or a phone camera writes the reflectance it measured
//! (the renderers draw in linear light, 8 bits). Applied to the finished image, before a
//! photo's JPEG compression, as a device applies it before it encodes.

use image::RgbImage;

/// A device's tone curve, linear reflectance (0..1) to the value written (0..1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DeviceTone {
    /// Written as measured.
    #[default]
    Linear,
    /// The sRGB transfer curve (IEC 61966-2-1).
    Srgb,
    /// A plain power law, `linear^(1 / gamma)`.
    Gamma(f64),
    /// A phone's rendering: the sRGB curve followed by an S-shaped contrast curve (`share` of a
    /// smoothstep blended in), which deepens the shadows and lifts the highlights.
    PhoneS { share: f64 },
}

impl DeviceTone {
    /// The value written for reflectance `l` (both 0..1).
    pub fn encode(self, l: f64) -> f64 {
        let l = l.clamp(0.0, 1.0);
        let srgb = |l: f64| {
            if l <= 0.003_130_8 {
                12.92 * l
            } else {
                1.055 * l.powf(1.0 / 2.4) - 0.055
            }
        };
        match self {
            Self::Linear => l,
            Self::Srgb => srgb(l),
            Self::Gamma(g) => l.powf(1.0 / g.max(1e-3)),
            Self::PhoneS { share } => {
                let e = srgb(l);
                (1.0 - share) * e + share * e * e * (3.0 - 2.0 * e)
            }
        }
    }

    /// Writes `img` (linear, 8 bits) through the curve.
    pub fn apply(self, img: &mut RgbImage) {
        if self == Self::Linear {
            return;
        }
        let mut lut = [0u8; 256];
        for (i, v) in lut.iter_mut().enumerate() {
            *v = (255.0 * self.encode(i as f64 / 255.0))
                .round()
                .clamp(0.0, 255.0) as u8;
        }
        let raw: &mut [u8] = img.as_mut();
        for v in raw.iter_mut() {
            *v = lut[*v as usize];
        }
    }
}
