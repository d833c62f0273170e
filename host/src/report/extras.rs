//! Pieces from the other tools when the run directory holds them: the planned poses
//! (`plan.csv` and `plan.json` from `rigctl plan`) and the trace overlays (`*overlay*.png` from
//! `rigctl trace --overlay`), embedded so that the page stays self-contained.

use serde_json::Value;

use super::markup::figure;
use super::run_dir::RunDir;
use super::Figure;
use crate::io::table::{Table, TableError};
use crate::plot::WorkspaceViews;

/// One parameter's sigma: planned, random poses, achieved.
#[derive(Debug, Clone, PartialEq)]
pub struct SigmaRow {
    /// Parameter name.
    pub name: String,
    /// Expected one-sigma with the planned poses (plan.json `expected_sigma`).
    pub expected: Option<f64>,
    /// The same number of random poses (`random_sigma`).
    pub random: Option<f64>,
    /// Achieved by a calibration (`calibrate*.json` `sigma`).
    pub achieved: Option<f64>,
}

/// The plan section.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlanSection {
    /// Files used.
    pub source: String,
    /// Planned poses in `plan.csv`.
    pub n_poses: Option<usize>,
    /// The poses in the workspace (x-y and x-z).
    pub figure: Option<Figure>,
    /// Key facts of plan.json (criterion, condition numbers, ...).
    pub facts: Vec<(String, String)>,
    /// Expected vs achieved sigma per parameter.
    pub sigma: Vec<SigmaRow>,
    /// Which calibrate document the achieved sigmas come from.
    pub achieved_source: Option<String>,
}

/// A raster image embedded in the page (a trace overlay).
#[derive(Debug, Clone, PartialEq)]
pub struct ImageFigure {
    /// What to look at.
    pub caption: String,
    /// PNG bytes, base64.
    pub png_base64: String,
    /// Size as embedded (px).
    pub width_px: u32,
    /// Size as embedded (px).
    pub height_px: u32,
}

/// Largest width an overlay is embedded at (px); larger images are downscaled.
pub const OVERLAY_MAX_WIDTH_PX: u32 = 1400;

/// Named point sets (mm, frame R), as [`WorkspaceViews`] draws them.
type PointSets = Vec<(String, Vec<[f64; 3]>)>;

/// The nominal points of `plan.csv`: `nom_x,nom_y,nom_z` (a chain's tool) as one set, else a
/// tree's `nom_x<k>,nom_y<k>,nom_z<k>` as one set per tip, named from `tips` (plan.json's) when
/// it has one name per tip.
fn read_plan_positions(path: &std::path::Path, tips: &[String]) -> Result<PointSets, TableError> {
    let t = Table::read(path)?;
    let read = |cols: [usize; 3]| -> Result<Vec<[f64; 3]>, TableError> {
        t.rows.iter().map(|r| t.numbers(r, cols)).collect()
    };
    if t.find("nom_x").is_some() || t.find("nom_x1").is_none() {
        let cols = [t.need("nom_x")?, t.need("nom_y")?, t.need("nom_z")?];
        return Ok(vec![("planned".to_string(), read(cols)?)]);
    }
    let mut sets = Vec::new();
    for k in 1.. {
        let Some(x) = t.find(&format!("nom_x{k}")) else {
            break;
        };
        let cols = [
            x,
            t.need(&format!("nom_y{k}"))?,
            t.need(&format!("nom_z{k}"))?,
        ];
        sets.push((format!("tip {k}"), read(cols)?));
    }
    if tips.len() == sets.len() {
        for (set, name) in sets.iter_mut().zip(tips) {
            set.0 = format!("tip {name}");
        }
    }
    Ok(sets)
}

/// The plan section, when the run directory holds `plan.csv` or `plan.json`.
pub(crate) fn plan_section(run: &RunDir, notes: &mut Vec<String>) -> Option<PlanSection> {
    if run.plan_csv.is_none() && run.plan_json.is_none() {
        return None;
    }
    let mut sec = PlanSection::default();
    let mut sources = Vec::new();
    if let Some(path) = &run.plan_csv {
        let tips = super::markup::strings(run.plan_json.as_ref().and_then(|(_, d)| d.get("tips")));
        match read_plan_positions(path, &tips) {
            Ok(sets) => {
                sources.push("plan.csv".to_string());
                let n = sets.first().map_or(0, |s| s.1.len());
                sec.n_poses = Some(n);
                let what = if sets.len() > 1 {
                    "every tip's point of the nominal tree"
                } else {
                    "tool position of the nominal model"
                };
                sec.figure = figure(
                    format!("The {n} planned poses, {what} seen from above (x-y) and from the side (x-z): they should fill the working volume, not a corner of it."),
                    &WorkspaceViews {
                        title: "Planned poses in the workspace (frame R)".into(),
                        sets,
                    },
                    notes,
                );
            }
            Err(e) => notes.push(format!("plan poses skipped: {e}")),
        }
    }
    if let Some((name, doc)) = &run.plan_json {
        sources.push(name.clone());
        sec.facts = plan_facts(doc);
        let (achieved_source, achieved) = run
            .calibrate
            .iter()
            .find_map(|(n, d)| d.get("sigma").and_then(Value::as_object).map(|s| (n, s)))
            .map_or((None, None), |(n, s)| (Some(n.clone()), Some(s)));
        sec.achieved_source = achieved_source;
        let num = |m: Option<&serde_json::Map<String, Value>>, k: &str| {
            m.and_then(|m| m.get(k)).and_then(Value::as_f64)
        };
        let expected = doc.get("expected_sigma").and_then(Value::as_object);
        let random = doc.get("random_sigma").and_then(Value::as_object);
        sec.sigma = expected
            .map(|e| {
                e.keys()
                    .map(|k| SigmaRow {
                        name: k.clone(),
                        expected: num(expected, k),
                        random: num(random, k),
                        achieved: num(achieved, k),
                    })
                    .collect()
            })
            .unwrap_or_default();
    }
    if sources.is_empty() {
        return None;
    }
    sec.source = sources.join(", ");
    Some(sec)
}

/// The `--sheets` ranking of plan.json as facts: reachable count, the best sheets and pairs
/// with what they leave blind.
fn sheet_facts(sh: &Value, out: &mut Vec<(String, String)>) {
    let u = |v: &Value, k: &str| v.get(k).and_then(Value::as_u64).unwrap_or(0);
    out.push((
        "pencil sheets reachable".into(),
        format!("{} of {} candidates", u(sh, "reachable"), u(sh, "tried")),
    ));
    let describe = |e: &Value| -> String {
        let blind: Vec<String> = e
            .get("blind")
            .and_then(Value::as_array)
            .map(|b| b.iter().map(super::docs::compact).collect())
            .unwrap_or_default();
        let med = e.get("median_scaled_sigma").and_then(Value::as_f64);
        format!(
            "{} identifiable, blind: {}; median sigma {} mm",
            e.get("identifiable")
                .and_then(Value::as_array)
                .map_or(0, Vec::len),
            if blind.is_empty() {
                "none".into()
            } else {
                blind.join(", ")
            },
            med.map_or("-".into(), |m| format!("{m:.4}"))
        )
    };
    let label = |e: &Value| e.get("label").map(super::docs::compact).unwrap_or_default();
    let ranked = sh.get("ranked").and_then(Value::as_array);
    for e in ranked.into_iter().flatten().take(3) {
        out.push((format!("sheet #{} {}", u(e, "rank"), label(e)), describe(e)));
    }
    if let Some(worst) = ranked.and_then(|r| r.last()) {
        out.push((format!("worst sheet {}", label(worst)), describe(worst)));
    }
    for e in sh
        .get("pairs")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .take(2)
    {
        let labels: Vec<String> = e
            .get("labels")
            .and_then(Value::as_array)
            .map(|l| l.iter().map(super::docs::compact).collect())
            .unwrap_or_default();
        out.push((
            format!("pair #{} {}", u(e, "rank"), labels.join(" + ")),
            describe(e),
        ));
    }
}

fn plan_facts(doc: &Value) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let text = |k: &str| doc.get(k).map(super::docs::compact);
    for (k, label) in [
        ("robot", "robot"),
        ("n", "poses planned"),
        ("criterion", "criterion"),
        ("candidates", "candidate poses searched"),
    ] {
        if let Some(v) = text(k) {
            out.push((label.to_string(), v));
        }
    }
    let f = |k: &str| doc.get(k).and_then(Value::as_f64);
    if let (Some(c), Some(r)) = (f("condition_number"), f("random_condition_number")) {
        out.push((
            "condition number, planned / random poses".into(),
            format!("{c:.1} / {r:.1}"),
        ));
    }
    if let Some(r) = f("median_sigma_ratio") {
        out.push(("median sigma, planned / random".into(), format!("{r:.3}")));
    }
    if let Some(o) = doc.get("optimum").filter(|v| v.is_object()) {
        let g = |k: &str| o.get(k).and_then(Value::as_f64);
        if let (Some(r), Some(e)) = (g("median_sigma_ratio"), g("efficiency")) {
            out.push((
                "best possible on the candidates: median sigma / random; plan's efficiency".into(),
                format!("{r:.3}; {e:.3}"),
            ));
        }
    }
    if let Some(u) = doc.get("unidentifiable").and_then(Value::as_array) {
        let names: Vec<String> = u.iter().map(super::docs::compact).collect();
        out.push((
            "unidentifiable".into(),
            if names.is_empty() {
                "none".into()
            } else {
                names.join(", ")
            },
        ));
    }
    if let Some(sh) = doc.get("sheets").filter(|v| v.is_object()) {
        sheet_facts(sh, &mut out);
    }
    if doc.get("from_diagnose").is_some_and(|v| !v.is_null()) {
        out.push((
            "aimed at".into(),
            "the effects of a diagnosis (--from-diagnose)".into(),
        ));
    }
    out
}

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(c.get(1).copied().unwrap_or(0)) << 8)
            | u32::from(c.get(2).copied().unwrap_or(0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(char::from(A[(n >> (18 - 6 * k) & 63) as usize]));
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Every `*overlay*.png`, downscaled to [`OVERLAY_MAX_WIDTH_PX`] when wider.
pub(crate) fn overlay_figures(run: &RunDir, notes: &mut Vec<String>) -> Vec<ImageFigure> {
    let mut out = Vec::new();
    for path in &run.overlays {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let img = match image::open(path) {
            Ok(i) => i,
            Err(e) => {
                notes.push(format!("overlay {name} skipped: {e}"));
                continue;
            }
        };
        let img = if img.width() > OVERLAY_MAX_WIDTH_PX {
            let h = (u64::from(img.height()) * u64::from(OVERLAY_MAX_WIDTH_PX)
                / u64::from(img.width().max(1))) as u32;
            img.resize(
                OVERLAY_MAX_WIDTH_PX,
                h.max(1),
                image::imageops::FilterType::Triangle,
            )
        } else {
            img
        };
        let mut png = std::io::Cursor::new(Vec::new());
        if let Err(e) = img.to_rgb8().write_to(&mut png, image::ImageFormat::Png) {
            notes.push(format!("overlay {name} skipped: {e}"));
            continue;
        }
        out.push(ImageFigure {
            caption: format!("{name}: the traced pencil line and the fitted fiducials drawn on the scan; the trace should lie on the grey pencil line everywhere, and each fiducial mark on its disc."),
            png_base64: base64(&png.into_inner()),
            width_px: img.width(),
            height_px: img.height(),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_examples() {
        for (i, o) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(i.as_bytes()), o);
        }
    }
}
