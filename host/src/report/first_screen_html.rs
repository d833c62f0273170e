//! The HTML of the first screen of the page ([`super::first_screen`] builds it as data): the
//! verdict, what was identified, the URDF's accuracy, the effects found, the stage bar chart and
//! the next steps.

use std::fmt::Write as _;

use super::answer::{verdict_line, Identified, UrdfAccuracy};
use super::markup::{escape, render_figure};
use super::summary::{headline_sentence, Diagnosis, FoundEffect, Summary};
use crate::plot::summary::fmt_mm;

/// Backquoted spans as `<code>`, the rest escaped.
fn with_code(text: &str) -> String {
    text.split('`')
        .enumerate()
        .map(|(k, part)| {
            if k % 2 == 1 {
                format!("<code>{}</code>", escape(part))
            } else {
                escape(part)
            }
        })
        .collect()
}

fn value_text(v: f64, sigma: Option<f64>) -> String {
    let digits = |x: f64| if x.abs() >= 1.0 { 3 } else { 4 };
    match sigma {
        Some(s) => format!("{v:.d$} &plusmn; {s:.d$}", d = digits(s).max(digits(v))),
        None => format!("{v:.d$}", d = digits(v)),
    }
}

/// One effect in a line: `id` and its values +- sigma.
fn effect_line(e: &FoundEffect) -> String {
    let vals: Vec<String> = e
        .values
        .iter()
        .map(|(n, v, sg)| format!("{} = {}", escape(n), value_text(*v, *sg)))
        .collect();
    format!("<code>{}</code> {}", escape(&e.id), vals.join(", "))
}

/// A diagnosis's verdict in one line, the statistics (the whole verdict, each effect's
/// evidence, the aliased pairs) folded below it.
fn render_verdict(out: &mut String, d: &Diagnosis) {
    let v = d
        .verdict
        .as_deref()
        .unwrap_or("No verdict in this document.");
    let _ = writeln!(
        out,
        "<p class=\"verdict\">Verdict (<code>{}</code>): {}</p>",
        escape(&d.source),
        escape(&verdict_line(v))
    );
    let _ = writeln!(
        out,
        "<details class=\"stats\"><summary>The statistics{}</summary>",
        if d.aliased.is_empty() {
            String::new()
        } else {
            format!(
                " and {} pair{} these {} cannot tell apart",
                d.aliased.len(),
                if d.aliased.len() == 1 { "" } else { "s" },
                d.noun
            )
        }
    );
    let _ = writeln!(out, "<p class=\"verdict-full\">{}</p>", escape(v));
    if !d.effects.is_empty() {
        out.push_str("<ol class=\"found\">\n");
        for e in &d.effects {
            let _ = writeln!(
                out,
                "<li>{}<br><span class=\"evidence\">{}</span></li>",
                effect_line(e),
                escape(&e.evidence)
            );
        }
        out.push_str("</ol>\n");
    }
    for a in &d.aliased {
        let _ = writeln!(
            out,
            "<p class=\"aliased\">Aliased: <code>{}</code> and <code>{}</code>{} cannot be told apart by these {}{}.</p>",
            escape(&a.a),
            escape(&a.b),
            a.correlation.map_or_else(String::new, |c| format!(" (correlation {c:.2})")),
            d.noun,
            if a.note.is_empty() { String::new() } else { format!(": {}", escape(&a.note)) }
        );
    }
    out.push_str("</details>\n");
}

/// The effects a diagnosis found, one line each.
fn render_found(out: &mut String, d: &Diagnosis) {
    if d.effects.is_empty() {
        let _ = writeln!(
            out,
            "<p>No effect the declared model lacks could be established (<code>{}</code>).</p>",
            escape(&d.source)
        );
        return;
    }
    let _ = writeln!(
        out,
        "<p class=\"found-head\">Found by <code>{}</code> ({}):</p>\n<ol class=\"found\">",
        escape(&d.source),
        d.effects.len()
    );
    for e in &d.effects {
        let _ = writeln!(out, "<li>{}</li>", effect_line(e));
    }
    out.push_str("</ol>\n");
}

/// The held-out error through the exported URDF beside the best model's.
fn render_urdf(out: &mut String, u: &UrdfAccuracy) {
    let _ = writeln!(
        out,
        "<p class=\"urdf\">Through the exported URDF (<code>model2urdf</code>; the {}, <code>{}</code>): <b>{} mm</b> mean (RMS {}); with {} (<code>{}</code>): <b>{} mm</b> (RMS {}). A URDF cannot hold {}.</p>",
        escape(&u.urdf.label),
        escape(&u.urdf.source),
        fmt_mm(u.urdf.mean_mm),
        fmt_mm(u.urdf.rms_mm),
        escape(&super::summary::stage_words(&u.model.label)),
        escape(&u.model.source),
        fmt_mm(u.model.mean_mm),
        fmt_mm(u.model.rms_mm),
        u.lacks
            .iter()
            .map(|l| format!("<code>{}</code>", escape(l)))
            .collect::<Vec<_>>()
            .join(", ")
    );
}

/// "N of M parameters identified", the kept ones and the combinations folded.
fn render_identified(out: &mut String, i: &Identified) {
    let _ = write!(
        out,
        "<details class=\"identified\"><summary><b>{} of {} parameters identified</b> (<code>{}</code>){}</summary>",
        i.identified,
        i.total,
        escape(&i.source),
        if i.kept.is_empty() { "" } else { "; the others kept at their input values" }
    );
    if !i.kept.is_empty() {
        let _ = write!(
            out,
            "<p>Kept at their input values: {}.</p>",
            i.kept
                .iter()
                .map(|k| format!("<code>{}</code>", escape(k)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !i.combinations.is_empty() {
        let _ = write!(
            out,
            "<p>Seen only together by these poses (fix one of each): {}.</p>",
            i.combinations
                .iter()
                .map(|k| format!("<code>{}</code>", escape(k)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    out.push_str("</details>\n");
}

/// Appends the first screen.
pub(crate) fn render(out: &mut String, s: &Summary) {
    out.push_str("<section id=\"answer\" class=\"answer\">\n");
    let _ = writeln!(out, "<p class=\"sentence\">{}</p>", escape(&s.sentence));
    out.push_str("<div class=\"headline\"><div class=\"words\">\n");
    for h in &s.headlines {
        let _ = writeln!(
            out,
            "<p class=\"lead\">{}</p>",
            escape(&headline_sentence(h))
        );
        if let Some(u) = &h.unregistered {
            let _ = writeln!(
                out,
                "<p class=\"unregistered\">Apart: the {} gives {} mm (RMS {}) on these poses: the distance between the instrument's frame and the robot's, not an error of the robot.</p>",
                escape(&u.label),
                fmt_mm(u.mean_mm),
                fmt_mm(u.rms_mm)
            );
        }
    }
    for d in &s.diagnoses {
        render_verdict(out, d);
    }
    for i in &s.identified {
        render_identified(out, i);
    }
    if let Some(u) = &s.urdf {
        render_urdf(out, u);
    }
    for d in &s.diagnoses {
        render_found(out, d);
    }
    out.push_str("</div>\n<div class=\"chart\">");
    if let Some(f) = &s.figure {
        render_figure(out, f);
    }
    for a in &s.about {
        let _ = writeln!(out, "<p class=\"about\">{}</p>", escape(a));
    }
    out.push_str("</div></div>\n");
    if !s.next_steps.is_empty() {
        out.push_str("<h3>What to do next</h3>\n<ul class=\"next\">\n");
        for n in &s.next_steps {
            let _ = writeln!(out, "<li>{}</li>", with_code(n));
        }
        out.push_str("</ul>\n");
    }
    out.push_str("</section>\n");
}
