//! Photos of a sheet that does not lie flat: bows (both edges up) and lifted edges of
//! 0.25-5 mm, about axes along either side of the sheet (the project's renderer, `synth::Bend`: a
//! parabola, the axis within 10 degrees of x or y) or at any angle (the independent renderer,
//! `render2::Sag`: a cosine roll or a cubic curl). The truth is the drawn path on the paper
//! itself (unrolled). The rule: never exit 0 below 0.95 coverage or above 0.05 mm RMS; a bend
//! is either traced within those or refused naming the sheet as not flat (exit 2).

use super::render2::Sag;
use super::{case, render_independent_with, render_project_with, shot, trace_outcome, Kind};
use rigctl::trace::synth::{Bend, BendShape, DeviceTone};

const HEIGHTS_MM: [f64; 6] = [0.25, 0.5, 1.0, 2.0, 3.0, 5.0];

/// Counts of a set: images, exit 0 within the photo bar (0.03 mm), exit 0 within 0.05 mm and
/// 0.95, refused naming the bend, refused otherwise, and exit 0 on a wrong trace.
#[derive(Debug, Default)]
struct Counts {
    n: usize,
    within: usize,
    over_photo_bar: usize,
    refused_not_flat: usize,
    refused_other: usize,
    wrong: usize,
}

fn tally(name: &str, seed: u64, what: &str, o: &super::Outcome, k: &mut Counts) {
    k.n += 1;
    let verdict = if !o.exit0 {
        if o.note.contains("not flat") {
            k.refused_not_flat += 1;
            "refused: not flat"
        } else {
            k.refused_other += 1;
            "refused"
        }
    } else if o.coverage < 0.95 || o.rms > 0.05 {
        k.wrong += 1;
        "WRONG"
    } else if o.rms > 0.03 {
        k.over_photo_bar += 1;
        "over the photo bar"
    } else {
        k.within += 1;
        "within"
    };
    eprintln!(
        "{name} seed {seed:>3} {what}: coverage {:.4}, rms {:.4} mm, {verdict} ({})",
        o.coverage, o.rms, o.note
    );
}

#[test]
fn project_renderer_bent_sheets_are_never_passed_wrong() {
    let mut k = Counts::default();
    for seed in 1..25u64 {
        let c = case(seed, false, false);
        let h = HEIGHTS_MM[(seed % 6) as usize];
        let axis = if seed % 4 < 2 { 0.0 } else { 90.0 } + (seed as f64 * 7.3) % 20.0 - 10.0;
        let bend = Bend {
            shape: if seed % 2 == 0 {
                BendShape::Bow
            } else {
                BendShape::LiftedEdge
            },
            height_mm: h,
            axis_deg: axis,
            half_width_mm: if axis.abs() < 45.0 { 148.5 } else { 105.0 },
        };
        let img = render_project_with(&c, Kind::Photo, seed, DeviceTone::Linear, Some(bend));
        let o = trace_outcome(&img, &c);
        let what = format!("{:?} {h} mm, axis {axis:.0} deg, {}", bend.shape, c.shape);
        tally("project bent", seed, &what, &o, &mut k);
    }
    eprintln!("project bent: {k:?}");
    assert_eq!(k.wrong, 0, "{k:?}");
    assert!(k.within + k.refused_not_flat >= k.n * 9 / 10, "{k:?}");
}

#[test]
fn independent_renderer_sagging_sheets_are_never_passed_wrong() {
    let mut k = Counts::default();
    for seed in 1..25u64 {
        let c = case(seed, false, false);
        let h = HEIGHTS_MM[((seed + 3) % 6) as usize];
        let sag = Sag {
            height_mm: h,
            across_rad: (seed as f64 * 0.77) % std::f64::consts::PI,
            half_mm: 120.0,
            curl: seed % 3 == 0,
        };
        let img = render_independent_with(
            &c,
            Kind::Photo,
            &shot(Kind::Photo, seed),
            seed,
            None,
            Some(sag),
        );
        let o = trace_outcome(&img, &c);
        let what = format!(
            "{} {h} mm, across {:.0} deg, {}",
            if sag.curl { "curl" } else { "roll" },
            sag.across_rad.to_degrees(),
            c.shape
        );
        tally("independent sagging", seed, &what, &o, &mut k);
    }
    eprintln!("independent sagging: {k:?}");
    assert_eq!(k.wrong, 0, "{k:?}");
    assert!(k.within + k.refused_not_flat >= k.n * 9 / 10, "{k:?}");
}
