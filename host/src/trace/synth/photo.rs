//! A simulated phone photo of a traced sheet, for tests and benches, with exact truth: the flat
//! sheet (rendered by [`render_scan`] as a texture) seen by a pinhole camera tilted away from the
//! sheet normal, with radial lens distortion, uneven light (a gradient and the soft shadow of the
//! phone), a desk around the page, blur, sensor noise and JPEG compression.
//!
//! Camera: the sheet is the plane z = 0 (sheet mm, x right, y up); the camera looks at the sheet
//! origin from `distance_mm`, its axis tilted by `tilt_deg` from the sheet normal about an
//! in-plane axis at `tilt_azimuth_deg`, and rolled by `roll_deg`. An ideal pixel is
//! `c + f * (X_c / Z_c, Y_c / Z_c)`; the lens moves it radially about the image centre `c`:
//! `p = c + d (1 + k1 r^2 + k2 r^4)`, `d` the ideal offset, `r = |d| / f`.

use super::scan::{render_scan, RenderSpec};
use crate::sheet::{PAGE_HEIGHT_MM, PAGE_WIDTH_MM};
use image::{Rgb, RgbImage};

/// The camera and the light of a simulated photo.
#[derive(Debug, Clone, PartialEq)]
pub struct PhotoSpec {
    pub width_px: u32,
    pub height_px: u32,
    /// Focal length, pixels.
    pub focal_px: f64,
    /// Distance from the camera to the sheet origin, mm.
    pub distance_mm: f64,
    /// Angle between the camera axis and the sheet normal, degrees.
    pub tilt_deg: f64,
    /// Direction (in the sheet plane) towards which the camera is displaced, degrees from +x.
    pub tilt_azimuth_deg: f64,
    /// Rotation of the camera about its axis, degrees.
    pub roll_deg: f64,
    /// Radial distortion coefficients.
    pub k1: f64,
    pub k2: f64,
    /// Light falls linearly by this fraction across the image along `gradient_dir_deg`.
    pub gradient: f64,
    pub gradient_dir_deg: f64,
    /// Soft shadow (e.g. the phone's): centre and radius as fractions of the image, depth.
    pub shadow: Option<([f64; 2], f64, f64)>,
    /// Gaussian blur, pixels (standard deviation).
    pub blur_px: f64,
    /// Sensor noise, standard deviation in 8-bit levels.
    pub noise: f64,
    /// JPEG quality; `None`: no compression.
    pub jpeg_quality: Option<u8>,
    /// Resolution of the flat sheet texture, dpi.
    pub texture_dpi: f64,
    /// Level of the desk around the page, 0..1.
    pub desk_level: f64,
    pub seed: u64,
    /// The sheet bent (a bow, a lifted edge); `None`: flat on the desk.
    pub bend: Option<super::Bend>,
    /// A hard shadow across the sheet (a phone's, sharp-edged); `None`: none.
    pub hard_shadow: Option<super::HardShadow>,
}

impl Default for PhotoSpec {
    fn default() -> Self {
        Self {
            width_px: 4000,
            height_px: 3000,
            focal_px: 3300.0,
            distance_mm: 380.0,
            tilt_deg: 25.0,
            tilt_azimuth_deg: -70.0,
            roll_deg: 88.0,
            k1: -0.05,
            k2: 0.0,
            gradient: 0.35,
            gradient_dir_deg: 30.0,
            shadow: Some(([0.3, 0.7], 0.25, 0.35)),
            blur_px: 0.8,
            noise: 2.0,
            jpeg_quality: Some(92),
            texture_dpi: 600.0,
            desk_level: 0.35,
            seed: 7,
            bend: None,
            hard_shadow: None,
        }
    }
}

/// The pinhole camera of a [`PhotoSpec`].
#[derive(Debug, Clone, Copy)]
pub struct Camera {
    /// Rows of the world -> camera rotation.
    rot: [[f64; 3]; 3],
    /// Camera centre in the sheet frame, mm.
    centre: [f64; 3],
    f: f64,
    c: [f64; 2],
    k: [f64; 2],
}

impl Camera {
    pub fn new(p: &PhotoSpec) -> Self {
        let (t, a, r) = (
            p.tilt_deg.to_radians(),
            p.tilt_azimuth_deg.to_radians(),
            p.roll_deg.to_radians(),
        );
        // Camera centre above the sheet, displaced towards the azimuth; it looks at the origin.
        let dir = [t.sin() * a.cos(), t.sin() * a.sin(), t.cos()];
        let centre = [
            p.distance_mm * dir[0],
            p.distance_mm * dir[1],
            p.distance_mm * dir[2],
        ];
        let z = [-dir[0], -dir[1], -dir[2]]; // optical axis
        let up = if z[2].abs() > 0.99 {
            [0.0, 1.0, 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        let x0 = normalise(cross(z, up));
        let y0 = cross(z, x0);
        let (cr, sr) = (r.cos(), r.sin());
        let x = normalise([
            cr * x0[0] + sr * y0[0],
            cr * x0[1] + sr * y0[1],
            cr * x0[2] + sr * y0[2],
        ]);
        let y = cross(z, x);
        Self {
            rot: [x, y, z],
            centre,
            f: p.focal_px,
            c: [p.width_px as f64 / 2.0, p.height_px as f64 / 2.0],
            k: [p.k1, p.k2],
        }
    }

    /// Sheet mm -> pixel (with distortion); `None` behind the camera.
    pub fn project(&self, s: [f64; 2]) -> Option<[f64; 2]> {
        let v = [
            s[0] - self.centre[0],
            s[1] - self.centre[1],
            -self.centre[2],
        ];
        let xc = dot(self.rot[0], v);
        let yc = dot(self.rot[1], v);
        let zc = dot(self.rot[2], v);
        if zc <= 1e-9 {
            return None;
        }
        let d = [self.f * xc / zc, self.f * yc / zc];
        let r2 = (d[0] * d[0] + d[1] * d[1]) / (self.f * self.f);
        let g = 1.0 + self.k[0] * r2 + self.k[1] * r2 * r2;
        Some([self.c[0] + d[0] * g, self.c[1] + d[1] * g])
    }

    /// Pixel -> sheet mm: the ray's intersection with the sheet, bent by `bend` (then the
    /// paper's own, unrolled coordinates) or flat.
    pub fn unproject_onto(&self, p: [f64; 2], bend: Option<&super::Bend>) -> Option<[f64; 2]> {
        let Some(b) = bend else {
            return self.unproject(p);
        };
        let ray = self.ray(p)?;
        // The ray meets the surface where its height is the surface's there: iterate from the
        // desk plane (slopes well under 1, so this converges quickly).
        let mut z = 0.0;
        let mut q = [0.0; 2];
        for _ in 0..12 {
            let l = (z - self.centre[2]) / ray[2];
            q = [self.centre[0] + l * ray[0], self.centre[1] + l * ray[1]];
            z = b.height_at(q);
        }
        Some(b.unroll(q))
    }

    /// The world direction of the ray through pixel `p`, pointing down (`None` otherwise).
    fn ray(&self, p: [f64; 2]) -> Option<[f64; 3]> {
        let dd = [p[0] - self.c[0], p[1] - self.c[1]];
        let mut d = dd;
        for _ in 0..30 {
            let r2 = (d[0] * d[0] + d[1] * d[1]) / (self.f * self.f);
            let g = 1.0 + self.k[0] * r2 + self.k[1] * r2 * r2;
            d = [dd[0] / g, dd[1] / g];
        }
        let ray_c = [d[0] / self.f, d[1] / self.f, 1.0];
        // world ray = R^T ray_c
        let ray = [
            self.rot[0][0] * ray_c[0] + self.rot[1][0] * ray_c[1] + self.rot[2][0] * ray_c[2],
            self.rot[0][1] * ray_c[0] + self.rot[1][1] * ray_c[1] + self.rot[2][1] * ray_c[2],
            self.rot[0][2] * ray_c[0] + self.rot[1][2] * ray_c[1] + self.rot[2][2] * ray_c[2],
        ];
        (ray[2] < -1e-12).then_some(ray)
    }

    /// Pixel -> sheet mm (the ray's intersection with the sheet plane).
    pub fn unproject(&self, p: [f64; 2]) -> Option<[f64; 2]> {
        let ray = self.ray(p)?;
        let l = -self.centre[2] / ray[2];
        Some([self.centre[0] + l * ray[0], self.centre[1] + l * ray[1]])
    }
}

/// Renders the photo of the sheet `sheet` (its `dpi`, rotation, shift and mirroring are ignored:
/// the texture is the flat page at `photo.texture_dpi`). Returns the image as it would be decoded
/// from the JPEG file when `jpeg_quality` is set.
pub fn render_photo(sheet: &RenderSpec, photo: &PhotoSpec) -> RgbImage {
    let tex_spec = RenderSpec {
        dpi: photo.texture_dpi,
        rotation_deg: 0.0,
        shift_mm: [0.0, 0.0],
        mirrored: false,
        desk_level: None,
        device_tone: super::DeviceTone::Linear,
        ..sheet.clone()
    };
    let tex = render_scan(&tex_spec);
    let ppmm = photo.texture_dpi / 25.4;
    let cam = Camera::new(photo);
    let (w, h) = (photo.width_px, photo.height_px);
    let mut img = RgbImage::new(w.max(1), h.max(1));
    let desk = 255.0 * photo.desk_level;
    let (gc, gs) = (
        photo.gradient_dir_deg.to_radians().cos(),
        photo.gradient_dir_deg.to_radians().sin(),
    );
    let diag = (w as f64).hypot(h as f64);
    // A pixel's size on the sheet, mm (for a hard shadow's edge).
    let pixel_mm = photo.distance_mm / photo.focal_px.max(1e-9);
    for y in 0..h {
        for x in 0..w {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let on_sheet = cam.unproject_onto(p, photo.bend.as_ref());
            let mut v = match on_sheet {
                Some(s) => {
                    let page = [
                        (PAGE_WIDTH_MM / 2.0 + s[0]) * ppmm,
                        (PAGE_HEIGHT_MM / 2.0 - s[1]) * ppmm,
                    ];
                    sample(&tex, page).unwrap_or([desk; 3])
                }
                None => [desk; 3],
            };
            // Light: a linear gradient and a soft shadow.
            let along = ((p[0] - w as f64 / 2.0) * gc + (p[1] - h as f64 / 2.0) * gs) / diag;
            let mut light = 1.0 - photo.gradient * (along + 0.5).clamp(0.0, 1.0);
            if let Some((c, r, depth)) = photo.shadow {
                let dx = p[0] / w as f64 - c[0];
                let dy = p[1] / h as f64 - c[1];
                let q = (dx.hypot(dy) / r).min(2.0);
                let t = ((q - 0.7) / 0.6).clamp(0.0, 1.0);
                let smooth = t * t * (3.0 - 2.0 * t);
                light *= 1.0 - depth * (1.0 - smooth);
            }
            if let (Some(hs), Some(s)) = (&photo.hard_shadow, on_sheet) {
                light *= hs.light_at(s, pixel_mm);
            }
            for c in v.iter_mut() {
                *c *= light;
            }
            img.put_pixel(x, y, Rgb(v.map(|c| c.round().clamp(0.0, 255.0) as u8)));
        }
    }
    if photo.blur_px > 0.0 {
        gaussian_blur(&mut img, photo.blur_px);
    }
    add_noise(&mut img, photo.noise, photo.seed);
    sheet.device_tone.apply(&mut img);
    match photo.jpeg_quality {
        Some(q) => jpeg_roundtrip(&img, q).unwrap_or(img),
        None => img,
    }
}

/// Encodes as JPEG (quality `q`) and decodes again.
pub fn jpeg_bytes(img: &RgbImage, q: u8) -> Option<Vec<u8>> {
    let mut buf = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, q);
    img.write_with_encoder(enc).ok()?;
    Some(buf)
}

fn jpeg_roundtrip(img: &RgbImage, q: u8) -> Option<RgbImage> {
    let buf = jpeg_bytes(img, q)?;
    image::load_from_memory_with_format(&buf, image::ImageFormat::Jpeg)
        .ok()
        .map(|i| i.into_rgb8())
}

/// Bilinear sample of `img` at pixel coordinates `p` (pixel centres at `i + 0.5`).
fn sample(img: &RgbImage, p: [f64; 2]) -> Option<[f64; 3]> {
    let (fx, fy) = (p[0] - 0.5, p[1] - 0.5);
    let (x0, y0) = (fx.floor(), fy.floor());
    if x0 < 0.0 || y0 < 0.0 || x0 + 1.0 >= img.width() as f64 || y0 + 1.0 >= img.height() as f64 {
        return None;
    }
    let (ax, ay) = (fx - x0, fy - y0);
    let (x0, y0) = (x0 as u32, y0 as u32);
    let mut out = [0.0; 3];
    for (dx, dy, wgt) in [
        (0, 0, (1.0 - ax) * (1.0 - ay)),
        (1, 0, ax * (1.0 - ay)),
        (0, 1, (1.0 - ax) * ay),
        (1, 1, ax * ay),
    ] {
        let px = img.get_pixel(x0 + dx, y0 + dy);
        for c in 0..3 {
            out[c] += wgt * px[c] as f64;
        }
    }
    Some(out)
}

/// Separable Gaussian blur (kernel radius 3 sigma).
fn gaussian_blur(img: &mut RgbImage, sigma: f64) {
    let r = (3.0 * sigma).ceil() as i64;
    let kern: Vec<f64> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f64 = kern.iter().sum();
    let kern: Vec<f64> = kern.iter().map(|k| k / sum).collect();
    let (w, h) = (img.width() as i64, img.height() as i64);
    for pass in 0..2 {
        let src = img.clone();
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0.0f64; 3];
                for (j, k) in kern.iter().enumerate() {
                    let o = j as i64 - r;
                    let (sx, sy) = if pass == 0 {
                        ((x + o).clamp(0, w - 1), y)
                    } else {
                        (x, (y + o).clamp(0, h - 1))
                    };
                    let p = src.get_pixel(sx as u32, sy as u32);
                    for c in 0..3 {
                        acc[c] += k * p[c] as f64;
                    }
                }
                img.put_pixel(
                    x as u32,
                    y as u32,
                    Rgb(acc.map(|v| v.round().clamp(0.0, 255.0) as u8)),
                );
            }
        }
    }
}

fn add_noise(img: &mut RgbImage, sd: f64, seed: u64) {
    if sd <= 0.0 {
        return;
    }
    for (i, v) in img.as_mut().iter_mut().enumerate() {
        let mut z = seed
            .wrapping_add((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .wrapping_add(0x632B_E59B_D9B4_E019);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        let u1 = (z & 0xFFFF_FFFF) as f64 / 4_294_967_296.0;
        let u2 = (z >> 32) as f64 / 4_294_967_296.0;
        let n = (u1 + u2 - 1.0) * 6f64.sqrt();
        *v = (*v as f64 + sd * n).round().clamp(0.0, 255.0) as u8;
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalise(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt().max(1e-300);
    [a[0] / n, a[1] / n, a[2] / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_projection_roundtrips() {
        let cam = Camera::new(&PhotoSpec::default());
        for s in [[0.0, 0.0], [90.0, -90.0], [-100.0, 140.0]] {
            let p = cam.project(s).expect("in front");
            let back = cam.unproject(p).expect("hits the sheet");
            assert!((back[0] - s[0]).abs() < 1e-6 && (back[1] - s[1]).abs() < 1e-6);
        }
        let c = cam.project([0.0, 0.0]).expect("origin");
        assert!((c[0] - 2000.0).abs() < 1e-6 && (c[1] - 1500.0).abs() < 1e-6);
    }
}
