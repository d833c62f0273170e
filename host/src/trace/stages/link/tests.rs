//! Linking across a skip on a crest whose curvature changes along it.

use super::continuity::continuity;
use super::end::{end_with, reads_own_bend, End};
use super::{link, LinkParams, Linking, Network, Strokes};
use crate::trace::chain::PieceMm;
use crate::trace::plane::{dist, farthest_from};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The points from arc length `s0` to `s1` (mm, 0.05 mm apart) of the curve whose heading is the
/// integral of `k(s)` from `s = -60`.
fn curve(k: impl Fn(f64) -> f64, s0: f64, s1: f64) -> Vec<[f64; 2]> {
    let ds = 0.05;
    let (mut p, mut h, mut s) = ([0.0f64, 0.0f64], 0.0f64, -60.0f64);
    let mut out = Vec::new();
    while s <= s1 {
        if s >= s0 {
            out.push(p);
        }
        let km = k(s + 0.5 * ds);
        let hm = h + 0.5 * km * ds;
        p = [p[0] + ds * hm.cos(), p[1] + ds * hm.sin()];
        h += km * ds;
        s += ds;
    }
    out
}

/// The open pieces of the curve of curvature `k` between the arc lengths of `spans`, mm.
fn pieces(k: impl Fn(f64) -> f64 + Copy, spans: &[(f64, f64)]) -> Vec<PieceMm> {
    spans
        .iter()
        .map(|&(s0, s1)| PieceMm {
            pts: curve(k, s0, s1),
            closed: false,
        })
        .collect()
}

/// The straight line from `from` heading `dir_deg` for `len` mm, a point every 0.05 mm.
fn line(from: [f64; 2], dir_deg: f64, len: f64) -> Vec<[f64; 2]> {
    let (s, c) = dir_deg.to_radians().sin_cos();
    (0..=(len / 0.05) as usize)
        .map(|i| {
            let l = i as f64 * 0.05;
            [from[0] + l * c, from[1] + l * s]
        })
        .collect()
}

/// The end at the last point of `v`, read as on the rig's one path (to the last point).
fn end_of(v: &[[f64; 2]]) -> Option<End> {
    end_with(v, 0.0, Strokes::ONE_PATH, &LinkParams::default())
}

/// The end at the first point of `v`.
fn head(mut v: Vec<[f64; 2]>) -> End {
    v.reverse();
    end_of(&v).expect("end")
}

/// Three pieces linked into one whole path, across their two gaps.
fn linked_whole_in_three(pieces: &[PieceMm]) {
    let l = link(pieces, 10.0, None, &LinkParams::default()).expect("linked");
    assert_eq!(l.pieces, 3, "{:?}", l.left_out);
    assert!(l.is_whole(), "{:?}", l.left_out);
    assert_eq!(l.gaps.len(), 2, "{:?}", l.gaps);
}

/// `pieces` linked into one whole path with one skip (a gap over 1.5 mm) of about `skip_mm`.
fn linked_with_one_skip(pieces: &[PieceMm], skip_mm: f64) -> Linking {
    let l = link(pieces, 10.0, None, &LinkParams::default()).expect("linked");
    assert_eq!(l.pieces, pieces.len(), "{:?}", l.left_out);
    assert!(l.is_whole(), "{:?}", l.left_out);
    let skip: Vec<_> = l.gaps.iter().filter(|g| g.length_mm > 1.5).collect();
    assert_eq!(skip.len(), 1, "{:?}", l.gaps);
    assert!((skip[0].length_mm - skip_mm).abs() < 0.3, "{:?}", l.gaps);
    l
}

/// A crest of radius 7.7 mm (curvature 0.13/mm, 4 mm wide) with a 5 mm skip on its flank: one
/// end reads a nearly straight curve, the other one bending hard. The curve turns across the gap
/// by the mean of the two curvatures (a curvature changing along the gap), not by either end's
/// alone: read from the nearly straight end alone, the turn is too small and the piece beyond
/// the skip is left out as one that "may continue" the path.
#[test]
fn a_skip_where_the_curvature_grows_is_bridged() {
    let k = |s: f64| 0.13 * (-(s - 8.0).powi(2) / (2.0 * 4.0f64.powi(2))).exp();
    let l = linked_with_one_skip(&pieces(k, &[(-40.0, 2.5), (7.5, 40.0)]), 5.0);
    assert_eq!(l.gaps.len(), 1);
}

/// A crest of radius 4 mm (curvature 0.25/mm, 2.5 mm wide) drawn at low resolution: the tracker
/// left it in short pieces (3.5 mm, too short to read a curvature), the one before the crest and
/// the one after it 3 mm apart across a skip on the crest itself, each meeting a long piece
/// 0.7 mm away. Neither short end bends, so each points along its own chord and the curve turns
/// across the gap by more than the tolerance of a straight continuation; it bends one way
/// through the gap, though (the chord between the ends splits the turn evenly), and is linked.
#[test]
fn a_skip_on_a_tight_crest_between_short_pieces_is_bridged() {
    let k = |s: f64| 0.25 * (-(s - 2.3).powi(2) / (2.0 * 2.5f64.powi(2))).exp();
    let spans = [(-40.0, -4.2), (-3.5, 0.8), (3.8, 8.1), (8.8, 40.0)];
    linked_with_one_skip(&pieces(k, &spans), 3.0);
}

/// The bend-through rule does not take a short stroke crossing the path for its continuation
/// (the path runs straight into the gap, the stroke leaves it at 50 deg: the turn lies on one
/// side of the chord only), nor the corner between two straight short strokes (they turn
/// across the gap but not along themselves); two short pieces of one crest continue.
#[test]
fn a_short_stroke_leaving_at_an_angle_does_not_bend_through() {
    // The path's short last piece ends at the origin heading +x; the stroke starts 2.5 mm ahead
    // and leaves at 50 deg.
    let path_end = end_of(&line([-3.5, 0.0], 0.0, 3.5)).expect("end");
    let stroke_head = head(line([2.5, 0.0], 50.0, 3.5));
    assert!(
        !path_end.k_read(&LinkParams::default()) && !stroke_head.k_read(&LinkParams::default())
    );
    assert!(continuity(&path_end, &stroke_head, 10.0, &LinkParams::default()).is_none());
    // A corner: straight short strokes at +25 and -25 deg either side of a 2.5 mm gap.
    let (c, s) = (25f64.to_radians().cos(), 25f64.to_radians().sin());
    let up = end_of(&line([-3.5 * c, -3.5 * s], 25.0, 3.5)).expect("end");
    let down = head(line([2.5, 0.0], -25.0, 3.5));
    assert!(continuity(&up, &down, 10.0, &LinkParams::default()).is_none());
    // A crest of radius 4 mm: 3.5 mm pieces either side of a 2.5 mm skip on its top.
    let k = |_: f64| -0.25;
    let crest = curve(k, -60.0, 200.0);
    let at = |s_mm: f64| (s_mm / 0.05).round() as usize;
    let (s0, gap) = (60.0, 2.5);
    let before = crest[at(s0 - 3.5)..=at(s0)].to_vec();
    let after = crest[at(s0 + gap)..=at(s0 + gap + 3.5)].to_vec();
    let (a, b) = (end_of(&before).expect("end"), head(after));
    assert!(!a.k_read(&LinkParams::default()) && !b.k_read(&LinkParams::default()));
    assert!(continuity(&a, &b, 10.0, &LinkParams::default()).is_some());
}

/// A crest of radius 5 mm (curvature 0.2/mm) with a 2 mm skip on its top, between long pieces:
/// each end reads its curvature only up to the clamp, so its tangent at the skip is off by
/// about 20 deg and the arcs miss. The path bends one way through the gap and both ends bend
/// with it: linked. Two long straight pieces meeting at a corner across the same gap turn as
/// much, but not along themselves: not linked.
#[test]
fn a_skip_on_a_crest_between_long_pieces_is_bridged() {
    let k = |s: f64| 0.2 / (1.0 + (s / 4.0).powi(2));
    let l = linked_with_one_skip(&pieces(k, &[(-40.0, -1.0), (1.0, 40.0)]), 2.0);
    assert_eq!(l.gaps.len(), 1, "{:?}", l.gaps);
    // The corner: 20 mm straight pieces at +30 and -30 deg either side of a 2 mm gap.
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let up = end_of(&line([-20.0 * c - 1.0, -20.0 * s], 30.0, 20.0)).expect("end");
    let down = head(line([1.0, 0.0], -30.0, 20.0));
    assert!(up.k_read(&LinkParams::default()) && down.k_read(&LinkParams::default()));
    assert!(continuity(&up, &down, 10.0, &LinkParams::default()).is_none());
}

/// The farthest any point of `pts` within `reach` mm of `centre` lies from the dense polyline
/// `truth`, mm.
fn worst_near(pts: &[[f64; 2]], truth: &[[f64; 2]], centre: [f64; 2], reach: f64) -> f64 {
    farthest_from(pts.iter().filter(|p| dist(**p, centre) <= reach), truth)
}

/// A wave (curvature up to 0.15/mm, changing sign every 25 mm) with a 5.5 mm skip across a
/// crest, its centres scattered across by 0.01 mm RMS (a 300 dpi scan's). On the rig's one path
/// the ends are read to their last points and the bridge refit gets the graphite right next to
/// the skip; read from 1.5 mm before each end (as a plotter's passes are), the refit spans
/// 8.5 mm and strays further from the curve (worst point within 5 mm of the skip, mean of
/// eight scatters).
#[test]
fn a_skip_on_a_wave_is_bridged_from_the_ends_themselves() {
    let k = |s: f64| 0.15 * (s / 8.0).cos();
    let truth = curve(k, -40.0, 40.0);
    let centre = curve(k, 0.0, 0.1)[0];
    let mut rng = ChaCha8Rng::seed_from_u64(24);
    let scatter = Normal::new(0.0, 0.01).expect("a normal scatter");
    let (mut one_mm, mut passes_mm) = (0.0, 0.0);
    let rounds = 8;
    for _ in 0..rounds {
        let mut parts = pieces(k, &[(-40.0, -2.75), (2.75, 40.0)]);
        for p in parts.iter_mut().flat_map(|piece| piece.pts.iter_mut()) {
            p[0] += scatter.sample(&mut rng);
            p[1] += scatter.sample(&mut rng);
        }
        let one = linked_with_one_skip(&parts, 5.5);
        one_mm += worst_near(&one.path.points_mm, &truth, centre, 5.0) / rounds as f64;
        let net =
            Network::build(&parts, 10.0, Strokes::PASSES, &LinkParams::default()).expect("network");
        let main = net.choose_main(None).expect("a chain");
        passes_mm += worst_near(
            &net.judge(main, &LinkParams::default()).path.points_mm,
            &truth,
            centre,
            5.0,
        ) / rounds as f64;
    }
    eprintln!("one path {one_mm:.4} mm, passes {passes_mm:.4} mm");
    assert!(one_mm < 0.05, "{one_mm}");
    assert!(passes_mm > 1.5 * one_mm, "{passes_mm} vs {one_mm}");
}

/// A crest of radius 2.8 mm (curvature 0.36/mm, 2.3 mm wide) 3.6 mm before the end of a long
/// piece, then a 5 mm skip where the curve has nearly straightened (0.1/mm at the end, 0.02/mm
/// beyond the skip). The end's 8 mm span reads the crest (0.26/mm, over the clamp); turned by
/// the clamped curvature its chord points the end about 35 deg off, and the piece beyond the
/// skip was left out as one that "may continue" the path. Read over the last 3 mm, the tangent
/// is within a few degrees, and the skip is bridged.
#[test]
fn a_crest_just_before_an_end_does_not_turn_its_tangent() {
    let k = |s: f64| 0.36 / (1.0 + ((s + 3.6) / 2.3).powi(2));
    let parts = pieces(k, &[(-40.0, 0.0), (5.0, 40.0)]);
    let end = end_of(&parts[0].pts).expect("end");
    assert!(end.k_raw.abs() > 0.2, "{}", end.k_raw);
    // The true heading at the end is the integral of k from s = -60.
    let heading: f64 = (0..12_000)
        .map(|i| k(-60.0 + (i as f64 + 0.5) * 0.005) * 0.005)
        .sum();
    let off_deg = (end.t[1].atan2(end.t[0]) - heading).to_degrees().abs();
    assert!(off_deg < 3.0, "tangent {off_deg:.1} deg off");
    let l = linked_with_one_skip(&parts, 5.0);
    assert_eq!(l.gaps.len(), 1, "{:?}", l.gaps);
}

/// A short piece (6 mm, its span 4.2 mm: too short to read a curvature to carry over a gap) on a
/// crest of radius 5 mm (0.2/mm), between skips of 5 and 4 mm to long, nearly straight pieces.
/// Its chord points about 19 deg off at each end, and bent by the other end's curvature (about
/// none) it stays so: the arcs miss and the pieces beyond were left out as ones that "may
/// continue" the path. Its own three points bend far beyond their noise, and its last
/// millimetre follows their circle: its tangent comes from that circle, and both skips are
/// bridged.
#[test]
fn a_short_piece_on_a_crest_takes_its_own_tangent() {
    let k = |s: f64| 0.2 * (-(s - 8.0).powi(2) / (2.0 * 3.0f64.powi(2))).exp();
    let parts = pieces(k, &[(-40.0, 0.0), (5.0, 11.0), (15.0, 50.0)]);
    let short = end_of(&parts[1].pts).expect("end");
    assert!(!short.k_read(&LinkParams::default()), "span {}", short.span);
    let heading: f64 = (0..14_200)
        .map(|i| k(-60.0 + (i as f64 + 0.5) * 0.005) * 0.005)
        .sum();
    let own = short.t_own.expect("the short piece's own tangent");
    let off_deg = (own[1].atan2(own[0]) - heading).to_degrees().abs();
    assert!(off_deg < 3.0, "own tangent {off_deg:.1} deg off");
    linked_whole_in_three(&parts);
}

/// A short straight piece, scattered by 0.03 mm, does not show a bend of its own (its three
/// points do not bend beyond twice their noise), and a short bent piece whose last millimetre
/// hooks off its circle by 20 deg (the pencil's flick at a skip) reads no own tangent.
#[test]
fn a_straight_or_hooked_short_piece_keeps_its_chord() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let scatter = Normal::new(0.0, 0.03).expect("a normal scatter");
    for _ in 0..20 {
        let mut v = line([0.0, 0.0], 10.0, 5.0);
        for p in v.iter_mut() {
            p[1] += scatter.sample(&mut rng);
        }
        assert!(!reads_own_bend(
            &end_of(&v).expect("end"),
            &LinkParams::default()
        ));
    }
    let k = |_: f64| 0.2;
    let mut bent = curve(k, 0.0, 5.0);
    let last = *bent.last().expect("a point");
    let hook = line(last, 0.2 * 65.0 * 180.0 / std::f64::consts::PI - 20.0, 1.0);
    bent.extend(hook.into_iter().skip(1));
    let e = end_of(&bent).expect("end");
    assert!(!e.k_read(&LinkParams::default()), "span {}", e.span);
    assert!(e.t_own.is_none());
    let e = end_of(&curve(k, 0.0, 6.0)).expect("end");
    assert!(reads_own_bend(&e, &LinkParams::default()));
}

/// A long piece ends on a crest's flank (0.14/mm 6 mm before its end, 0.07 at it: its 8 mm read
/// over the clamp), then a 5.7 mm skip to a short piece (its span 4.8 mm) where the curve has
/// nearly straightened (0.01-0.02/mm), then a 3 mm skip. Bent by the long end's clamped
/// curvature, the short piece's tangent turns 14 deg too far and the skip is not bridged (the
/// pieces beyond it were left out as ones that "may continue" the path). Its own points show
/// it does not bend that much: it takes its own tangent, and both skips are bridged.
#[test]
fn a_short_piece_past_a_crest_is_not_bent_by_it() {
    let k = |s: f64| 0.14 * (-(s + 6.0).powi(2) / (2.0 * 5.0f64.powi(2))).exp();
    let parts = pieces(k, &[(-40.0, 0.0), (5.7, 12.5), (15.5, 50.0)]);
    let short = head(parts[1].pts.clone());
    assert!(!short.k_read(&LinkParams::default()), "span {}", short.span);
    assert!(
        !reads_own_bend(&short, &LinkParams::default()),
        "k_raw {}",
        short.k_raw
    );
    linked_whole_in_three(&parts);
}

/// A crest of radius 3.6 mm (curvature 0.28/mm) with a 5.5 mm skip just past its top, and the
/// stroke before the skip only 2.9 mm long (a 1.2 mm skip before it): too short to read its own
/// bend, so the first round cannot tell the crest from a corner and leaves the two apart. Read
/// from the chain it is already linked to (its stroke and the one before, bridged), the end bends
/// with the crest: linked, one path.
#[test]
fn a_short_stroke_between_skips_on_a_crest_is_read_through_its_chain() {
    let k = |s: f64| -0.28 * (-(s * s) / (2.0 * 3.5f64.powi(2))).exp();
    let spans = [(-60.0, -7.5), (-6.3, -3.4), (2.1, 60.0)];
    let l = link(&pieces(k, &spans), 10.0, None, &LinkParams::default()).expect("linked");
    assert_eq!(l.pieces, 3, "{:?}", l.left_out);
    assert!(l.is_whole(), "{:?}", l.left_out);
    let skips: Vec<f64> = l.gaps.iter().map(|g| g.length_mm).collect();
    assert_eq!(skips.len(), 2, "{skips:?}");
}

/// The same crest with a 5.5 mm skip just past its top, between long strokes: beyond the skip
/// the curve straightens within a few millimetres, so its end's 8 mm read a mean curvature under
/// half the turn across the gap, as a corner's straight stroke would. Its last 5 mm bend with
/// the crest: linked.
#[test]
fn a_crest_that_straightens_past_its_skip_bends_through() {
    let k = |s: f64| -0.28 * (-(s * s) / (2.0 * 3.5f64.powi(2))).exp();
    let l = linked_with_one_skip(&pieces(k, &[(-60.0, -1.0), (4.5, 60.0)]), 5.5);
    assert_eq!(l.gaps.len(), 1, "{:?}", l.gaps);
}
