//! The page: inline CSS and SVG only, no scripts, no external resources.

use std::fmt::Write as _;

use super::table::ErrorTable;
use super::{Figure, Report};

/// `text` with `& < > " '` escaped for HTML text and attribute values.
pub fn escape(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            '\'' => s.push_str("&#39;"),
            c => s.push(c),
        }
    }
    s
}

const CSS: &str =
    "body{font-family:sans-serif;margin:24px auto;max-width:1100px;color:#222;line-height:1.4}\
h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;margin-top:2em}\
table{border-collapse:collapse;margin:0.6em 0 1.2em}th,td{border:1px solid #bbb;padding:3px 8px}\
td.num{text-align:right;font-variant-numeric:tabular-nums}th{background:#f0f0f0}\
figure{margin:1em 0}figure svg{max-width:100%;height:auto;border:1px solid #ddd}\
figcaption{font-size:0.9em;color:#444}.note{color:#8a5a00}code,pre{font-size:0.85em}\
pre{background:#f6f6f6;padding:6px;overflow-x:auto}";

fn num(v: Option<f64>, decimals: usize) -> String {
    v.map_or_else(|| "&ndash;".to_string(), |x| format!("{x:.decimals$}"))
}

fn error_table(s: &mut String, t: &ErrorTable, id: &str) {
    let _ = writeln!(
        s,
        "<h3>{} ({} poses), mm</h3>\n<table class=\"errors\" id=\"{id}\"><tr><th></th><th></th>",
        escape(&t.title),
        t.n
    );
    for c in &t.columns {
        let _ = write!(s, "<th>{}</th>", escape(c));
    }
    s.push_str("</tr>\n");
    let mut last = "";
    for r in &t.rows {
        let stat = if r.statistic != last { r.statistic } else { "" };
        last = r.statistic;
        let _ = write!(s, "<tr><th>{stat}</th><th>{}</th>", escape(r.quantity));
        for v in &r.values {
            let _ = write!(s, "<td class=\"num\">{}</td>", num(*v, 4));
        }
        s.push_str("</tr>\n");
    }
    let _ = writeln!(
        s,
        "</table>\n<p class=\"src\">source: <code>{}</code></p>",
        escape(&t.source)
    );
}

/// Strips an XML declaration, so the SVG can be inlined in HTML.
fn inline_svg(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

/// Appends `f` as a `<figure>` (inline SVG and caption).
pub(crate) fn figure(s: &mut String, f: &Figure) {
    let _ = writeln!(
        s,
        "<figure>{}<figcaption>{}</figcaption></figure>",
        inline_svg(&f.svg),
        escape(&f.caption)
    );
}

/// The whole page.
pub fn render_html(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>rigctl report: {dir}</title><style>{CSS}</style></head><body>\n\
         <h1>Calibration report</h1>\n<p>Run directory <code>{dir}</code>, rigctl {v}.</p>",
        dir = escape(&r.run_dir),
        v = escape(r.rigctl_version)
    );
    s.push_str("<h2 id=\"errors\">Position errors (thesis table 4.5)</h2>\n");
    if r.tables.is_empty() {
        s.push_str("<p class=\"note\">No error statistics: no pose files or calibrate JSON.</p>\n");
    }
    for (k, t) in r.tables.iter().enumerate() {
        error_table(&mut s, t, &format!("table-{k}"));
    }
    s.push_str("<h2 id=\"parameters\">Identified parameters</h2>\n");
    if r.parameters.is_empty() {
        s.push_str("<p class=\"note\">No calibrate JSON in the run directory.</p>\n");
    }
    for p in &r.parameters {
        let _ = writeln!(
            s,
            "<h3>{} (method {})</h3>\n<table class=\"params\"><tr><th>parameter</th><th>nominal</th>\
             <th>identified</th><th>&sigma;</th><th>truth</th></tr>",
            escape(&p.source),
            escape(&p.method)
        );
        for row in &p.rows {
            let _ = writeln!(
                s,
                "<tr><th>{}</th><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
                escape(&row.name),
                num(row.nominal, 6),
                num(Some(row.value), 6),
                row.sigma.map_or_else(|| "fixed".to_string(), |x| format!("{x:.6}")),
                num(row.truth, 6)
            );
        }
        s.push_str("</table>\n<p>Degrees for angles, millimetres for lengths.");
        if let Some(c) = p.condition_number {
            let _ = write!(s, " Condition number {c:.1}.");
        }
        if !p.unidentifiable.is_empty() {
            let _ = write!(
                s,
                " Unidentifiable: {}.",
                escape(&p.unidentifiable.join(", "))
            );
        }
        s.push_str("</p>\n");
    }
    s.push_str("<h2 id=\"diagnose\">Effects added (diagnose)</h2>\n");
    match &r.diagnose {
        None => s.push_str("<p class=\"note\">No diagnose JSON in the run directory.</p>\n"),
        Some(d) => {
            for (k, t) in d.tables.iter().enumerate() {
                error_table(&mut s, t, &format!("diagnose-table-{k}"));
            }
            if d.effects.is_empty() {
                s.push_str("<p>No effect added: the declared model explains the data down to the noise.</p>\n");
            } else {
                s.push_str("<table class=\"effects\"><tr><th>#</th><th>effect</th><th>parameters</th>\
                    <th>validation mean before (mm)</th><th>after (mm)</th><th>evidence</th></tr>\n");
                for (k, e) in d.effects.iter().enumerate() {
                    let _ = writeln!(
                        s,
                        "<tr><td>{}</td><td><code>{}</code></td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
                        k + 1,
                        escape(&e.id),
                        escape(&e.parameters),
                        num(e.validation_mean_mm_before, 4),
                        num(e.validation_mean_mm_after, 4),
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
    if let Some(p) = &r.path_errors {
        super::path_errors::render(&mut s, p);
    }
    s.push_str("<h2 id=\"figures\">Figures</h2>\n");
    for f in &r.figures {
        figure(&mut s, f);
    }
    s.push_str("<h2 id=\"provenance\">Data provenance</h2>\n");
    let _ = writeln!(
        s,
        "<p>rigctl {}; run directory <code>{}</code>.</p>",
        escape(r.rigctl_version),
        escape(&r.run_dir)
    );
    s.push_str("<table class=\"files\"><tr><th>file</th><th>used as</th><th>bytes</th><th>SHA-256</th></tr>\n");
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
    if !r.notes.is_empty() {
        s.push_str("<h2 id=\"notes\">Skipped</h2>\n<ul class=\"notes\">");
        for n in &r.notes {
            let _ = write!(s, "<li class=\"note\">{}</li>", escape(n));
        }
        s.push_str("</ul>\n");
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
        assert!(html.starts_with("<!DOCTYPE html>"));
        assert!(!html.contains("<script"));
        assert!(!html.contains("http://") && !html.contains("https://"));
        assert!(html.contains("&lt;dir&gt;"));
    }
}
