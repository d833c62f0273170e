//! The tone curve of an ICC profile: its grey TRC (`kTRC`) or red TRC (`rTRC`), a `curv`
//! (identity, a gamma, or a sampled table) or a `para` (parametric, types 0-4) tag. Anything
//! else, or a profile cut short, gives `None`.

use super::ToneCurve;

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

fn s15f16_at(b: &[u8], at: usize) -> Option<f64> {
    Some(f64::from(u32_at(b, at)? as i32) / 65536.0)
}

/// The profile's grey or red tone curve.
pub(super) fn tone_curve(profile: &[u8]) -> Option<ToneCurve> {
    let count = u32_at(profile, 128)? as usize;
    let mut found = None;
    for i in 0..count.min(256) {
        let at = 132 + 12 * i;
        let sig = profile.get(at..at + 4)?;
        let (off, size) = (
            u32_at(profile, at + 4)? as usize,
            u32_at(profile, at + 8)? as usize,
        );
        if sig == b"kTRC" || (sig == b"rTRC" && found.is_none()) {
            found = Some((off, size));
            if sig == b"kTRC" {
                break;
            }
        }
    }
    let (off, size) = found?;
    let tag = profile.get(off..off.checked_add(size)?)?;
    match tag.get(0..4)? {
        b"curv" => {
            let n = u32_at(tag, 8)? as usize;
            match n {
                0 => Some(ToneCurve::Linear),
                1 => {
                    let g = f64::from(u16_at(tag, 12)?) / 256.0;
                    (g > 0.0).then_some(ToneCurve::Gamma(g))
                }
                _ => {
                    let table = (0..n.min(65536))
                        .map(|k| u16_at(tag, 12 + 2 * k).map(|v| f64::from(v) / 65535.0))
                        .collect::<Option<Vec<f64>>>()?;
                    Some(ToneCurve::Table(table))
                }
            }
        }
        b"para" => {
            let kind = u16_at(tag, 8)?;
            let n = match kind {
                0 => 1,
                1 => 3,
                2 => 4,
                3 => 5,
                4 => 7,
                _ => return None,
            };
            let v = (0..n)
                .map(|k| s15f16_at(tag, 12 + 4 * k))
                .collect::<Option<Vec<f64>>>()?;
            // As [g, a, b, c, d, e, f]: Y = (aX + b)^g + e for X >= d, else cX + f.
            let p = match kind {
                0 => [v[0], 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                1 => [v[0], v[1], v[2], 0.0, -v[2] / v[1], 0.0, 0.0],
                2 => [v[0], v[1], v[2], 0.0, -v[2] / v[1], v[3], v[3]],
                3 => [v[0], v[1], v[2], v[3], v[4], 0.0, 0.0],
                _ => [v[0], v[1], v[2], v[3], v[4], v[5], v[6]],
            };
            p.iter()
                .all(|x| x.is_finite())
                .then_some(ToneCurve::Parametric(p))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A profile of one tag `sig` holding `tag`.
    fn profile(sig: &[u8; 4], tag: &[u8]) -> Vec<u8> {
        let mut p = vec![0u8; 128];
        p.extend(1u32.to_be_bytes());
        p.extend(sig);
        p.extend(144u32.to_be_bytes());
        p.extend((tag.len() as u32).to_be_bytes());
        p.extend(tag);
        p
    }

    #[test]
    fn reads_gamma_table_and_parametric_srgb() {
        let mut curv = b"curv\0\0\0\0".to_vec();
        curv.extend(1u32.to_be_bytes());
        curv.extend(((2.2 * 256.0) as u16).to_be_bytes());
        let Some(ToneCurve::Gamma(g)) = tone_curve(&profile(b"rTRC", &curv)) else {
            panic!("gamma")
        };
        assert!((g - 2.2).abs() < 0.01);

        let mut table = b"curv\0\0\0\0".to_vec();
        table.extend(3u32.to_be_bytes());
        for v in [0u16, 10000, 65535] {
            table.extend(v.to_be_bytes());
        }
        let c = tone_curve(&profile(b"kTRC", &table)).expect("table");
        assert!((c.to_linear(0.5) - 10000.0 / 65535.0).abs() < 1e-9);

        // sRGB as a type-3 parametric curve.
        let mut para = b"para\0\0\0\0".to_vec();
        para.extend(3u16.to_be_bytes());
        para.extend([0, 0]);
        for v in [2.4, 1.0 / 1.055, 0.055 / 1.055, 1.0 / 12.92, 0.04045] {
            para.extend(((v * 65536.0f64).round() as i32).to_be_bytes());
        }
        let c = tone_curve(&profile(b"rTRC", &para)).expect("para");
        for e in [0.02, 0.3, 0.8] {
            assert!((c.to_linear(e) - ToneCurve::Srgb.to_linear(e)).abs() < 1e-4);
        }
        assert_eq!(tone_curve(&[1, 2, 3]), None);
    }
}
