//! The device's tone curve, undone before anything measures darkness. A scanner or a phone
//! writes reflectance through a tone curve (sRGB's, or a plain gamma of about 1/2.2), which
//! roughly halves how dark light graphite looks and lifts the print's black from a few per cent
//! of the paper to a quarter of it; every darkness threshold of the tracer is a fraction of the
//! local paper level in linear light. So the image is linearised first:
//!
//! - a PNG that says how it is encoded (an `sRGB` chunk, an `iCCP` profile's tone curve, a
//!   `gAMA` chunk) is decoded as it says, while it is read ([`super::files`]);
//! - an image that says nothing is measured ([`estimate`]): the print's black is ink or toner
//!   reflecting about [`PRINT_BLACK`] of the paper; where the corner discs are lighter than
//!   [`LINEAR_BLACK_MAX`] of the paper around them, the image went through a tone curve, fitted
//!   as the gamma that takes the discs' measured level to the print's black. Darker than that,
//!   the image is taken as linear, as written (every renderer of the project writes linear
//!   reflectance, its black at 0.07 of the paper).
//!
//! The linear image is kept in 8 bits (a lookup table per curve).

mod icc;

use image::RgbImage;

/// The print's black, reflectance relative to the paper (toner or inkjet black: 0.03-0.10; the project's renderers print 0.07).
pub const PRINT_BLACK: f64 = 0.07;
/// A black darker than this fraction of the paper is taken as written in linear light.
pub const LINEAR_BLACK_MAX: f64 = 0.15;
/// The gamma fitted from the black is kept within this range.
const GAMMA_RANGE: (f64, f64) = (1.0, 3.2);

/// How encoded values map to reflectance.
#[derive(Debug, Clone, PartialEq)]
pub enum ToneCurve {
    /// Written in linear light.
    Linear,
    /// The sRGB curve (IEC 61966-2-1).
    Srgb,
    /// `encoded = linear^(1 / gamma)`.
    Gamma(f64),
    /// A table of linear values (0..1) for encoded values spread evenly over 0..1 (an ICC
    /// profile's sampled curve); interpolated linearly.
    Table(Vec<f64>),
    /// ICC parametric curve (type 0-4): `[g, a, b, c, d, e, f]`.
    Parametric([f64; 7]),
}

impl ToneCurve {
    /// Linear reflectance (0..1) of an encoded value `e` (0..1).
    pub fn to_linear(&self, e: f64) -> f64 {
        let e = e.clamp(0.0, 1.0);
        let v = match self {
            Self::Linear => e,
            Self::Srgb => {
                if e <= 0.04045 {
                    e / 12.92
                } else {
                    ((e + 0.055) / 1.055).powf(2.4)
                }
            }
            Self::Gamma(g) => e.powf(*g),
            Self::Table(t) => match t.len() {
                0 => e,
                1 => t[0],
                n => {
                    let f = e * (n - 1) as f64;
                    let i = (f.floor() as usize).min(n - 2);
                    t[i] + (t[i + 1] - t[i]) * (f - i as f64)
                }
            },
            Self::Parametric([g, a, b, c, d, e0, f]) => {
                if e >= *d {
                    (a * e + b).max(0.0).powf(*g) + e0
                } else {
                    c * e + f
                }
            }
        };
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            e
        }
    }

    /// Whether the curve leaves values as they are.
    pub fn is_identity(&self) -> bool {
        (0..256).all(|i| {
            let e = f64::from(i) / 255.0;
            ((self.to_linear(e) - e) * 255.0).abs() < 0.5
        })
    }

    /// The 8-bit lookup table: linear value of each encoded one.
    pub fn lut(&self) -> [u8; 256] {
        let mut t = [0u8; 256];
        for (i, v) in t.iter_mut().enumerate() {
            *v = (self.to_linear(i as f64 / 255.0) * 255.0).round() as u8;
        }
        t
    }

    /// A short description for the report.
    pub fn describe(&self) -> String {
        match self {
            Self::Linear => "linear".into(),
            Self::Srgb => "sRGB".into(),
            Self::Gamma(g) => format!("gamma {g:.2}"),
            Self::Table(t) => format!("a sampled curve of {} points", t.len()),
            Self::Parametric(p) => format!("a parametric curve (gamma {:.2})", p[0]),
        }
    }
}

/// Where the curve came from.
#[derive(Debug, Clone, PartialEq)]
pub enum ToneSource {
    /// The file said so (`what`: the chunk or profile).
    File(String),
    /// Measured on the image: the corner discs' level relative to the paper.
    Estimated { black_of_paper: f64 },
    /// Nothing said or measured: taken as written.
    Assumed,
}

/// The tone curve an image was linearised through, and how it was known.
#[derive(Debug, Clone, PartialEq)]
pub struct Tone {
    pub curve: ToneCurve,
    pub source: ToneSource,
}

impl Tone {
    /// Taken as written (nothing known yet).
    pub fn assumed() -> Self {
        Self {
            curve: ToneCurve::Linear,
            source: ToneSource::Assumed,
        }
    }

    /// Whether the file said how it is encoded (nothing left to estimate).
    pub fn from_file(&self) -> bool {
        matches!(self.source, ToneSource::File(_))
    }

    /// One line for the report.
    pub fn describe(&self) -> String {
        match &self.source {
            ToneSource::File(what) => {
                format!("linearised through {} ({what})", self.curve.describe())
            }
            ToneSource::Estimated { black_of_paper } => format!(
                "linearised through {} (measured: the print's black at {:.2} of the paper, taken as {PRINT_BLACK})",
                self.curve.describe(),
                black_of_paper
            ),
            ToneSource::Assumed => "taken as linear".into(),
        }
    }
}

/// The curve a PNG's header declares: `sRGB` first, then an `iCCP` profile's grey or red tone
/// curve (a profile without one is taken as sRGB), then `gAMA`; `None` when it says nothing.
pub fn from_png_info(info: &png::Info) -> Option<Tone> {
    let file = |curve, what: &str| {
        Some(Tone {
            curve,
            source: ToneSource::File(what.into()),
        })
    };
    if info.srgb.is_some() {
        return file(ToneCurve::Srgb, "the PNG's sRGB chunk");
    }
    if let Some(icc) = &info.icc_profile {
        return from_icc(icc);
    }
    if let Some(g) = info.gama_chunk {
        let file_gamma = f64::from(g.into_value());
        if file_gamma > 0.05 && file_gamma < 20.0 {
            let curve = if (file_gamma - 1.0).abs() < 0.02 {
                ToneCurve::Linear
            } else {
                ToneCurve::Gamma(1.0 / file_gamma)
            };
            return file(curve, "the PNG's gAMA chunk");
        }
    }
    None
}

/// The curve of an embedded ICC profile (its grey or red TRC); sRGB when it has none that can
/// be read.
pub fn from_icc(profile: &[u8]) -> Option<Tone> {
    let (curve, what) = match icc::tone_curve(profile) {
        Some(c) => (c, "the embedded ICC profile's tone curve"),
        None => (
            ToneCurve::Srgb,
            "an embedded ICC profile without a readable tone curve, taken as sRGB",
        ),
    };
    let curve = if curve.is_identity() {
        ToneCurve::Linear
    } else {
        curve
    };
    Some(Tone {
        curve,
        source: ToneSource::File(what.into()),
    })
}

/// The gamma that takes the corner discs' level (`black_of_paper`, relative to the paper
/// around them) to the print's black; `None` when they are dark enough for linear light.
pub fn estimate(black_of_paper: f64) -> Option<Tone> {
    if !black_of_paper.is_finite() || black_of_paper <= LINEAR_BLACK_MAX || black_of_paper >= 0.9 {
        return None;
    }
    let gamma = (PRINT_BLACK.ln() / black_of_paper.ln()).clamp(GAMMA_RANGE.0, GAMMA_RANGE.1);
    Some(Tone {
        curve: ToneCurve::Gamma(gamma),
        source: ToneSource::Estimated { black_of_paper },
    })
}

/// Applies `curve` to every sample of `img` in place.
pub fn apply(img: &mut RgbImage, curve: &ToneCurve) {
    apply_raw(img, curve);
}

/// Applies `curve` to RGB bytes in place.
pub fn apply_raw(raw: &mut [u8], curve: &ToneCurve) {
    if *curve == ToneCurve::Linear {
        return;
    }
    let lut = curve.lut();
    for v in raw.iter_mut() {
        *v = lut[*v as usize];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_and_black() {
        let enc = |l: f64| {
            if l <= 0.0031308 {
                12.92 * l
            } else {
                1.055 * l.powf(1.0 / 2.4) - 0.055
            }
        };
        for i in 0..=100 {
            let l = f64::from(i) / 100.0;
            assert!((ToneCurve::Srgb.to_linear(enc(l)) - l).abs() < 1e-9);
        }
        // A black of 0.07 through sRGB sits at 0.29 of the paper: lighter than linear black.
        assert!(enc(0.07) > LINEAR_BLACK_MAX);
    }

    #[test]
    fn estimated_gamma_recovers_the_print_black() {
        for g in [1.8, 2.2, 2.6] {
            let b = PRINT_BLACK.powf(1.0 / g);
            let t = estimate(b).expect("a tone curve");
            let ToneCurve::Gamma(got) = t.curve else {
                panic!("gamma expected")
            };
            assert!((got - g).abs() < 1e-9, "{got} {g}");
        }
        assert_eq!(estimate(0.07), None);
        assert_eq!(estimate(f64::NAN), None);
    }

    #[test]
    fn lut_is_monotone() {
        for c in [
            ToneCurve::Srgb,
            ToneCurve::Gamma(2.2),
            ToneCurve::Table(vec![0.0, 0.2, 1.0]),
        ] {
            let t = c.lut();
            assert!(t.windows(2).all(|w| w[0] <= w[1]), "{c:?}");
            assert_eq!((t[0], t[255]), (0, 255), "{c:?}");
        }
    }
}
