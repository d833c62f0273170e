//! Shadows and page edges, which are illumination, not ink (issue 49, items 3 and 5).
//!
//! - Hard shadows on photos: a phone's (the project's renderer, `synth::HardShadow`: a
//!   rectangle, its edge a smoothstep penumbra) or a hand's (the independent renderer,
//!   `render2::Hand`: a palm and four fingers, curved edges, a linear penumbra), taking 0.3-0.6
//!   of the light, the edge blurred over 0-1.5 mm, at any angle, its edge across the trace area.
//! - The page's edge in scans: the print off-centre on the page by 2-6 mm sideways, so that one
//!   page edge lies inside the trace area with the lid beyond it (white, grey or black) and the
//!   edge's shadow on the lid (the project's: a band 0.3-1.5 mm wide; the independent one's: an
//!   exponential fall-off).
//!
//! The rule, per set: exit 0 only within coverage >= 0.95 and RMS <= 0.05 mm (never a wrong
//! trace passed); a refusal names its cause. Counted: within the medium's bar (photos 0.03 mm,
//! 600 dpi 0.015, 300 dpi 0.02), over it, refused, wrong.

use super::render2::{self, scan_view_wide, Hand, Page};
use super::renderers::{independent_scene, render_project_changed};
use super::{case, shot, trace_outcome, Kind, Outcome};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rigctl::trace::synth::{DeviceTone, HardShadow};

#[derive(Debug, Default)]
struct Counts {
    n: usize,
    within: usize,
    over_medium_bar: usize,
    refused: usize,
    wrong: usize,
    /// The refusals' causes, as the tracer named them (the first words of its note).
    causes: Vec<String>,
}

fn bar(kind: Kind) -> f64 {
    match kind {
        Kind::Photo => 0.03,
        Kind::Scan300 => 0.02,
        Kind::Scan600 => 0.015,
    }
}

/// Tallies one image's outcome.
fn tally(name: &str, seed: u64, kind: Kind, what: &str, o: &Outcome, k: &mut Counts) {
    k.n += 1;
    let verdict = if !o.exit0 {
        assert!(
            !o.note.is_empty(),
            "{name} seed {seed}: a refusal names its cause"
        );
        k.refused += 1;
        let text = o.note.strip_prefix("error: ").unwrap_or(&o.note);
        let text = text.split_once("; ").map_or(text, |(_, why)| why);
        let cause: String = text.chars().take(50).collect();
        k.causes.push(cause);
        "refused"
    } else if o.coverage < 0.95 || o.rms > 0.05 {
        k.wrong += 1;
        "WRONG"
    } else if o.rms > bar(kind) {
        k.over_medium_bar += 1;
        "over the medium's bar"
    } else {
        k.within += 1;
        "within"
    };
    eprintln!(
        "{name} seed {seed:>3} {kind:?} {what}: coverage {:.4}, rms {:.4} mm, {verdict} ({})",
        o.coverage, o.rms, o.note
    );
}

fn dump(name: &str, seed: u64, img: &image::RgbImage) {
    if let Some(dir) = std::env::var_os("TRACE_SHADOW_DUMP") {
        let f = std::path::Path::new(&dir).join(format!("{}_{seed}.png", name.replace(' ', "_")));
        img.save(&f).expect("dump");
    }
}

const SEEDS: std::ops::Range<u64> = 1..23;

/// The seeds: 1..23, or `TRACE_SHADOW_SEEDS=a..b` for a closer look.
fn seeds() -> std::ops::Range<u64> {
    std::env::var("TRACE_SHADOW_SEEDS")
        .ok()
        .and_then(|v| {
            let (a, b) = v.split_once("..")?;
            Some(a.parse().ok()?..b.parse().ok()?)
        })
        .unwrap_or(SEEDS)
}

/// No wrong trace passed; the counts printed.
fn check(name: &str, k: &Counts) {
    eprintln!("{name}: {k:?}");
    assert_eq!(k.wrong, 0, "{name}: exit 0 on a wrong trace: {k:?}");
}

#[test]
fn project_renderer_phone_shadows() {
    let name = "project phone shadow";
    let mut k = Counts::default();
    for seed in seeds() {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5AD0);
        let c = case(seed, false, false);
        let at = rng.gen_range(0.0..std::f64::consts::TAU);
        // The phone's near long side 20-80 mm from the centre, facing it.
        let near_mm = rng.gen_range(20.0..80.0);
        let half = [75.0, 37.0];
        let centre = [
            (near_mm + half[1]) * at.cos(),
            (near_mm + half[1]) * at.sin(),
        ];
        let hs = HardShadow {
            centre_mm: centre,
            half_size_mm: half,
            angle_deg: at.to_degrees() + 90.0 + rng.gen_range(-25.0..25.0),
            depth: rng.gen_range(0.3..0.6),
            blur_mm: rng.gen_range(0.0..1.5),
        };
        let img =
            render_project_changed(&c, Kind::Photo, seed, DeviceTone::Linear, None, |_, p| {
                p.hard_shadow = Some(hs);
            });
        dump(name, seed, &img);
        let o = trace_outcome(&img, &c);
        let what = format!(
            "{}, edge {near_mm:.0} mm out at {:.0} deg, depth {:.2}, blur {:.2} mm",
            c.shape,
            at.to_degrees(),
            hs.depth,
            hs.blur_mm
        );
        tally(name, seed, Kind::Photo, &what, &o, &mut k);
    }
    check(name, &k);
}

#[test]
fn independent_renderer_hand_shadows() {
    let name = "independent hand shadow";
    let mut k = Counts::default();
    for seed in seeds() {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x4A4D);
        let c = case(seed, false, false);
        let at = rng.gen_range(0.0..std::f64::consts::TAU);
        let hand = Hand::reaching(
            at,
            rng.gen_range(120.0..190.0),
            rng.gen_range(0.12..0.3),
            rng.gen_range(0.3..0.6),
            rng.gen_range(0.0..1.5),
        );
        let what = format!(
            "{}, palm {:.0} mm out at {:.0} deg, depth {:.2}, blur {:.2} mm",
            c.shape,
            hand.palm[0].hypot(hand.palm[1]),
            at.to_degrees(),
            hand.depth,
            hand.blur_mm
        );
        let mut scene =
            independent_scene(&c, Kind::Photo, &shot(Kind::Photo, seed), seed, None, None);
        scene.hand = Some(hand);
        let img = render2::render(&scene);
        dump(name, seed, &img);
        let o = trace_outcome(&img, &c);
        tally(name, seed, Kind::Photo, &what, &o, &mut k);
    }
    check(name, &k);
}

/// The lid beyond the page: white, grey or black.
const LIDS: [f64; 3] = [0.9, 0.55, 0.12];

#[test]
fn project_renderer_page_edge_in_scans() {
    let name = "project page edge";
    let mut k = Counts::default();
    for seed in seeds() {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xED6E);
        let kind = if seed % 2 == 0 {
            Kind::Scan300
        } else {
            Kind::Scan600
        };
        let c = case(seed, true, false);
        let side = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
        let off = rng.gen_range(2.0..6.0);
        let lid = LIDS[(seed % 3) as usize];
        let shadow = [rng.gen_range(0.3..1.5), rng.gen_range(0.3..0.7)];
        let img = render_project_changed(&c, kind, seed, DeviceTone::Linear, None, |s, _| {
            // The page's centre moved away from the edge that comes in.
            s.page_offset_mm = [-side * off, 0.0];
            s.desk_level = Some(lid);
            s.lid_shadow = Some(shadow);
        });
        dump(name, seed, &img);
        let o = trace_outcome(&img, &c);
        let what = format!(
            "{}, page edge at x {:.1} mm, lid {lid}, shadow {:.2} mm x {:.2}",
            c.shape,
            side * (105.0 - off),
            shadow[0],
            shadow[1]
        );
        tally(name, seed, kind, &what, &o, &mut k);
    }
    check(name, &k);
}

#[test]
fn independent_renderer_page_edge_in_scans() {
    let name = "independent page edge";
    let mut k = Counts::default();
    for seed in seeds() {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9A6E);
        let kind = if seed % 2 == 0 {
            Kind::Scan600
        } else {
            Kind::Scan300
        };
        let c = case(seed, true, seed % 3 == 0);
        let s = shot(kind, seed);
        let off = rng.gen_range(2.0..6.0);
        let right = rng.gen_bool(0.5);
        let lid = LIDS[((seed + 1) % 3) as usize];
        let page = Page {
            x_mm: if right {
                [-105.0 - off, 105.0 - off]
            } else {
                [-105.0 + off, 105.0 + off]
            },
            lid: [lid, lid * 0.98, lid * 0.95],
            shadow_mm: rng.gen_range(0.2..1.0),
            shadow_depth: rng.gen_range(0.3..0.8),
            ..Page::default()
        };
        let mut scene = independent_scene(&c, kind, &s, seed, None, None);
        scene.view = scan_view_wide(s.ppm * 25.4, s.rot_deg, 112.0);
        scene.page = page;
        let img = render2::render(&scene);
        dump(name, seed, &img);
        let o = trace_outcome(&img, &c);
        let what = format!(
            "{}, page edge at x {:.1} mm, lid {lid}, shadow {:.2} mm x {:.2}",
            c.shape,
            if right { 105.0 - off } else { -105.0 + off },
            page.shadow_mm,
            page.shadow_depth
        );
        tally(name, seed, kind, &what, &o, &mut k);
    }
    check(name, &k);
}
