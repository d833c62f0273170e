//! What the sections of the page share, importing none of them: a chart drawn as a page
//! [`Figure`], HTML escaping, and a figure's HTML (`<figure>` with inline SVG and caption).

use std::fmt::Write as _;

use super::Figure;
use crate::plot::{svg_string, Chart};

/// The strings of a JSON array (other elements, or anything but an array, give none).
pub(crate) fn strings(v: Option<&serde_json::Value>) -> Vec<String> {
    v.and_then(serde_json::Value::as_array)
        .map(|a| {
            a.iter()
                .filter_map(serde_json::Value::as_str)
                .map(String::from)
                .collect()
        })
        .unwrap_or_default()
}

/// `chart` as a [`Figure`] with `caption`; a chart that cannot be drawn becomes a note.
pub(crate) fn figure<C: Chart>(
    caption: String,
    chart: &C,
    notes: &mut Vec<String>,
) -> Option<Figure> {
    match svg_string(chart) {
        Ok(svg) => Some(Figure {
            caption,
            svg,
            series: Vec::new(),
        }),
        Err(e) => {
            notes.push(format!("figure {:?} skipped: {e}", chart.title()));
            None
        }
    }
}

/// [`figure`] keeping the values the caption speaks of.
pub(crate) fn figure_with<C: Chart>(
    caption: String,
    chart: &C,
    series: Vec<(String, Vec<f64>)>,
    notes: &mut Vec<String>,
) -> Option<Figure> {
    figure(caption, chart, notes).map(|f| Figure { series, ..f })
}

/// `text` with `& < > " '` escaped for HTML text and attribute values.
pub fn escape(text: &str) -> String {
    crate::io::markup::escape(text, crate::io::markup::Blanks::Literal)
}

/// Strips an XML declaration, so the SVG can be inlined in HTML.
fn inline_svg(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

/// Appends `f` as a `<figure>` (inline SVG and caption).
pub(crate) fn render_figure(s: &mut String, f: &Figure) {
    let _ = writeln!(
        s,
        "<figure>{}<figcaption>{}</figcaption></figure>",
        inline_svg(&f.svg),
        escape(&f.caption)
    );
}
