//! SpatialAnalyzer (SA) ASCII point export of a laser tracker's logged points, exported with
//! "Time Stamps" on: `//` comment lines (SA version, frame, axis comments), then one point per
//! line, fields separated by commas or spaces: the point's name (`Collection Group Target`,
//! `Group Target` or `Target`: any fields before the coordinates), `X Y Z` (the first three
//! numeric fields; the --units length, default mm), then optional fields (tolerances,
//! uncertainties, offsets, comments) among which the time stamp: the first field that reads as
//! a date and time, `YYYY/MM/DD HH:MM:SS[.fff]` (`-` or `/` in the date; space, `T` or `,`
//! before the time), or the first field `t=SECONDS`. Every line is the one reflector (the SMR);
//! `t` counts from the first point's time stamp.

use super::{assemble, at_line, cell, Format, InstrumentLog, ReadOptions};
use crate::capture::error::CaptureError;

/// Days from 1970-01-01 to the civil date (proleptic Gregorian).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// `YYYY/MM/DD` or `YYYY-MM-DD`: days since 1970.
fn date(s: &str) -> Option<i64> {
    let p: Vec<&str> = s.split(['/', '-']).collect();
    let [y, m, d] = p.as_slice() else { return None };
    if y.len() != 4 {
        return None;
    }
    let (y, m, d): (i64, i64, i64) = (y.parse().ok()?, m.parse().ok()?, d.parse().ok()?);
    ((1..=12).contains(&m) && (1..=31).contains(&d)).then(|| days_from_civil(y, m, d))
}

/// `HH:MM:SS[.fff]`: seconds of the day.
fn time_of_day(s: &str) -> Option<f64> {
    let p: Vec<&str> = s.split(':').collect();
    let [h, m, sec] = p.as_slice() else {
        return None;
    };
    let (h, m, sec): (f64, f64, f64) = (h.parse().ok()?, m.parse().ok()?, sec.parse().ok()?);
    ((0.0..24.0).contains(&h) && (0.0..60.0).contains(&m) && (0.0..61.0).contains(&sec))
        .then_some(h * 3600.0 + m * 60.0 + sec)
}

/// The time stamp (s since 1970, or the `t=` seconds) among `fields`.
fn stamp(fields: &[&str]) -> Option<f64> {
    let fields: Vec<&str> = fields.iter().flat_map(|f| f.split_whitespace()).collect();
    for (i, f) in fields.iter().enumerate() {
        if let Some(t) = f.strip_prefix("t=").and_then(|v| v.parse::<f64>().ok()) {
            return Some(t);
        }
        let (d, rest) = match f.split_once('T') {
            Some((d, t)) => (d, Some(t)),
            None => (*f, None),
        };
        if let Some(days) = date(d) {
            let t = rest.or(fields.get(i + 1).copied()).and_then(time_of_day)?;
            return Some(days as f64 * 86_400.0 + t);
        }
    }
    None
}

pub(super) fn parse(
    text: &str,
    file: &str,
    opts: &ReadOptions,
) -> Result<InstrumentLog, CaptureError> {
    let err = at_line(file);
    let mut rows = Vec::new();
    let mut t0 = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with("//") {
            continue;
        }
        let l = opts.dialect.normalize(l);
        let fields: Vec<&str> = if l.contains(',') {
            l.split(',')
                .map(str::trim)
                .filter(|f| !f.is_empty())
                .collect()
        } else {
            l.split_whitespace().collect()
        };
        let numeric = |f: &str| matches!(cell(f), Ok(Some(_)));
        let at = (0..fields.len().saturating_sub(2))
            .find(|&k| numeric(fields[k]) && numeric(fields[k + 1]) && numeric(fields[k + 2]))
            .ok_or_else(|| {
                err(
                    line,
                    "no X Y Z coordinates (three numbers) on the line".into(),
                )
            })?;
        let p = [0, 1, 2]
            .map(|c| cell(fields[at + c]).ok().flatten().unwrap_or(0.0) * opts.mm_per_unit);
        let t_abs = stamp(&fields[at + 3..]).ok_or_else(|| {
            err(
                line,
                "no time stamp (export the points with Time Stamps on)".into(),
            )
        })?;
        let t = t_abs - *t0.get_or_insert(t_abs);
        rows.push((line, t, vec![Some(p)]));
    }
    assemble(file, Format::Sa, vec!["SMR".into()], rows)
}

#[cfg(test)]
mod tests {
    use super::super::{parse_instrument, tests::opts, Format};

    #[test]
    fn sa_points_with_time_stamps() {
        let text = "// SA Version 2023.1\n// Frame: TrackerFrame\n\
                    A::Log::P1, 1000.125, -200.5, 300.25, 2024/05/12 10:11:12.250\n\
                    A::Log::P2, 1000.126, -200.5, 300.25, 2024/05/12 10:11:12.350\n\
                    Log P3 1000.127 -200.5 300.25 0.01 2024-05-12T10:11:12.450\n";
        let log = parse_instrument(text, "sa.txt", &opts()).unwrap();
        assert_eq!(log.format, Format::Sa);
        assert_eq!(log.t_s.len(), 3);
        assert!((log.t_s[2] - 0.2).abs() < 1e-6, "{:?}", log.t_s);
        assert_eq!(log.points[1][0], Some([1000.126, -200.5, 300.25]));
        let e = parse_instrument(
            "// x\nP1, 1, 2, 3\nP2, 1, 2, 3\nP3, 1, 2, 3\n",
            "sa.txt",
            &opts(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("sa.txt:2") && e.contains("Time Stamps"), "{e}");
    }

    #[test]
    fn civil_days() {
        assert_eq!(super::days_from_civil(1970, 1, 1), 0);
        assert_eq!(super::days_from_civil(2000, 3, 1), 11_017);
    }
}
