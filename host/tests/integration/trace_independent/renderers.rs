//! The two renderers as the sets draw a case: the camera and light of a seed ([`Shot`]) and the
//! case rendered by `render2` (the independent renderer) or by the project's own
//! (`rigctl::trace::synth`), as a photo or a 300 / 600 dpi scan.

use super::cases::Case;
use super::render2::{self, photo_view, scan_view, Printed, Scene};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::sheet::ReferencePath;
use rigctl::trace::synth::{render_photo, render_scan, Bend, DeviceTone, PhotoSpec, RenderSpec};

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kind {
    Photo,
    Scan300,
    Scan600,
}

fn printed(p: Printed) -> ReferencePath {
    match p {
        Printed::Circle => ReferencePath::Circle,
        Printed::Line => ReferencePath::Line,
    }
}

/// The camera and light of a photo or scan of `seed`, drawn independently of the path.
pub(super) struct Shot {
    pub(super) ppm: f64,
    pub(super) tilt: f64,
    pub(super) azimuth: f64,
    pub(super) roll: f64,
    pub(super) k1: f64,
    pub(super) rot_deg: f64,
    pub(super) jpeg: u8,
    /// The principal point this far from the image centre, px (a photo cropped off its centre).
    pub(super) centre_off_px: f64,
}

pub(super) fn shot(kind: Kind, seed: u64) -> Shot {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5407_0000);
    Shot {
        ppm: match kind {
            Kind::Photo => rng.gen_range(200.0..300.0) / 25.4,
            Kind::Scan300 => 300.0 / 25.4,
            Kind::Scan600 => 600.0 / 25.4,
        },
        tilt: rng.gen_range(0.0f64..40.0).to_radians(),
        azimuth: rng.gen_range(0.0..std::f64::consts::TAU),
        roll: rng.gen_range(0.0..std::f64::consts::TAU),
        k1: rng.gen_range(-0.08..0.08),
        rot_deg: rng.gen_range(-4.0..4.0),
        jpeg: rng.gen_range(85..96),
        centre_off_px: 0.0,
    }
}

pub(super) fn render_independent(c: &Case, kind: Kind, seed: u64) -> image::RgbImage {
    render_independent_shot(c, kind, &shot(kind, seed), seed)
}

/// [`render_independent`] with the camera and light of `s`.
pub(super) fn render_independent_shot(
    c: &Case,
    kind: Kind,
    s: &Shot,
    seed: u64,
) -> image::RgbImage {
    render_independent_toned(c, kind, s, seed, None)
}

/// [`render_independent_shot`] written through the tone curve `tone` (`None`: linear).
pub(super) fn render_independent_toned(
    c: &Case,
    kind: Kind,
    s: &Shot,
    seed: u64,
    tone: Option<fn(f64) -> f64>,
) -> image::RgbImage {
    render_independent_with(c, kind, s, seed, tone, None)
}

/// [`render_independent_toned`] with a photo's sheet sagging by `sag`.
pub(super) fn render_independent_with(
    c: &Case,
    kind: Kind,
    s: &Shot,
    seed: u64,
    tone: Option<fn(f64) -> f64>,
    sag: Option<render2::Sag>,
) -> image::RgbImage {
    render2::render(&independent_scene(c, kind, s, seed, tone, sag))
}

/// The scene [`render_independent_with`] renders (for sets that change it further: a hand's
/// shadow, the page's edge).
pub(super) fn independent_scene(
    c: &Case,
    kind: Kind,
    s: &Shot,
    seed: u64,
    tone: Option<fn(f64) -> f64>,
    sag: Option<render2::Sag>,
) -> Scene {
    let mut marks = vec![render2::Mark {
        pts: c.truth.clone(),
        width_mm: c.width_mm,
        darkness: c.darkness,
        skips: c.skips.clone(),
    }];
    if let Some((pts, closed)) = &c.second_run {
        let mut pts = pts.clone();
        if *closed {
            pts.push(pts[0]);
        }
        marks.push(render2::Mark {
            pts,
            width_mm: c.width_mm,
            darkness: c.darkness,
            skips: Vec::new(),
        });
    }
    for extra in c.crossing.iter().chain(&c.strays) {
        marks.push(render2::Mark {
            pts: extra.clone(),
            width_mm: c.width_mm,
            darkness: c.darkness,
            skips: Vec::new(),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x11_6417);
    let (view, light, noise, jpeg) = match kind {
        Kind::Photo => (
            {
                let view = photo_view(
                    s.ppm,
                    s.tilt,
                    s.azimuth,
                    s.roll,
                    s.k1,
                    [rng.gen_range(-8.0..8.0), rng.gen_range(-8.0..8.0)],
                );
                let a = seed as f64 * 2.399_963; // a direction per seed, outside `rng`'s stream
                render2::off_centre(view, [s.centre_off_px * a.cos(), s.centre_off_px * a.sin()])
            },
            [
                rng.gen_range(0.75..0.95),
                rng.gen_range(-0.25..0.25),
                rng.gen_range(-0.25..0.25),
                rng.gen_range(0.0..0.3),
            ],
            rng.gen_range(2.0..5.0),
            Some(s.jpeg),
        ),
        _ => (
            scan_view(s.ppm * 25.4, s.rot_deg),
            [
                rng.gen_range(0.9..1.0),
                rng.gen_range(-0.04..0.04),
                rng.gen_range(-0.04..0.04),
                0.0,
            ],
            rng.gen_range(1.0..3.0),
            None,
        ),
    };
    Scene {
        printed: c.printed,
        marks,
        dust: c.dust.clone(),
        fibres: c.fibres.clone(),
        view,
        light,
        noise,
        jpeg,
        seed,
        tone,
        sag,
        hand: None,
        page: render2::Page::default(),
    }
}

pub(super) fn render_project(c: &Case, kind: Kind, seed: u64) -> image::RgbImage {
    render_project_toned(c, kind, seed, DeviceTone::Linear)
}

/// [`render_project`] written through the device's tone curve `tone`.
pub(super) fn render_project_toned(
    c: &Case,
    kind: Kind,
    seed: u64,
    tone: DeviceTone,
) -> image::RgbImage {
    render_project_with(c, kind, seed, tone, None)
}

/// [`render_project_toned`] with a photo's sheet bent by `bend`.
pub(super) fn render_project_with(
    c: &Case,
    kind: Kind,
    seed: u64,
    tone: DeviceTone,
    bend: Option<Bend>,
) -> image::RgbImage {
    render_project_changed(c, kind, seed, tone, bend, |_, _| {})
}

/// [`render_project_with`], the sheet's and the photo's specs changed by `change` before the
/// render (a hard shadow, the page's edge).
pub(super) fn render_project_changed(
    c: &Case,
    kind: Kind,
    seed: u64,
    tone: DeviceTone,
    bend: Option<Bend>,
    change: impl FnOnce(&mut RenderSpec, &mut PhotoSpec),
) -> image::RgbImage {
    let s = shot(kind, seed);
    let spec = RenderSpec {
        dpi: if kind == Kind::Photo {
            450.0
        } else {
            s.ppm * 25.4
        },
        pencil_mm: c.truth.clone(),
        pencil_closed: c.closed,
        more_pencil_mm: c.second_run.iter().cloned().collect(),
        pencil_width_mm: c.width_mm,
        pencil_darkness: c.darkness,
        reference: Some(printed(c.printed)),
        ring: true,
        rotation_deg: s.rot_deg,
        skips_mm: c.skips.clone(),
        dust_mm: c.dust.iter().map(|d| [d[0], d[1], d[2]]).collect(),
        fibres_mm: c.fibres.clone(),
        seed,
        device_tone: tone,
        ..RenderSpec::default()
    };
    let dist = 400.0;
    let half = (s.ppm * 100.0 * 1.45) as u32;
    let mut photo = PhotoSpec {
        width_px: 2 * half + 80,
        height_px: 2 * half + 80,
        focal_px: s.ppm * dist,
        distance_mm: dist,
        tilt_deg: s.tilt.to_degrees(),
        tilt_azimuth_deg: s.azimuth.to_degrees(),
        roll_deg: s.roll.to_degrees(),
        k1: s.k1,
        texture_dpi: 450.0,
        jpeg_quality: Some(s.jpeg),
        seed,
        bend,
        ..PhotoSpec::default()
    };
    let mut spec = spec;
    change(&mut spec, &mut photo);
    match kind {
        Kind::Photo => render_photo(&spec, &photo),
        _ => render_scan(&spec),
    }
}
