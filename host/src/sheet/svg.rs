//! The printable sheet as SVG: an A4 page whose user units are millimetres.

use super::{
    fiducial_centres_mm, orientation_dot_mm, ring_dots_mm, scale_bar_rects_mm, sheet_to_page_mm,
    ReferencePath, FIDUCIAL_DIAMETER_MM, FIDUCIAL_SPACING_MM, ORIENTATION_DOT_DIAMETER_MM,
    PAGE_HEIGHT_MM, PAGE_WIDTH_MM, RING_DOT_DIAMETER_MM, SCALE_BAR_LENGTH_MM, SCALE_BAR_Y_MM,
};
use std::fmt::Write as _;

/// Width of the printed red reference path, mm.
pub const REFERENCE_STROKE_MM: f64 = 0.3;
/// Colour of the printed reference path.
pub const REFERENCE_COLOUR: &str = "#ff0000";

/// Renders the sheet with the given reference paths as a standalone SVG document.
pub fn render_svg(paths: &[ReferencePath]) -> String {
    let mut s = String::new();
    // `write!` into a String cannot fail; the results are ignored deliberately.
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{PAGE_WIDTH_MM}mm" height="{PAGE_HEIGHT_MM}mm" viewBox="0 0 {PAGE_WIDTH_MM} {PAGE_HEIGHT_MM}">"#
    );
    let _ = writeln!(
        s,
        r#"<rect x="0" y="0" width="{PAGE_WIDTH_MM}" height="{PAGE_HEIGHT_MM}" fill="white"/>"#
    );
    let _ = writeln!(
        s,
        "<!-- fiducials: 6 mm discs at (+-90, +-90) mm, orientation dot at (-90, 75) mm -->"
    );
    for c in fiducial_centres_mm(FIDUCIAL_SPACING_MM) {
        circle(&mut s, c, FIDUCIAL_DIAMETER_MM / 2.0);
    }
    circle(
        &mut s,
        orientation_dot_mm(FIDUCIAL_SPACING_MM),
        ORIENTATION_DOT_DIAMETER_MM / 2.0,
    );
    let _ = writeln!(
        s,
        "<!-- sheet v2 ring: 43 dots of 1.5 mm every 15 mm along the square's sides -->"
    );
    for c in ring_dots_mm(FIDUCIAL_SPACING_MM) {
        circle(&mut s, c, RING_DOT_DIAMETER_MM / 2.0);
    }

    for path in paths {
        let _ = writeln!(s, "<!-- reference path: {} -->", path.description());
        match path {
            ReferencePath::Circle => {
                let c = sheet_to_page_mm([0.0, 0.0]);
                let _ = writeln!(
                    s,
                    r#"<circle cx="{}" cy="{}" r="{}" fill="none" stroke="{REFERENCE_COLOUR}" stroke-width="{REFERENCE_STROKE_MM}"/>"#,
                    c[0],
                    c[1],
                    super::CIRCLE_RADIUS_MM
                );
            }
            ReferencePath::Line => {
                let pts = path.polyline_mm(1000.0);
                let (a, b) = (
                    sheet_to_page_mm(pts[0]),
                    sheet_to_page_mm(pts[pts.len() - 1]),
                );
                let _ = writeln!(
                    s,
                    r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{REFERENCE_COLOUR}" stroke-width="{REFERENCE_STROKE_MM}"/>"#,
                    a[0], a[1], b[0], b[1]
                );
            }
        }
    }

    let _ = writeln!(s, "<!-- scale bar: {SCALE_BAR_LENGTH_MM} mm -->");
    for r in scale_bar_rects_mm() {
        let p0 = sheet_to_page_mm([r.min[0], r.max[1]]);
        let _ = writeln!(
            s,
            r#"<rect x="{:.3}" y="{:.3}" width="{:.3}" height="{:.3}" fill="black"/>"#,
            p0[0],
            p0[1],
            r.max[0] - r.min[0],
            r.max[1] - r.min[1]
        );
    }
    let label_y = sheet_to_page_mm([0.0, SCALE_BAR_Y_MM - 4.0])[1];
    for (x_mm, label) in [(0.0, "0"), (50.0, "50"), (100.0, "100 mm")] {
        let x = sheet_to_page_mm([x_mm - SCALE_BAR_LENGTH_MM / 2.0, 0.0])[0];
        text(&mut s, x, label_y, 3.0, "middle", label);
    }
    let x_left = sheet_to_page_mm([-FIDUCIAL_SPACING_MM / 2.0, 0.0])[0];
    let caption = [
        "After printing, measure the centre-to-centre spacing of the corner discs, horizontally",
        "and vertically (expected 180.0 mm); pass the measured value to",
        "rigctl trace --fiducial-spacing-mm. The dot near the top-left disc marks the top left.",
    ];
    for (i, line) in caption.iter().enumerate() {
        let y = sheet_to_page_mm([0.0, SCALE_BAR_Y_MM - 12.0 - 5.0 * i as f64])[1];
        text(&mut s, x_left, y, 3.2, "start", line);
    }
    let title_y = sheet_to_page_mm([0.0, 118.0])[1];
    let title = format!(
        "rigctl trace sheet: {}",
        paths
            .iter()
            .map(|p| p.description())
            .collect::<Vec<_>>()
            .join("; ")
    );
    text(&mut s, x_left, title_y, 3.5, "start", &title);
    let _ = writeln!(s, "</svg>");
    s
}

fn circle(s: &mut String, centre_mm: [f64; 2], radius_mm: f64) {
    let c = sheet_to_page_mm(centre_mm);
    let _ = writeln!(
        s,
        r#"<circle cx="{}" cy="{}" r="{}" fill="black"/>"#,
        c[0], c[1], radius_mm
    );
}

fn text(s: &mut String, x: f64, y: f64, size_mm: f64, anchor: &str, body: &str) {
    let escaped = body
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    let _ = writeln!(
        s,
        r#"<text x="{x:.3}" y="{y:.3}" font-family="sans-serif" font-size="{size_mm}" text-anchor="{anchor}" fill="black">{escaped}</text>"#
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_has_a4_viewbox_fiducials_and_red_path() {
        let svg = render_svg(&[ReferencePath::Circle]);
        assert!(svg.contains(r#"viewBox="0 0 210 297""#));
        assert!(svg.contains(r#"width="210mm""#));
        // four fiducials + orientation dot, in page mm
        assert!(svg.contains(r#"<circle cx="15" cy="58.5" r="3" fill="black"/>"#));
        assert!(svg.contains(r#"<circle cx="195" cy="238.5" r="3" fill="black"/>"#));
        assert!(svg.contains(r#"<circle cx="15" cy="73.5" r="1.5" fill="black"/>"#));
        assert!(
            svg.contains(r##"<circle cx="105" cy="148.5" r="100" fill="none" stroke="#ff0000""##)
        );
        assert!(svg.contains("expected 180.0 mm"));
        // sheet v2 ring: 43 dots of 1.5 mm
        assert_eq!(svg.matches(r#"r="0.75" fill="black""#).count(), 43);
        assert!(svg.contains(r#"<circle cx="30" cy="58.5" r="0.75" fill="black"/>"#));
        assert!(svg.contains("--fiducial-spacing-mm"));
        let line = render_svg(&[ReferencePath::Line]);
        assert!(line.contains(r#"<line x1="5" y1="148.5" x2="205" y2="148.5""#));
    }
}
