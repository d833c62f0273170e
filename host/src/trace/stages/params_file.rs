//! `rigctl trace --params FILE`: the stages' numbers read from TOML, a table per stage named as
//! [`TraceParams`]' fields (`[link]`, `[lines]`, ...), each key a number of that stage's struct;
//! what the file leaves out keeps its tuned value. Unknown tables or keys, a value of the wrong
//! type, or a number out of [`Bounded`]'s range are refused with the file's line and the field.

use std::path::{Path, PathBuf};

use super::TraceParams;

/// What every stage number must be: finite and within `[1e-3, 1e4]` (a ratio, a length in mm,
/// an angle in degrees, a cosine, pixels), or a count within `1..=1000`. The tracer divides by
/// and allocates from these numbers; a zero, a negative or a vast value would stop it or make
/// it run without end, so none is accepted.
pub(crate) trait Bounded {
    fn in_range(&self) -> bool;
}

/// The range of a floating-point stage number.
pub const NUMBER_RANGE: (f64, f64) = (1e-3, 1e4);
/// The range of a counted stage number (threads, rows, steps, candidates).
pub const COUNT_RANGE: (usize, usize) = (1, 1000);

impl Bounded for f64 {
    fn in_range(&self) -> bool {
        (NUMBER_RANGE.0..=NUMBER_RANGE.1).contains(self)
    }
}

impl Bounded for f32 {
    fn in_range(&self) -> bool {
        f64::from(*self).in_range()
    }
}

impl Bounded for usize {
    fn in_range(&self) -> bool {
        (COUNT_RANGE.0..=COUNT_RANGE.1).contains(self)
    }
}

/// A list of stage numbers (candidates, or one number per case): every one in range.
impl<T: Bounded, const N: usize> Bounded for [T; N] {
    fn in_range(&self) -> bool {
        self.iter().all(Bounded::in_range)
    }
}

/// A parameter file that could not be used.
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {message}", path.display(), line.map_or_else(String::new, |l| format!(":{l}")))]
pub struct ParamsFileError {
    pub path: PathBuf,
    /// The file's line (1-based) where known.
    pub line: Option<usize>,
    /// What is wrong, naming the table and key.
    pub message: String,
}

impl TraceParams {
    /// Reads a parameter file (see the module documentation).
    pub fn read_toml(path: &Path) -> Result<Self, ParamsFileError> {
        let text = std::fs::read_to_string(path).map_err(|e| ParamsFileError {
            path: path.to_path_buf(),
            line: None,
            message: format!("cannot read: {e}"),
        })?;
        Self::from_toml(&text).map_err(|(line, message)| ParamsFileError {
            path: path.to_path_buf(),
            line,
            message,
        })
    }

    /// The parameters of a TOML text over the tuned values; an error as (line, message).
    pub fn from_toml(text: &str) -> Result<Self, (Option<usize>, String)> {
        let params: Self = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start));
            let message = e.message().trim();
            match line.and_then(|l| key_at(text, l)) {
                Some(key) => (line, format!("{key}: {message}")),
                None => (line, message.to_string()),
            }
        })?;
        let stages = [
            ("prepare", params.prepare.out_of_range()),
            ("fiducials", params.fiducials.out_of_range()),
            ("camera", params.camera.out_of_range()),
            ("centreline", params.centreline.out_of_range()),
            ("link", params.link.out_of_range()),
            ("lines", params.lines.out_of_range()),
        ];
        match stages.into_iter().find_map(|(t, f)| f.map(|f| (t, f))) {
            None => Ok(params),
            Some((table, field)) => Err((
                key_line(text, table, field),
                format!(
                    "{table}.{field} out of range: a number must be finite and within \
                     [{}, {}], a count within {}..={}",
                    NUMBER_RANGE.0, NUMBER_RANGE.1, COUNT_RANGE.0, COUNT_RANGE.1
                ),
            )),
        }
    }
}

/// The 1-based line of byte `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    1 + text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// The key (`table.field`) set on the 1-based line `line`, if one is.
fn key_at(text: &str, line: usize) -> Option<String> {
    let mut current = String::new();
    for (i, raw) in text.lines().enumerate().take(line) {
        let l = raw.trim();
        if let Some(h) = l.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
            current = h.trim().to_string();
        } else if i + 1 == line {
            let (key, _) = l.split_once('=')?;
            let key: String = key.chars().filter(|c| !c.is_whitespace()).collect();
            return Some(if current.is_empty() {
                key
            } else {
                format!("{current}.{key}")
            });
        }
    }
    None
}

/// The line setting `table.field`: `field = ...` under `[table]`, or `table.field = ...`.
fn key_line(text: &str, table: &str, field: &str) -> Option<usize> {
    let mut current = String::new();
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        if let Some(h) = l.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
            current = h.trim().to_string();
            continue;
        }
        let Some((key, _)) = l.split_once('=') else {
            continue;
        };
        let key: String = key.chars().filter(|c| !c.is_whitespace()).collect();
        if (current == table && key == field)
            || (current.is_empty() && key == format!("{table}.{field}"))
        {
            return Some(i + 1);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::stages::LinesParams;

    #[test]
    fn a_file_sets_what_it_names_and_keeps_the_rest() {
        let p = TraceParams::from_toml(
            "[link]\nmin_mark_mm = 7.5\n\n[fiducials]\nmax_corner_candidates = 20\n",
        )
        .expect("valid");
        let mut want = TraceParams::default();
        want.link.min_mark_mm = 7.5;
        want.fiducials.max_corner_candidates = 20;
        assert_eq!(p, want);
        assert_eq!(
            TraceParams::from_toml("").expect("empty"),
            TraceParams::default()
        );
        let dotted = TraceParams::from_toml("lines.pass_mm = 4.0\n").expect("dotted");
        assert_eq!(dotted.lines.pass_mm, 4.0);
        let lists = TraceParams::from_toml(
            "[link]\nbridge_side_mm = [4.0, 7.0, 10.0]\n[lines]\nband_turn_deg = [30.0, 50.0]\n",
        )
        .expect("lists");
        assert_eq!(lists.link.bridge_side_mm, [4.0, 7.0, 10.0]);
        assert_eq!(lists.lines.band_turn_deg, [30.0, 50.0]);
        assert_eq!(
            lists.lines.band_turn_over_mm,
            LinesParams::default().band_turn_over_mm
        );
    }

    #[test]
    fn bad_files_name_their_line_and_field() {
        for (text, line, names) in [
            (
                "[link]\nmin_mark_mm = 5.0\nbridge_step_mm = 0.0\n",
                Some(3),
                "link.bridge_step_mm",
            ),
            (
                "lines.line_spacing_mm = -1\n",
                Some(1),
                "lines.line_spacing_mm",
            ),
            (
                "[centreline]\n\nfaint_run_steps = 100000\n",
                Some(3),
                "centreline.faint_run_steps",
            ),
            ("[link]\nmin_mark = 5.0\n", Some(2), "link.min_mark"),
            ("[camera]\ncentre_f = \"ten\"\n", Some(2), "camera.centre_f"),
            ("[camera]\ncentre_f = nan\n", Some(2), "camera.centre_f"),
            ("[linking]\n", Some(1), "linking"),
            (
                "[lines]\nband_turn_deg = [45.0, 0.0]\n",
                Some(2),
                "lines.band_turn_deg",
            ),
            (
                "[link]\nbridge_side_mm = [3.5, 6.0]\n",
                Some(2),
                "link.bridge_side_mm",
            ),
        ] {
            let (at, msg) = TraceParams::from_toml(text).expect_err(text);
            assert_eq!(at, line, "{text}: {msg}");
            assert!(msg.contains(names), "{text}: {msg}");
        }
    }
}
