//! Vicon Nexus CSV export, `Trajectories` section: a line `Trajectories`, the frame rate (Hz),
//! the marker names (`Subject:Marker`, in the column of each marker's X), the header
//! `Frame,Sub Frame,X,Y,Z,X,Y,Z,...`, the units (`mm`), then one row per frame; an empty cell
//! is a marker not seen in that frame. Other sections (Devices, Joints, Model Outputs,
//! Segments) are skipped. Files written with `;` and decimal commas are recognised.
//! `t` = frame / rate (s).

use super::{
    assemble, at_line, cell, detect_dialect, numbered_lines, point, Format, InstrumentLog,
    ReadOptions,
};
use crate::capture::error::CaptureError;

fn unit_mm(u: &str) -> Option<f64> {
    match u.trim() {
        "mm" => Some(1.0),
        "cm" => Some(10.0),
        "m" => Some(1000.0),
        _ => None,
    }
}

pub(super) fn parse(
    text: &str,
    file: &str,
    opts: &ReadOptions,
) -> Result<InstrumentLog, CaptureError> {
    let err = at_line(file);
    let lines = numbered_lines(text);
    let first = |l: &str| {
        l.split([',', ';', '\t'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string()
    };
    let start = lines
        .iter()
        .position(|(_, l)| first(l) == "Trajectories")
        .ok_or_else(|| {
            err(
                1,
                "no `Trajectories` section (export the marker trajectories)".into(),
            )
        })?;
    let need = |i: usize, what: &str| {
        lines.get(i).copied().ok_or_else(|| {
            err(
                lines.len(),
                format!("the Trajectories section ends before its {what}"),
            )
        })
    };
    let (rate_line, rate_text) = need(start + 1, "frame rate")?;
    let (names_line, names_text) = need(start + 2, "marker names")?;
    let (head_line, head_text) = need(start + 3, "header `Frame,Sub Frame,X,Y,Z,...`")?;
    let (units_line, units_text) = need(start + 4, "units row")?;
    let data_probe = lines.get(start + 5).map(|(_, l)| *l);
    let d = detect_dialect(opts, head_text, data_probe);
    let split = |l: &str| -> Vec<String> {
        d.normalize(l)
            .split(',')
            .map(|f| f.trim().to_string())
            .collect()
    };
    let rate_hz = match cell(&split(rate_text)[0]) {
        Ok(Some(r)) if r > 0.0 => r,
        _ => {
            return Err(err(
                rate_line,
                format!("frame rate `{}`: not a positive number", rate_text.trim()),
            ))
        }
    };
    let names = split(names_text);
    let head = split(head_text);
    let units = split(units_text);
    if head.first().map(String::as_str) != Some("Frame") {
        return Err(err(
            head_line,
            "expected the header `Frame,Sub Frame,X,Y,Z,...`".into(),
        ));
    }
    let mut markers: Vec<(String, usize, f64)> = Vec::new();
    for c in 0..head.len().saturating_sub(2) {
        if head[c] == "X" && head[c + 1] == "Y" && head[c + 2] == "Z" {
            let name = names
                .get(c)
                .filter(|n| !n.is_empty())
                .cloned()
                .unwrap_or(format!("marker{}", markers.len() + 1));
            let u = units.get(c).map(String::as_str).unwrap_or("");
            let mm = unit_mm(u).ok_or_else(|| {
                err(
                    units_line,
                    format!("marker `{name}`: unit `{u}` (mm, cm or m)"),
                )
            })?;
            markers.push((name, c, mm));
        }
    }
    if !opts.markers.is_empty() {
        let short = |n: &str| n.rsplit(':').next().unwrap_or(n).to_string();
        for want in &opts.markers {
            if !markers
                .iter()
                .any(|(n, _, _)| n == want || short(n) == *want)
            {
                let known =
                    crate::error::nearest_first(want, markers.iter().map(|m| m.0.as_str()), 30);
                return Err(err(
                    names_line,
                    format!("no marker `{want}`; its markers, nearest first: {known}"),
                ));
            }
        }
        markers.retain(|(n, _, _)| opts.markers.iter().any(|w| w == n || *w == short(n)));
    }
    if markers.is_empty() {
        return Err(err(head_line, "no marker columns X,Y,Z".into()));
    }
    let mut rows = Vec::new();
    for &(line, l) in &lines[(start + 5).min(lines.len())..] {
        if l.trim().is_empty() {
            break; // the end of the section
        }
        let f = split(l);
        let frame = match cell(&f[0]) {
            Ok(Some(v)) => v,
            _ => break, // the next section's name
        };
        let mut pts = Vec::with_capacity(markers.len());
        for (_, c, mm) in &markers {
            let get = |i: usize| f.get(i).map(String::as_str).unwrap_or("");
            pts.push(point([get(*c), get(c + 1), get(c + 2)], *mm).map_err(|p| err(line, p))?);
        }
        rows.push((line, frame / rate_hz, pts));
    }
    assemble(
        file,
        Format::Vicon,
        markers.into_iter().map(|m| m.0).collect(),
        rows,
    )
}

#[cfg(test)]
mod tests {
    use super::super::{parse_instrument, tests::opts, Format};

    #[test]
    fn a_semicolon_export_with_an_occluded_marker() {
        let text = "Trajectories\n100\n;;Arm:SMR;;;Arm:B;;\nFrame;Sub Frame;X;Y;Z;X;Y;Z\n\
                    ;;mm;mm;mm;mm;mm;mm\n1;0;-391.888;-6180.01;1734.43;-378.647;-6190.14;1713.82\n\
                    2;0;-391.978;-6180.03;1734.43;;;\n3;0;-392.012;-6180.04;1734.48;-378.718;-6189.96;1714.06\n\
                    \nJoints\n";
        let log = parse_instrument(text, "v.csv", &opts()).unwrap();
        assert_eq!(log.format, Format::Vicon);
        assert_eq!(log.marker_names, ["Arm:SMR", "Arm:B"]);
        assert_eq!(log.t_s, [0.01, 0.02, 0.03]);
        assert_eq!(log.missing, 1);
        let mut o = opts();
        o.markers = vec!["SMR".into()];
        let one = parse_instrument(text, "v.csv", &o).unwrap();
        assert_eq!(one.marker_names, ["Arm:SMR"]);
        o.markers = vec!["SMX".into()];
        let e = parse_instrument(text, "v.csv", &o).unwrap_err().to_string();
        assert!(
            e.contains("no marker `SMX`") && e.contains("`Arm:SMR`"),
            "{e}"
        );
    }
}
