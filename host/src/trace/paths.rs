//! Every drawn line of a drawing as a path of its own (`rigctl trace --paths DIR`): the chains
//! of linked pieces ([`super::stages::link`]) of at least [`LinkParams::min_mark_mm`] are each judged as the drawn
//! path is in the single-path mode (bridged across the marks that touch it, its bridges
//! refitted, the gaps beyond its free ends and the marks that may continue it listed); shorter
//! chains are strays (dust, flicks), listed apart. Written as one CSV `x,y` per path and a JSON
//! summary.

use super::chain::{resample, PieceMm, Stroke};
use super::stages::lines::{self, DrawnLine, Loose, LooseWhat};
use super::stages::link::{orient, Gap, LeftOut, LeftOutKind, Network, Strokes};
use super::{write_csv, CameraModel, Fiducials, TraceError, TraceOptions};
use crate::io::atomic::write_bytes_atomic;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// One drawn line.
#[derive(Debug, Clone)]
pub struct DrawnPath {
    /// The centreline, resampled at the requested spacing, bridges included.
    pub stroke: Stroke,
    /// Its gaps: bridged ones in order along it, then the missing ones (too long to bridge).
    pub gaps: Vec<Gap>,
    /// Marks ahead of one of its free ends that may continue it (written as paths of their
    /// own when long enough, so the drawn line is split).
    pub continued_by: Vec<LeftOut>,
    /// Length of the end left out where an open line ends on itself and was closed there (a
    /// corner drawn past), mm.
    pub overshoot_mm: f64,
    /// The chain of linked pieces it was made of.
    pub(crate) chain: usize,
    /// What lies beyond its free ends: each missing gap and each mark that may continue it.
    pub(crate) beyond: Vec<Beyond>,
}

/// A missing gap or a mark that may continue a path, beyond one of its free ends.
#[derive(Debug, Clone)]
pub(crate) struct Beyond {
    /// The chain it leads to (`None`: the path's own other end).
    pub chain: Option<usize>,
    /// The free end and its outward direction.
    pub end_mm: [f64; 2],
    pub dir: [f64; 2],
    pub what: LooseWhat,
}

impl DrawnPath {
    /// Whether the path is a whole drawn line: no gap too long to bridge, nothing that may
    /// continue it.
    pub fn is_whole(&self) -> bool {
        self.gaps.iter().all(|g| g.bridged) && self.continued_by.is_empty()
    }
}

/// Every drawn line of an image.
#[derive(Debug, Clone)]
pub struct Drawing {
    /// The paths, longest first.
    pub paths: Vec<DrawnPath>,
    /// The drawn lines: the paths that run alongside each other grouped as the passes of one
    /// line ([`super::stages::lines`]), longest first.
    pub lines: Vec<DrawnLine>,
    /// Marks shorter than a path (dust, fibres, flicks), longest first.
    pub strays: Vec<LeftOut>,
    /// The strays' points, sheet mm, resampled (in the order they were found, not that of
    /// `strays`).
    pub(crate) stray_points: Vec<Vec<[f64; 2]>>,
    /// Image scale, pixels per mm.
    pub px_per_mm: f64,
    /// The camera model and the fiducials (fiducial mapping only).
    pub camera: Option<CameraModel>,
    pub fiducials: Option<Fiducials>,
}

impl Drawing {
    /// Whether every drawn line is whole (FORMATS.md: exit 0 only then).
    pub fn is_whole(&self) -> bool {
        self.lines.iter().all(DrawnLine::is_whole)
    }
}

/// Links `pieces` and judges every chain of path size. `None` without pieces.
pub(super) fn drawing(pieces: &[PieceMm], opts: &TraceOptions, px_per_mm: f64) -> Option<Drawing> {
    let net = Network::build(pieces, opts.max_gap_mm, Strokes::PASSES, &opts.params.link)?;
    let min_len_mm = opts.params.link.min_mark_mm.max(opts.min_stroke_mm);
    let mut paths = Vec::new();
    let mut strays = Vec::new();
    let mut stray_pts = Vec::new();
    for (ci, &len) in net.lengths.iter().enumerate() {
        let path = (len >= min_len_mm).then(|| judged_path(&net, ci, opts));
        // A chain is a stray when shorter than a path, also once cut across what touches it.
        let length_mm = path.as_ref().map_or(len, |p| p.stroke.length_mm());
        match path {
            Some(p) if length_mm >= min_len_mm => paths.push(p),
            _ => {
                let pts = &net.chain_stroke(ci).points_mm;
                stray_pts.push(resample(pts, false, opts.spacing_mm));
                if let (Some(&from_mm), Some(&to_mm)) = (pts.first(), pts.last()) {
                    strays.push(LeftOut {
                        from_mm,
                        to_mm,
                        length_mm,
                        kind: if length_mm < opts.params.link.min_mark_mm {
                            LeftOutKind::Speck
                        } else {
                            LeftOutKind::Mark
                        },
                    });
                }
            }
        }
    }
    paths.sort_by(|a, b| b.stroke.length_mm().total_cmp(&a.stroke.length_mm()));
    strays.sort_by(|a, b| b.length_mm.total_cmp(&a.length_mm));
    let mut path_of_chain: Vec<Option<usize>> = vec![None; net.lengths.len()];
    for (i, p) in paths.iter().enumerate() {
        path_of_chain[p.chain] = Some(i);
    }
    let loose: Vec<Vec<Loose>> = paths
        .iter()
        .map(|p| {
            p.beyond
                .iter()
                .map(|b| Loose {
                    path: b.chain.and_then(|c| path_of_chain[c]),
                    mark: b
                        .chain
                        .map(|c| net.chain_stroke(c).points_mm.clone())
                        .unwrap_or_default(),
                    end_mm: b.end_mm,
                    dir: b.dir,
                    what: b.what,
                })
                .collect()
        })
        .collect();
    let lines = lines::lines(
        &paths,
        &stray_pts,
        &loose,
        opts.max_gap_mm,
        opts.params.link.min_mark_mm,
        &opts.params.lines,
    );
    Some(Drawing {
        paths,
        lines,
        strays,
        stray_points: stray_pts,
        px_per_mm,
        camera: None,
        fiducials: None,
    })
}

/// Chain `ci` judged as a drawn line, closed where it ends on itself, resampled.
fn judged_path(net: &Network, ci: usize, opts: &TraceOptions) -> DrawnPath {
    let judged = net.judge(ci, &opts.params.link);
    let free = judged.free_ends();
    let marks: Vec<(usize, LeftOut)> = net
        .left_out_indexed(ci, &judged, &opts.params.link)
        .into_iter()
        .filter(|(_, o)| o.kind == LeftOutKind::Continues)
        .collect();
    let mut beyond = Vec::new();
    let n_bridged = judged.gaps.iter().filter(|g| g.bridged).count();
    for (k, g) in judged.gaps.iter().enumerate().filter(|(_, g)| !g.bridged) {
        let chain = judged.missing_to.get(k - n_bridged).copied().flatten();
        let (end_mm, dir) = nearest_end(&free, &[g.from_mm]);
        beyond.push(Beyond {
            chain,
            end_mm,
            dir,
            what: LooseWhat::Gap(k),
        });
    }
    for (k, (c, _)) in marks.iter().enumerate() {
        let (end_mm, dir) = nearest_end(&free, &net.chain_stroke(*c).points_mm);
        beyond.push(Beyond {
            chain: Some(*c),
            end_mm,
            dir,
            what: LooseWhat::Mark(k),
        });
    }
    let mut path = DrawnPath {
        stroke: judged.path,
        gaps: judged.gaps,
        continued_by: marks.into_iter().map(|(_, o)| o).collect(),
        overshoot_mm: 0.0,
        chain: ci,
        beyond,
    };
    close_on_itself(&mut path, opts.max_gap_mm);
    let s = &path.stroke;
    path.stroke.points_mm = resample(&s.points_mm, s.closed, opts.spacing_mm);
    path
}

/// The free end (position, outward direction) nearest to any of `pts`.
fn nearest_end(free: &[([f64; 2], [f64; 2])], pts: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let d = |e: &([f64; 2], [f64; 2])| {
        pts.iter()
            .map(|q| (q[0] - e.0[0]).hypot(q[1] - e.0[1]))
            .fold(f64::INFINITY, f64::min)
    };
    free.iter()
        .min_by(|a, b| d(a).total_cmp(&d(b)))
        .copied()
        .unwrap_or((pts.first().copied().unwrap_or([0.0; 2]), [1.0, 0.0]))
}

/// An end of an open line this close to the line near its other end closes it there, mm.
const CLOSE_TOUCH_MM: f64 = 1.5;

/// Closes an open line whose end comes back onto the line within `max_gap_mm` (along it) of its
/// other end: a shape drawn round to its start with the last corner drawn past, or stopped just
/// short of it. The line is cut where the end meets it, the part before (the overshoot) left
/// out; a closed line has no free ends, so nothing continues it.
fn close_on_itself(path: &mut DrawnPath, max_gap_mm: f64) {
    let pts = &path.stroke.points_mm;
    let n = pts.len();
    let total = path.stroke.length_mm();
    let reach = max_gap_mm.max(CLOSE_TOUCH_MM);
    if path.stroke.closed || n < 8 || total < 4.0 * reach {
        return;
    }
    let mut s = vec![0.0; n];
    for i in 1..n {
        s[i] = s[i - 1] + (pts[i][0] - pts[i - 1][0]).hypot(pts[i][1] - pts[i - 1][1]);
    }
    let near = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    // The tail's end onto the line near the head: keep head-cut `i..n`; the head's end onto
    // the line near the tail: keep `0..=j`. The shorter overshoot wins.
    let tail_on_head = (0..n)
        .take_while(|&i| s[i] <= reach)
        .filter(|&i| near(pts[n - 1], pts[i]) <= CLOSE_TOUCH_MM)
        .min_by(|&a, &b| near(pts[n - 1], pts[a]).total_cmp(&near(pts[n - 1], pts[b])))
        .map(|i| (s[i], i, n));
    let head_on_tail = (0..n)
        .rev()
        .take_while(|&j| total - s[j] <= reach)
        .filter(|&j| near(pts[0], pts[j]) <= CLOSE_TOUCH_MM)
        .min_by(|&a, &b| near(pts[0], pts[a]).total_cmp(&near(pts[0], pts[b])))
        .map(|j| (total - s[j], 0, j + 1));
    let best = match (tail_on_head, head_on_tail) {
        (Some(a), Some(b)) => Some(if a.0 <= b.0 { a } else { b }),
        (a, b) => a.or(b),
    };
    let Some((overshoot_mm, from, to)) = best else {
        return;
    };
    let closed = Stroke {
        points_mm: pts[from..to].to_vec(),
        closed: true,
        bridged_mm: path.stroke.bridged_mm,
    };
    path.stroke = orient(closed);
    path.overshoot_mm = overshoot_mm;
    path.gaps.retain(|g| g.bridged);
    path.continued_by.clear();
    path.beyond.clear();
}

/// The file name of path `i` (0-based) in the output directory.
pub fn path_file_name(i: usize) -> String {
    format!("path-{:03}.csv", i + 1)
}

/// The file name of drawn line `i` (0-based) in the output directory.
pub fn line_file_name(i: usize) -> String {
    format!("line-{:03}.csv", i + 1)
}

/// Name of the summary in the output directory.
pub const SUMMARY_FILE: &str = "paths.json";

/// Writes `drawing` into `dir` (created if missing): `path-001.csv`, ... (CSV `x,y`, mm, one
/// per path, longest first) and [`SUMMARY_FILE`]; path files of an earlier run beyond the new
/// ones are removed. Returns the summary's path.
pub fn write_drawing(dir: &Path, drawing: &Drawing) -> Result<PathBuf, TraceError> {
    let io_err = |path: &Path, source| TraceError::Write {
        path: path.to_path_buf(),
        source,
    };
    std::fs::create_dir_all(dir).map_err(|e| io_err(dir, e))?;
    // the files as one commit; numbered files of an earlier run beyond the new ones go then
    let set = crate::io::file_set::begin(dir, numbered_file)?;
    for (i, p) in drawing.paths.iter().enumerate() {
        write_csv(&dir.join(path_file_name(i)), &p.stroke.points_mm)?;
    }
    for (i, l) in drawing.lines.iter().enumerate() {
        write_csv(&dir.join(line_file_name(i)), &l.points_mm)?;
    }
    let summary = dir.join(SUMMARY_FILE);
    let text = serde_json::to_string_pretty(&summary_json(drawing)).unwrap_or_default() + "\n";
    write_bytes_atomic(&summary, text.as_bytes())?;
    set.commit()?;
    Ok(summary)
}

/// `path-NNN.csv` or `line-NNN.csv`: the numbered files of `write_drawing`.
fn numbered_file(name: &str) -> bool {
    ["path-", "line-"].iter().any(|p| {
        name.strip_prefix(p)
            .and_then(|r| r.strip_suffix(".csv"))
            .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
    })
}

fn point(p: [f64; 2]) -> Value {
    json!([round4(p[0]), round4(p[1])])
}

fn round4(v: f64) -> f64 {
    (v * 1e4).round() / 1e4
}

/// `v` (a line's or a path's object) with its gaps, bridged and missing, and the marks that may
/// continue it (the keys are written sorted, wherever they are put in).
fn with_gaps(mut v: Value, gaps: &[Gap], continued_by: &[LeftOut]) -> Value {
    if let Value::Object(m) = &mut v {
        let (bridged, missing): (Vec<&Gap>, Vec<&Gap>) = gaps.iter().partition(|g| g.bridged);
        let list = |gs: Vec<&Gap>| gs.into_iter().map(gap_json).collect::<Value>();
        m.insert("gaps_bridged".into(), list(bridged));
        m.insert("gaps_missing".into(), list(missing));
        m.insert(
            "continued_by".into(),
            continued_by.iter().map(mark_json).collect::<Value>(),
        );
    }
    v
}

fn mark_json(o: &LeftOut) -> Value {
    json!({
        "from_mm": point(o.from_mm),
        "to_mm": point(o.to_mm),
        "length_mm": round4(o.length_mm),
    })
}

fn gap_json(g: &Gap) -> Value {
    json!({
        "from_mm": point(g.from_mm),
        "to_mm": point(g.to_mm),
        "length_mm": round4(g.length_mm),
    })
}

/// The file names of the paths `idx`.
fn files(idx: &[usize]) -> Vec<String> {
    idx.iter().map(|&i| path_file_name(i)).collect()
}

/// The summary: every drawn line (its passes, ends, length, what no pass covers, what may
/// continue it, whether it is whole), every path (file, length, ends, gaps bridged and
/// missing, the marks that may continue it, whether it is whole) and the strays.
fn summary_json(d: &Drawing) -> Value {
    let lines: Vec<Value> = d
        .lines
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let line = json!({
                "file": line_file_name(i),
                "passes": files(&l.passes),
                "closed": l.closed,
                "from_mm": point(l.from_mm),
                "to_mm": point(l.to_mm),
                "length_mm": round4(l.length_mm),
                "covered_mm": round4(l.covered_mm),
                "whole": l.is_whole(),
            });
            with_gaps(line, &l.gaps, &l.continued_by)
        })
        .collect();
    let paths: Vec<Value> = d
        .paths
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let pts = &p.stroke.points_mm;
            let ends = |k: usize| pts.get(k).copied().map(point).unwrap_or(Value::Null);
            let path = json!({
                "file": path_file_name(i),
                "length_mm": round4(p.stroke.length_mm()),
                "closed": p.stroke.closed,
                "points": pts.len(),
                "from_mm": ends(0),
                "to_mm": ends(pts.len().saturating_sub(1)),
                // + 0.0 writes a bridge sum of -0 as 0
                "bridged_mm": round4(p.stroke.bridged_mm) + 0.0,
                "overshoot_mm": round4(p.overshoot_mm),
                "whole": p.is_whole(),
            });
            with_gaps(path, &p.gaps, &p.continued_by)
        })
        .collect();
    json!({
        "whole": d.is_whole(),
        "px_per_mm": round4(d.px_per_mm),
        "lines": lines,
        "paths": paths,
        "strays": d.strays.iter().map(mark_json).collect::<Vec<_>>(),
    })
}

/// An open path through `pts` with nothing bridged, missing or beyond it (unit tests).
#[cfg(test)]
pub(crate) fn open_path(pts: Vec<[f64; 2]>) -> DrawnPath {
    DrawnPath {
        stroke: Stroke {
            points_mm: pts,
            closed: false,
            bridged_mm: 0.0,
        },
        gaps: Vec::new(),
        continued_by: Vec::new(),
        overshoot_mm: 0.0,
        chain: 0,
        beyond: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A polyline through `corners`, a point every 0.25 mm.
    fn through(corners: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let mut out = Vec::new();
        for w in corners.windows(2) {
            let n = ((w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]) / 0.25).ceil() as usize;
            out.extend((0..n).map(|k| {
                let t = k as f64 / n as f64;
                [
                    w[0][0] + t * (w[1][0] - w[0][0]),
                    w[0][1] + t * (w[1][1] - w[0][1]),
                ]
            }));
        }
        out.extend(corners.last());
        out
    }

    #[test]
    fn a_box_drawn_past_its_last_corner_closes_there() {
        // From 2 mm left of the bottom-left corner, round the box and down onto the bottom.
        let mut p = open_path(through(&[
            [-2.0, 0.0],
            [40.0, 0.0],
            [40.0, 45.0],
            [0.0, 45.0],
            [0.0, 0.4],
        ]));
        close_on_itself(&mut p, 10.0);
        assert!(p.stroke.closed);
        assert!((p.overshoot_mm - 2.0).abs() < 0.3, "{}", p.overshoot_mm);
        let len = p.stroke.length_mm();
        assert!((len - 170.0).abs() < 0.5, "{len}");
    }

    #[test]
    fn lines_that_do_not_end_on_themselves_stay_open() {
        // A U: its ends 40 mm apart.
        let mut u = open_path(through(&[
            [0.0, 45.0],
            [0.0, 0.0],
            [40.0, 0.0],
            [40.0, 45.0],
        ]));
        close_on_itself(&mut u, 10.0);
        assert!(!u.stroke.closed && u.overshoot_mm == 0.0);
        // A short hook whose end comes back onto its start: shorter than 4 x the reach.
        let mut hook = open_path(through(&[[0.0, 0.0], [12.0, 0.0], [12.0, 8.0], [0.5, 0.5]]));
        close_on_itself(&mut hook, 10.0);
        assert!(!hook.stroke.closed);
        // A box whose end stops 3 mm from the line: farther than the touch distance.
        let mut gap = open_path(through(&[
            [0.0, 0.0],
            [40.0, 0.0],
            [40.0, 45.0],
            [0.0, 45.0],
            [0.0, 3.0],
        ]));
        close_on_itself(&mut gap, 10.0);
        assert!(!gap.stroke.closed);
    }
}
