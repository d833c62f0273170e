//! The page: inline CSS and SVG only, no scripts, no external resources.

use std::fmt::Write as _;

pub use super::markup::escape;
use super::markup::render_figure;
use super::table::ErrorTable;
use super::Report;

const CSS: &str = "body{font-family:'DejaVu Sans',sans-serif;margin:16px auto;max-width:1180px;padding:0 12px;color:#222;line-height:1.35}\
h1{font-size:1.45em;margin:0.2em 0}h2{border-bottom:1px solid #ccc;margin-top:1.8em}h3{margin:0.8em 0 0.3em}\
table{border-collapse:collapse;margin:0.5em 0 1em}th,td{border:1px solid #bbb;padding:2px 8px}\
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}th{background:#f0f0f0;text-align:left}\
th.num{text-align:right}figure{margin:0.8em 0}figure svg,figure img{max-width:100%;height:auto;border:1px solid #ddd}\
figcaption{font-size:0.9em;color:#444}.note{color:#8a5a00}code,pre{font-size:0.85em}\
pre{background:#f6f6f6;padding:6px;overflow-x:auto;white-space:pre-wrap}\
.answer{border:2px solid #2a6;border-radius:6px;padding:8px 16px;background:#f7fcf8}\
.answer .about{margin:0.1em 0;color:#555;font-size:0.88em}.lead{font-weight:bold;margin:0.4em 0}\
.sentence{font-size:1.3em;font-weight:bold;margin:0.3em 0 0.5em;line-height:1.3}\
.unregistered,.urdf{margin:0.3em 0}.urdf{background:#fff8e6;padding:3px 6px;border-left:3px solid #c90}\
.headline{display:flex;flex-wrap:wrap;gap:16px;align-items:flex-start}.headline .words{flex:1 1 460px}\
.headline .chart{flex:0 1 560px}.headline figure{margin:0}ol.found{margin:0.1em 0;padding-left:1.6em}\
.found-head{margin:0.3em 0 0}details{margin:0.3em 0}summary{cursor:pointer}\
.evidence{color:#444;font-size:0.92em}.verdict{font-weight:bold;margin:0.4em 0 0.2em}.aliased{color:#8a5a00}\
nav.toc{margin:1em 0}nav.toc ol{columns:2;margin:0.3em 0}\
@page{size:A4;margin:12mm}\
@media print{body{max-width:none;margin:0;padding:0;font-size:9.5pt}section.details{break-before:page}\
figure,tr,.answer{break-inside:avoid}nav.toc{break-after:page}a{color:inherit;text-decoration:none}\
pre{white-space:pre-wrap}.headline .chart{flex-basis:100%}}";

fn num(v: f64, decimals: usize) -> String {
    format!("{v:.decimals$}")
}

/// A table of thesis-4.5 statistics; rows with no computed value are left out, a value that a
/// source does not have (per-axis extremes of a JSON document) is a blank cell.
fn error_table(s: &mut String, t: &ErrorTable, id: &str) {
    let _ = writeln!(
        s,
        "<h3>{}, {} {}</h3>\n<table class=\"errors\" id=\"{id}\"><tr><th>statistic</th><th>quantity</th>",
        escape(&t.title),
        t.n,
        t.noun
    );
    for c in &t.columns {
        let _ = write!(s, "<th class=\"num\">{}, mm</th>", escape(c));
    }
    s.push_str("</tr>\n");
    let mut last = "";
    for r in t.computed_rows() {
        let stat = if r.statistic != last { r.statistic } else { "" };
        last = r.statistic;
        let _ = write!(s, "<tr><th>{stat}</th><th>{}</th>", escape(r.quantity));
        for v in &r.values {
            match v {
                Some(x) => {
                    let _ = write!(s, "<td class=\"num\">{}</td>", num(*x, 4));
                }
                None => s.push_str("<td class=\"num\" title=\"not in this source\"></td>"),
            }
        }
        s.push_str("</tr>\n");
    }
    let _ = writeln!(
        s,
        "</table>\n<p class=\"src\">source: <code>{}</code></p>",
        escape(&t.source)
    );
}

/// The sections present, in page order: (id, heading).
fn sections(r: &Report) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    if !r.tables.is_empty() {
        out.push((
            "errors",
            "Position errors per set (thesis table 4.5)".to_string(),
        ));
    }
    if !r.diagnose.is_empty() {
        out.push(("diagnose", "Effects added by diagnose".to_string()));
    }
    if !r.parameters.is_empty() {
        out.push(("parameters", "Identified parameters".to_string()));
    }
    if r.path_errors.is_some() {
        out.push(("path-errors", super::path_errors::HEADING.to_string()));
    }
    if r.plan.is_some() {
        out.push(("plan", "Planned poses".to_string()));
    }
    if !r.overlays.is_empty() {
        out.push(("overlay", "Trace overlay".to_string()));
    }
    if !r.figures.is_empty() {
        out.push(("figures", "Figures".to_string()));
    }
    out.push(("provenance", "Data provenance".to_string()));
    if !r.notes.is_empty() {
        out.push(("notes", "Skipped".to_string()));
    }
    out
}

fn toc(s: &mut String, secs: &[(&'static str, String)]) {
    s.push_str("<nav class=\"toc\"><h2 id=\"contents\">Details</h2><ol>");
    for (id, h) in secs {
        let _ = write!(s, "<li><a href=\"#{id}\">{}</a></li>", escape(h));
    }
    s.push_str("</ol></nav>\n");
}

fn params_section(s: &mut String, r: &Report) {
    for p in &r.parameters {
        let _ = writeln!(
            s,
            "<h3>{} (method {})</h3>\n<table class=\"params\"><tr><th>parameter</th><th>unit</th>\
             <th class=\"num\">nominal</th><th class=\"num\">identified</th><th class=\"num\">&sigma;</th>{}</tr>",
            escape(&p.source),
            escape(&p.method),
            if p.rows.iter().any(|x| x.truth.is_some()) { "<th class=\"num\">truth</th>" } else { "" }
        );
        let with_truth = p.rows.iter().any(|x| x.truth.is_some());
        for row in &p.rows {
            let opt = |v: Option<f64>| v.map_or_else(String::new, |x| num(x, 6));
            let _ = write!(
                s,
                "<tr><th>{}</th><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>",
                escape(&row.name),
                escape(row.unit.as_deref().unwrap_or("")),
                opt(row.nominal),
                num(row.value, 6),
                row.sigma.map_or_else(|| "fixed".to_string(), |x| num(x, 6)),
            );
            if with_truth {
                let _ = write!(s, "<td class=\"num\">{}</td>", opt(row.truth));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</table>\n<p>");
        if let Some(c) = p.condition_number {
            let _ = write!(s, "Condition number {c:.1}. ");
        }
        if !p.unidentifiable.is_empty() {
            let _ = write!(
                s,
                "Unidentifiable: {}.",
                escape(&p.unidentifiable.join(", "))
            );
        }
        s.push_str("</p>\n");
    }
}

fn diagnose_details(s: &mut String, r: &Report) {
    for (k, d) in r.diagnose.iter().enumerate() {
        let _ = writeln!(s, "<h3>{}</h3>", escape(&d.source));
        for (i, t) in d.tables.iter().enumerate() {
            error_table(s, t, &format!("diagnose-{k}-table-{i}"));
        }
        if d.effects.is_empty() {
            match d.verdict_kind.as_deref() {
                None | Some("floor") => s.push_str(
                    "<p>No effect added: the declared model explains the data down to the noise.</p>\n",
                ),
                Some(kind) => {
                    let _ = writeln!(s, "<p>No effect added (verdict: {}).</p>", escape(kind));
                }
            }
        } else {
            s.push_str("<table class=\"effects\"><tr><th>#</th><th>effect</th><th>final values &plusmn; &sigma; (deg, mm, kg, ppm as the id says)</th>\
                <th class=\"num\">held-out mean before (mm)</th><th class=\"num\">held-out mean after (mm)</th><th>evidence</th></tr>\n");
            for (i, e) in d.effects.iter().enumerate() {
                let opt = |v: Option<f64>| v.map_or_else(String::new, |x| num(x, 4));
                let _ = writeln!(
                    s,
                    "<tr><td class=\"num\">{}</td><td><code>{}</code></td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
                    i + 1,
                    escape(&e.id),
                    escape(&e.parameters),
                    opt(e.validation_mean_mm_before),
                    opt(e.validation_mean_mm_after),
                    escape(&e.evidence)
                );
            }
            s.push_str("</table>\n");
        }
        if !d.unexplained.is_empty() {
            let _ = writeln!(s, "<p>Unexplained: {}</p>", escape(&d.unexplained));
        }
    }
}

fn plan_details(s: &mut String, p: &super::PlanSection) {
    let _ = writeln!(
        s,
        "<p class=\"src\">source: <code>{}</code></p>",
        escape(&p.source)
    );
    if let Some(f) = &p.figure {
        render_figure(s, f);
    }
    if !p.facts.is_empty() {
        s.push_str("<table class=\"plan\">");
        for (k, v) in &p.facts {
            let _ = write!(s, "<tr><th>{}</th><td>{}</td></tr>", escape(k), escape(v));
        }
        s.push_str("</table>\n");
    }
    if !p.sigma.is_empty() {
        let achieved = p.sigma.iter().any(|x| x.achieved.is_some());
        let _ = write!(
            s,
            "<h3>Expected and achieved one-sigma per parameter (deg or mm, the parameter's unit)</h3>\n\
             <table class=\"plan-sigma\"><tr><th>parameter</th><th class=\"num\">planned poses, expected &sigma;</th>\
             <th class=\"num\">random poses, expected &sigma;</th>{}</tr>\n",
            if achieved {
                format!("<th class=\"num\">achieved &sigma; ({})</th>", escape(p.achieved_source.as_deref().unwrap_or("")))
            } else {
                String::new()
            }
        );
        let opt = |v: Option<f64>| v.map_or_else(String::new, |x| format!("{x:.3e}"));
        for row in &p.sigma {
            let _ = write!(
                s,
                "<tr><th>{}</th><td class=\"num\">{}</td><td class=\"num\">{}</td>",
                escape(&row.name),
                opt(row.expected),
                opt(row.random)
            );
            if achieved {
                let _ = write!(s, "<td class=\"num\">{}</td>", opt(row.achieved));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</table>\n");
    }
}

fn provenance(s: &mut String, r: &Report) {
    let _ = writeln!(
        s,
        "<p>rigctl {}; run directory <code>{}</code>.</p>",
        escape(r.rigctl_version),
        escape(&r.run_dir)
    );
    s.push_str("<table class=\"files\"><tr><th>file</th><th>used as</th><th class=\"num\">size (bytes)</th><th>SHA-256</th></tr>\n");
    for f in &r.files {
        let _ = writeln!(
            s,
            "<tr><td><code>{}</code></td><td>{}</td><td class=\"num\">{}</td><td><code>{}</code></td></tr>",
            escape(&f.name),
            escape(if f.role.is_empty() { "(not used)" } else { &f.role }),
            f.size_bytes,
            f.sha256
        );
    }
    s.push_str("</table>\n");
    if !r.simulation.is_empty() {
        s.push_str("<h3>Simulation (truth.json)</h3>\n<table class=\"sim\">");
        for (k, v) in &r.simulation {
            let _ = write!(
                s,
                "<tr><th>{}</th><td><code>{}</code></td></tr>",
                escape(k),
                escape(v)
            );
        }
        s.push_str("</table>\n");
    }
    if r.commands.is_empty() {
        s.push_str("<p>No command lines recorded (<code>commands.txt</code> absent).</p>\n");
    }
    for (name, text) in &r.commands {
        let _ = writeln!(s, "<h3>{}</h3><pre>{}</pre>", escape(name), escape(text));
    }
}

/// The whole page: the first screen (the answer), a table of contents, then the details.
/// How every page `render_html` writes begins (before the run directory's name).
pub const PAGE_PREFIX: &str =
    "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>rigctl report: ";

/// Whether `path` is a page an earlier `rigctl report` wrote: a regular file (not a link), with
/// no other hard link, beginning with [`PAGE_PREFIX`]. Such a page in the run directory may be
/// replaced by a new report; no other file of the run may.
pub fn is_report_page(path: &std::path::Path) -> bool {
    use std::io::Read as _;
    use std::os::unix::fs::MetadataExt as _;
    let plain = std::fs::symlink_metadata(path).is_ok_and(|m| m.is_file() && m.nlink() == 1);
    let mut head = vec![0u8; PAGE_PREFIX.len()];
    plain
        && std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut head))
            .is_ok()
        && head == PAGE_PREFIX.as_bytes()
}

pub fn render_html(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>rigctl report: {dir}</title><style>{CSS}</style></head><body>\n\
         <h1>Calibration report: <code>{dir}</code></h1>",
        dir = escape(&r.run_dir),
    );
    super::first_screen_html::render(&mut s, &r.summary);
    let secs = sections(r);
    toc(&mut s, &secs);
    for (id, heading) in &secs {
        let _ = writeln!(
            s,
            "<section class=\"details\"><h2 id=\"{id}\">{}</h2>",
            escape(heading)
        );
        match *id {
            "errors" => {
                for (k, t) in r.tables.iter().enumerate() {
                    error_table(&mut s, t, &format!("table-{k}"));
                }
            }
            "diagnose" => diagnose_details(&mut s, r),
            "parameters" => params_section(&mut s, r),
            "path-errors" => {
                if let Some(p) = &r.path_errors {
                    super::path_errors::render(&mut s, p);
                }
            }
            "plan" => {
                if let Some(p) = &r.plan {
                    plan_details(&mut s, p);
                }
            }
            "overlay" => {
                for o in &r.overlays {
                    let _ = writeln!(
                        s,
                        "<figure><img alt=\"trace overlay\" width=\"{}\" height=\"{}\" src=\"data:image/png;base64,{}\"><figcaption>{}</figcaption></figure>",
                        o.width_px,
                        o.height_px,
                        o.png_base64,
                        escape(&o.caption)
                    );
                }
            }
            "figures" => {
                for f in &r.figures {
                    render_figure(&mut s, f);
                }
            }
            "provenance" => provenance(&mut s, r),
            _ => {
                s.push_str("<ul class=\"notes\">");
                for n in &r.notes {
                    let _ = write!(s, "<li class=\"note\">{}</li>", escape(n));
                }
                s.push_str("</ul>\n");
            }
        }
        s.push_str("</section>\n");
    }
    s.push_str("</body></html>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
    }

    #[test]
    fn page_has_no_scripts_or_external_links_and_escapes_names() {
        let r = Report {
            run_dir: "<dir>".into(),
            rigctl_version: "0.1.0",
            notes: vec!["x <script>".into()],
            ..Default::default()
        };
        let html = render_html(&r);
        assert!(html.starts_with(PAGE_PREFIX));
        assert!(!html.contains("<script"));
        assert!(!html.contains("http://") && !html.contains("https://"));
        assert!(html.contains("&lt;dir&gt;"));
    }
}
