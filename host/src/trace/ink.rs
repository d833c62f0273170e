//! Separating graphite from printed red: a per-pixel "graphite darkness".
//!
//! Layers multiply (paper x red ink x graphite). Graphite is neutral grey, so it darkens all
//! channels alike; red ink keeps most of the red channel and removes green and blue. The green
//! to red ratio of a pixel therefore gives the red-ink coverage `c`, and dividing the red
//! channel by the red ink's red transmittance at that coverage leaves the graphite alone:
//!
//! `rho = (G/Gp) / (R/Rp)`, `c = (1 - rho) / ((1 - Tg) - rho (1 - Tr))`,
//! `graphite = (R/Rp) / (1 - c (1 - Tr))`, darkness = `1 - graphite`,
//!
//! with `Rp, Gp` the paper level and `Tr, Tg` the red ink's transmittances, estimated from the
//! scan's most saturated pixels.

use super::paper::PaperMap;
use image::RgbImage;

/// Darkness below which a pixel counts as paper (weights are `darkness - floor`): the most it
/// is, for noisy photos; quiet scans get a lower one from their paper noise ([`paper_floor`]),
/// so faint graphite keeps its weight.
pub(crate) const DEFAULT_FLOOR: f32 = 0.12;
/// The least floor.
const MIN_FLOOR: f32 = 0.06;

/// The per-pixel graphite model of one scan.
#[derive(Debug, Clone, Copy)]
pub(crate) struct InkModel {
    /// Red ink transmittance `[red, green]` relative to paper, if red ink was found.
    pub red_ink: Option<[f32; 2]>,
    /// Darkness treated as zero weight.
    pub floor: f32,
}

impl InkModel {
    /// Estimates the red ink from the strongly red pixels among every `step`-th pixel of every
    /// `step`-th row, each relative to its local paper level.
    pub fn estimate(img: &RgbImage, paper_map: &PaperMap, floor: f32, step: usize) -> Self {
        let step = step.max(1);
        let (w, h) = (img.width() as usize, img.height() as usize);
        let raw = img.as_raw();
        let mut samples: Vec<[f32; 2]> = Vec::new();
        let mut paper_dark: Vec<f32> = Vec::new();
        for y in (0..h).step_by(step) {
            let row = &raw[3 * w * y..3 * w * (y + 1)];
            for (i, px) in row.chunks_exact(3).enumerate().step_by(step) {
                // Every 7th sample (offset within its block) for the paper's own darkness.
                if (i / step + y / step).is_multiple_of(7) {
                    let q = (i + step / 2).min(w - 1);
                    let local = paper_map.at(q as f64 + 0.5, y as f64 + 0.5);
                    if local[0] > 1.0 {
                        paper_dark.push(1.0 - row[3 * q] as f32 / local[0]);
                    }
                }
                // Only strongly red pixels matter: skip the rest before the local paper lookup.
                if 2 * px[1] as u32 >= px[0] as u32 {
                    continue;
                }
                let local = paper_map.at(i as f64 + 0.5, y as f64 + 0.5);
                let r = px[0] as f32 / local[0];
                let g = px[1] as f32 / local[1];
                if r > 0.6 && g < 0.5 * r {
                    samples.push([r, g]);
                }
            }
        }
        let red_ink = (samples.len() >= 50).then(|| {
            // The most saturated fifth: pixels fully covered by the ink.
            samples.sort_by(|a, b| (a[1] / a[0]).total_cmp(&(b[1] / b[0])));
            let core_len = samples.len().div_ceil(5);
            let core = &samples[..core_len];
            let mid = core.len() / 2;
            let tr = core.iter().map(|s| s[0]).sum::<f32>() / core.len() as f32;
            let tg = core[mid][1];
            [tr.min(1.0), tg.clamp(0.0, 0.5)]
        });
        Self {
            red_ink,
            floor: paper_floor(&mut paper_dark, floor),
        }
    }

    /// Graphite darkness of one pixel on paper of level `paper`, 0 (paper, red ink) .. 1 (black).
    #[inline]
    pub fn darkness_on(&self, px: &[u8], paper: [f32; 3]) -> f32 {
        let r = px[0] as f32 / paper[0];
        let mut graphite = r;
        if let Some([tr, tg]) = self.red_ink {
            let g = px[1] as f32 / paper[1];
            if r > 1e-3 {
                let rho = g / r;
                if rho < 0.98 {
                    let denom = (1.0 - tg) - rho * (1.0 - tr);
                    if denom > 1e-3 {
                        let c = ((1.0 - rho) / denom).clamp(0.0, 1.0);
                        graphite = r / (1.0 - c * (1.0 - tr));
                    }
                }
            }
        }
        (1.0 - graphite).clamp(0.0, 1.0)
    }
}

/// The floor for a paper whose sampled darkness (relative to the local paper level) is
/// `dark`: the 90th percentile of the light samples (paper, not marks) plus 0.04, within
/// [`MIN_FLOOR`]..`most`.
fn paper_floor(dark: &mut [f32], most: f32) -> f32 {
    let mut light: Vec<f32> = dark.iter().copied().filter(|d| *d < 0.2).collect();
    if light.len() < 100 {
        return most;
    }
    light.sort_by(f32::total_cmp);
    let q90 = light[light.len() * 9 / 10];
    (q90 + 0.04).clamp(MIN_FLOOR.min(most), most)
}

#[cfg(test)]
mod tests {
    #[test]
    fn floor_follows_the_paper_noise() {
        let mut quiet: Vec<f32> = (0..1000)
            .map(|i| 0.01 * ((i % 7) as f32 - 3.0) / 3.0)
            .collect();
        assert!((super::paper_floor(&mut quiet, 0.12) - 0.06).abs() < 1e-6);
        let mut noisy: Vec<f32> = (0..1000)
            .map(|i| 0.06 * ((i % 7) as f32 - 3.0) / 3.0)
            .collect();
        assert!((super::paper_floor(&mut noisy, 0.12) - 0.1).abs() < 0.011);
        assert_eq!(super::paper_floor(&mut [0.0; 10], 0.12), 0.12);
    }

    use super::*;

    #[test]
    fn red_ink_is_removed_and_graphite_kept() {
        let paper = [240.0, 240.0, 240.0];
        let model = InkModel {
            red_ink: Some([0.9, 0.12]),
            floor: 0.0,
        };
        let mix = |red_cov: f32, graphite: f32| -> [u8; 3] {
            let tr = 1.0 - red_cov * 0.1;
            let tg = 1.0 - red_cov * 0.88;
            [
                (240.0 * tr * graphite) as u8,
                (240.0 * tg * graphite) as u8,
                (240.0 * tg * graphite) as u8,
            ]
        };
        for cov in [0.0, 0.3, 0.7, 1.0] {
            for graphite in [1.0, 0.45] {
                let d = model.darkness_on(&mix(cov, graphite), paper);
                assert!(
                    (d - (1.0 - graphite)).abs() < 0.02,
                    "cov {cov} g {graphite}: {d}"
                );
            }
        }
    }
}
