//! The second renderer's raster: every pixel mapped back to sheet mm and the sheet evaluated
//! there (n x n sub-samples near ink), paper tooth, light (shading, vignette, shadow edge, a
//! hand's hard shadow), the page's edge and the lid beyond it,
//! hashed triangular noise, a 3-tap blur and JPEG for photos, the device's tone curve.

use image::RgbImage;

use super::scene::{black_at, red_at, Printed, Scene, RING};
use super::strokes::{stamps_of, StampGrid};
use super::view::{on_paper, View};

/// Renders the scene.
pub fn render(scene: &Scene) -> RgbImage {
    let grids: Vec<StampGrid> = scene
        .marks
        .iter()
        .enumerate()
        .map(|(i, m)| {
            StampGrid::new(stamps_of(
                m,
                scene.seed.wrapping_mul(31).wrapping_add(i as u64),
            ))
        })
        .collect();
    // Where ink may be: cells of 1 mm within reach of a stamp, dust, fibre, red or black print.
    let cell = 1.0;
    let n_cells = 240usize; // -120 .. 120 mm
    let idx = |p: [f64; 2]| -> Option<usize> {
        let (i, j) = ((p[0] + 120.0) / cell, (p[1] + 120.0) / cell);
        (i >= 0.0 && j >= 0.0 && (i as usize) < n_cells && (j as usize) < n_cells)
            .then(|| j as usize * n_cells + i as usize)
    };
    // Bits per cell: graphite, black print, red print, dust or fibre.
    const GRAPHITE: u8 = 1;
    const BLACK: u8 = 2;
    const RED: u8 = 4;
    const SPECK: u8 = 8;
    let mut near = vec![0u8; n_cells * n_cells];
    let mut specks: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    let mut flag = |p: [f64; 2], reach: f64, bit: u8, speck: Option<usize>| {
        let r = (reach / cell).ceil() as i64 + 1;
        for dj in -r..=r {
            for di in -r..=r {
                if let Some(k) = idx([p[0] + di as f64 * cell, p[1] + dj as f64 * cell]) {
                    near[k] |= bit;
                    if let Some(d) = speck {
                        let v = specks.entry(k).or_default();
                        if !v.contains(&d) {
                            v.push(d);
                        }
                    }
                }
            }
        }
    };
    for g in &grids {
        for s in g.stamps.iter().step_by(10) {
            flag(s.c, s.r + 0.5, GRAPHITE, None);
        }
    }
    let n_dust = scene.dust.len();
    for (i, d) in scene.dust.iter().enumerate() {
        flag([d[0], d[1]], d[2] + 0.3, SPECK, Some(i));
    }
    for (i, f) in scene.fibres.iter().enumerate() {
        for k in 0..=20 {
            let t = k as f64 / 20.0;
            flag(
                [f[0] + t * (f[2] - f[0]), f[1] + t * (f[3] - f[1])],
                0.5,
                SPECK,
                Some(n_dust + i),
            );
        }
    }
    for i in 0..2000 {
        let t = i as f64 / 2000.0;
        let p = match scene.printed {
            Printed::Circle => {
                let a = t * std::f64::consts::TAU;
                [100.0 * a.cos(), 100.0 * a.sin()]
            }
            Printed::Line => [-100.0 + 200.0 * t, 0.0],
        };
        flag(p, 0.5, RED, None);
    }
    for c in [[-90.0, -90.0], [90.0, -90.0], [-90.0, 90.0], [90.0, 90.0]] {
        flag(c, 3.6, BLACK, None);
    }
    flag([-90.0, 75.0], 2.0, BLACK, None);
    for t in RING {
        for c in [[t, 90.0], [t, -90.0], [90.0, t], [-90.0, t]] {
            flag(c, 1.2, BLACK, None);
        }
    }

    let [w, h] = scene.view.size();
    let photo = matches!(scene.view, View::Photo { .. });
    let sub = 2;
    let seed = scene.seed;
    let mut buf = vec![0f32; 3 * w as usize * h as usize];
    // Reflectance of the sheet at `p` (mm) for a pixel `aa` mm across.
    let sheet = |p: [f64; 2], aa: f64| -> [f64; 3] {
        let out = scene.page.outside_mm(p);
        if out > 0.0 {
            let pg = &scene.page;
            let shade = if pg.shadow_mm > 0.0 {
                1.0 - pg.shadow_depth * (-out / pg.shadow_mm).exp()
            } else {
                1.0
            };
            return pg.lid.map(|v| v * shade);
        }
        let mut rgb = [0.93, 0.92, 0.885];
        let Some(cell) = idx(p) else {
            return rgb;
        };
        let bits = near[cell];
        if bits == 0 {
            return rgb;
        }
        let mut g: f64 = 0.0;
        if bits & GRAPHITE != 0 {
            for grid in &grids {
                g = g.max(grid.at(p));
            }
            if g > 0.0 {
                // Paper tooth: graphite on the crests.
                let tooth = 0.65 + 0.35 * value_noise(p, 0.07, seed ^ 0xA5);
                g *= tooth;
            }
        }
        if bits & SPECK != 0 {
            for &i in specks.get(&cell).into_iter().flatten() {
                if let Some(d) = scene.dust.get(i) {
                    let dd = (p[0] - d[0]).hypot(p[1] - d[1]);
                    let cov = (0.5 - (dd - d[2]) / aa).clamp(0.0, 1.0);
                    g = g.max(cov * d[3]);
                } else if let Some(f) = scene.fibres.get(i - n_dust) {
                    let dd = seg_dist(p, [f[0], f[1]], [f[2], f[3]]);
                    g = g.max((0.5 - (dd - 0.03) / aa).clamp(0.0, 1.0) * 0.3);
                }
            }
        }
        let red = if bits & RED != 0 {
            red_at(scene.printed, p, aa)
        } else {
            0.0
        };
        let black = if bits & BLACK != 0 {
            black_at(p, aa)
        } else {
            0.0
        };
        let tint = [1.0 - 0.08 * red, 1.0 - 0.78 * red, 1.0 - 0.74 * red];
        for k in 0..3 {
            rgb[k] *= tint[k] * (1.0 - g) * (1.0 - 0.93 * black);
        }
        rgb
    };
    for y in 0..h {
        for x in 0..w {
            let centre = [x as f64 + 0.5, y as f64 + 0.5];
            let Some(pm) = on_paper(scene, centre) else {
                continue;
            };
            let inked = idx(pm).is_some_and(|k| near[k] != 0);
            let rgb = if inked {
                // Pixel size in mm from the neighbouring pixel.
                let aa = scene
                    .view
                    .to_mm([centre[0] + 1.0, centre[1]])
                    .map_or(0.1, |q| (q[0] - pm[0]).hypot(q[1] - pm[1]))
                    / sub as f64;
                let mut acc = [0.0; 3];
                for j in 0..sub {
                    for i in 0..sub {
                        let q = [
                            x as f64 + (i as f64 + 0.5) / sub as f64,
                            y as f64 + (j as f64 + 0.5) / sub as f64,
                        ];
                        if let Some(pq) = on_paper(scene, q) {
                            let v = sheet(pq, aa);
                            for k in 0..3 {
                                acc[k] += v[k];
                            }
                        }
                    }
                }
                acc.map(|a| a / (sub * sub) as f64)
            } else {
                sheet(pm, 0.1)
            };
            // Light: linear field in sheet mm, a vignette in the image, a soft shadow edge.
            let [l0, gx, gy, vig] = scene.light;
            let mut light = l0 * (1.0 + gx * pm[0] / 100.0 + gy * pm[1] / 100.0);
            if photo {
                let (cx, cy) = (0.5 * w as f64, 0.5 * h as f64);
                let r2 = ((x as f64 - cx).powi(2) + (y as f64 - cy).powi(2)) / (cx * cx + cy * cy);
                light *= 1.0 - vig * r2;
                let edge = (pm[0] * 0.6 + pm[1] * 0.8 - 40.0) / 25.0;
                light *= 1.0 - 0.22 / (1.0 + (-edge).exp());
                if let Some(hand) = &scene.hand {
                    light *= hand.light_at(pm);
                }
            }
            let o = 3 * (y as usize * w as usize + x as usize);
            for k in 0..3 {
                let tri = unit(seed ^ (o as u64 + k as u64).wrapping_mul(0x9E37))
                    + unit(
                        (seed.wrapping_add(77)) ^ (o as u64 + k as u64).wrapping_mul(0x5851_F42D),
                    )
                    - 1.0;
                buf[o + k] = (255.0 * light * rgb[k] + scene.noise * tri) as f32;
            }
        }
    }
    if photo {
        blur(&mut buf, w as usize, h as usize);
    }
    if let Some(curve) = scene.tone {
        for v in buf.iter_mut() {
            *v = (255.0 * curve((f64::from(*v) / 255.0).clamp(0.0, 1.0))) as f32;
        }
    }
    let img = RgbImage::from_fn(w, h, |x, y| {
        let o = 3 * (y as usize * w as usize + x as usize);
        image::Rgb([0, 1, 2].map(|k| buf[o + k].round().clamp(0.0, 255.0) as u8))
    });
    match scene.jpeg {
        Some(q) => jpeg_roundtrip(&img, q).unwrap_or(img),
        None => img,
    }
}

fn hash(a: u64) -> u64 {
    let mut z = a.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn unit(a: u64) -> f64 {
    (hash(a) >> 11) as f64 / (1u64 << 53) as f64
}

/// Value noise on a lattice of `cell` mm, bilinear, in [0, 1].
fn value_noise(p: [f64; 2], cell: f64, seed: u64) -> f64 {
    let (x, y) = (p[0] / cell, p[1] / cell);
    let (xi, yi) = (x.floor(), y.floor());
    let (fx, fy) = (x - xi, y - yi);
    let at = |i: f64, j: f64| {
        unit(seed ^ ((i as i64 as u64).wrapping_mul(0x1000_0000_01B3)) ^ (j as i64 as u64) << 21)
    };
    let (a, b, c, d) = (
        at(xi, yi),
        at(xi + 1.0, yi),
        at(xi, yi + 1.0),
        at(xi + 1.0, yi + 1.0),
    );
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    (a * (1.0 - sx) + b * sx) * (1.0 - sy) + (c * (1.0 - sx) + d * sx) * sy
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

fn blur(buf: &mut [f32], w: usize, h: usize) {
    let mut tmp = buf.to_vec();
    for y in 0..h {
        for x in 1..w.saturating_sub(1) {
            for k in 0..3 {
                let o = 3 * (y * w + x) + k;
                tmp[o] = 0.25 * buf[o - 3] + 0.5 * buf[o] + 0.25 * buf[o + 3];
            }
        }
    }
    for y in 1..h.saturating_sub(1) {
        for x in 0..w {
            for k in 0..3 {
                let o = 3 * (y * w + x) + k;
                buf[o] = 0.25 * tmp[o - 3 * w] + 0.5 * tmp[o] + 0.25 * tmp[o + 3 * w];
            }
        }
    }
}

fn jpeg_roundtrip(img: &RgbImage, quality: u8) -> Option<RgbImage> {
    let mut bytes = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality);
    img.write_with_encoder(enc).ok()?;
    image::load_from_memory(&bytes).ok().map(|d| d.to_rgb8())
}
