//! OptiTrack Motive CSV export: a first line of `key,value` pairs (`Format Version`, `Export
//! Frame Rate`, `Length Units` ...), then the rows `,Type,...` (`Rigid Body`, `Marker`, `Rigid
//! Body Marker`), `,Name,...`, `,ID,...`, a row naming each column's quantity (`Rotation`,
//! `Position`, `Mean Marker Error`, ...) and the header `Frame,Time (Seconds),X,Y,Z,...`; one
//! row per frame, an empty cell where the object was not tracked. The positions (`Position`
//! X,Y,Z) of the rigid bodies are taken (their pivot point: set it on the tool point in Motive),
//! or of the markers when there is no rigid body, or of the objects named with `--marker`.
//! Lengths in the file's `Length Units` (Meters, Centimeters, Millimeters; without the key,
//! the --units length). Rotations are not used.

use super::{
    assemble, at_line, cell, detect_dialect, numbered_lines, point, Format, InstrumentLog,
    ReadOptions,
};
use crate::capture::error::CaptureError;

pub(super) fn parse(
    text: &str,
    file: &str,
    opts: &ReadOptions,
) -> Result<InstrumentLog, CaptureError> {
    let err = at_line(file);
    let lines = numbered_lines(text);
    let (_, first) = lines.first().copied().unwrap_or((1, ""));
    let head_at = lines
        .iter()
        .position(|(_, l)| l.trim_start().starts_with("Frame"))
        .ok_or_else(|| err(1, "no header row `Frame,Time (Seconds),...`".into()))?;
    let d = detect_dialect(opts, lines[head_at].1, lines.get(head_at + 1).map(|l| l.1));
    let split = |l: &str| -> Vec<String> {
        d.normalize(l)
            .split(',')
            .map(|f| f.trim().to_string())
            .collect()
    };
    // the first line's key,value pairs
    let meta = split(first);
    let value = |key: &str| {
        meta.chunks(2)
            .find(|kv| kv[0].eq_ignore_ascii_case(key))
            .and_then(|kv| kv.get(1).cloned())
    };
    let mm = match value("Length Units").as_deref() {
        Some("Meters") => 1000.0,
        Some("Centimeters") => 10.0,
        Some("Millimeters") => 1.0,
        Some(other) => {
            return Err(err(
                1,
                format!("Length Units `{other}` (Meters, Centimeters or Millimeters)"),
            ))
        }
        None => opts.mm_per_unit,
    };
    let row_named = |label: &str| {
        lines[..head_at]
            .iter()
            .find(|(_, l)| split(l).get(1).map(String::as_str) == Some(label))
            .map(|(n, l)| (*n, split(l)))
    };
    let (_, types) = row_named("Type").ok_or_else(|| err(1, "no row `,Type,...`".into()))?;
    let (names_line, names) =
        row_named("Name").ok_or_else(|| err(1, "no row `,Name,...`".into()))?;
    let kinds = head_at
        .checked_sub(1)
        .map(|i| split(lines[i].1))
        .unwrap_or_default();
    let head = split(lines[head_at].1);
    let time_col = head
        .iter()
        .position(|h| h.starts_with("Time"))
        .ok_or_else(|| err(lines[head_at].0, "no column `Time (Seconds)`".into()))?;
    let get = |v: &Vec<String>, i: usize| v.get(i).cloned().unwrap_or_default();
    // (name, type, first column) of every Position X,Y,Z triple
    let mut objects: Vec<(String, String, usize)> = Vec::new();
    for c in 0..head.len().saturating_sub(2) {
        let position = (c..c + 3).all(|i| get(&kinds, i) == "Position");
        if position && head[c] == "X" && head[c + 1] == "Y" && head[c + 2] == "Z" {
            objects.push((get(&names, c), get(&types, c), c));
        }
    }
    if opts.markers.is_empty() {
        let bodies = objects.iter().any(|o| o.1 == "Rigid Body");
        let keep = if bodies { "Rigid Body" } else { "Marker" };
        objects.retain(|o| o.1 == keep);
    } else {
        for want in &opts.markers {
            if !objects.iter().any(|o| &o.0 == want) {
                let known =
                    crate::error::nearest_first(want, objects.iter().map(|o| o.0.as_str()), 30);
                return Err(err(
                    names_line,
                    format!(
                        "no rigid body or marker `{want}`; its objects, nearest first: {known}"
                    ),
                ));
            }
        }
        objects.retain(|o| opts.markers.contains(&o.0));
    }
    if objects.is_empty() {
        return Err(err(
            lines[head_at].0,
            "no rigid-body or marker Position X,Y,Z columns".into(),
        ));
    }
    let mut rows = Vec::new();
    for &(line, l) in &lines[head_at + 1..] {
        if l.trim().is_empty() {
            continue;
        }
        let f = split(l);
        let g = |i: usize| f.get(i).map(String::as_str).unwrap_or("");
        let t = match cell(g(time_col)) {
            Ok(Some(t)) => t,
            Ok(None) => return Err(err(line, "missing time".into())),
            Err(p) => return Err(err(line, format!("Time: {p}"))),
        };
        let pts = objects
            .iter()
            .map(|(_, _, c)| point([g(*c), g(c + 1), g(c + 2)], mm))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|p| err(line, p))?;
        rows.push((line, t, pts));
    }
    assemble(
        file,
        Format::Motive,
        objects.into_iter().map(|o| o.0).collect(),
        rows,
    )
}

#[cfg(test)]
mod tests {
    use super::super::{parse_instrument, tests::opts, Format};

    #[test]
    fn rigid_body_positions_in_metres() {
        let text = "Format Version,1.23,Take Name,t1,Export Frame Rate,120.000000,Rotation Type,Quaternion,Length Units,Meters,Coordinate Space,Global\n\
                    \n\
                    ,Type,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Rigid Body,Marker,Marker,Marker\n\
                    ,Name,Tool,Tool,Tool,Tool,Tool,Tool,Tool,Tool,Unlabeled 1,Unlabeled 1,Unlabeled 1\n\
                    ,ID,1,1,1,1,1,1,1,1,2,2,2\n\
                    ,,Rotation,Rotation,Rotation,Rotation,Position,Position,Position,Mean Marker Error,Position,Position,Position\n\
                    Frame,Time (Seconds),X,Y,Z,W,X,Y,Z,,X,Y,Z\n\
                    0,0.000000,0,0,0,1,0.1,0.2,0.3,0.0001,1,1,1\n\
                    1,0.008333,0,0,0,1,,,,,1,1,1\n\
                    2,0.016667,0,0,0,1,0.1005,0.2,0.3,0.0001,1,1,1\n";
        let log = parse_instrument(text, "m.csv", &opts()).unwrap();
        assert_eq!(log.format, Format::Motive);
        assert_eq!(log.marker_names, ["Tool"]);
        assert_eq!(log.points[0][0], Some([100.0, 200.0, 300.0]));
        assert_eq!(log.missing, 1);
        let mut o = opts();
        o.markers = vec!["Unlabeled 1".into()];
        let m = parse_instrument(text, "m.csv", &o).unwrap();
        assert_eq!(m.points[1][0], Some([1000.0; 3]));
    }
}
