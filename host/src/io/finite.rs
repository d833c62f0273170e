//! The one guard every text writer goes through: no non-finite number (`NaN`, `inf`) in a CSV
//! table, a model file (TOML) or a URDF that a command writes. A text whose numbers are not all
//! finite is refused before it is written, naming the value and where it is
//! ([`check_text`]); [`super::atomic::write_text_atomic`] checks and writes in one call.
//!
//! JSON reports (`calibrate`, `diagnose`, `joints`) go through [`super::finite_json`] instead:
//! `serde_json` would write a non-finite number as `null`, which reads as "not available".

use std::fmt;

/// The format of a text, for [`check_text`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TextFormat {
    /// A CSV table: a header line, then rows of comma-separated cells (`#` lines are comments).
    Csv,
    /// A TOML document (model files, pot calibrations, sheet placements).
    Toml,
    /// An XML document (URDF): every whitespace-separated token of an attribute value, names
    /// (`name`, `link`, `joint`, `type`, `filename`) excepted.
    Xml,
}

/// A non-finite number found in a text about to be written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NonFinite {
    /// Where it is: `line 3, column x_mm`, `key chain[2].value`, `<origin xyz> of joint j2`.
    pub location: String,
    /// The number as it would have been written (`NaN`, `inf`, `-inf`).
    pub value: String,
}

impl fmt::Display for NonFinite {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} is not a finite number (the computation left every physical range); nothing written",
            self.location, self.value
        )
    }
}

impl std::error::Error for NonFinite {}

/// `token` read as a number that is not finite (`NaN`, `nan`, `inf`, `-inf`, `infinity`, ...).
fn non_finite(token: &str) -> bool {
    let t = token.trim();
    !t.is_empty() && t.parse::<f64>().is_ok_and(|v| !v.is_finite())
}

/// The first non-finite number of `text`, read as `format`, if any.
pub fn check_text(format: TextFormat, text: &str) -> Result<(), NonFinite> {
    match format {
        TextFormat::Csv => check_csv(text),
        TextFormat::Toml => check_toml(text),
        TextFormat::Xml => check_xml(text),
    }
}

fn check_csv(text: &str) -> Result<(), NonFinite> {
    let mut header: Option<Vec<&str>> = None;
    for (k, line) in text.lines().enumerate() {
        if line.trim_start().starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let Some(names) = &header else {
            header = Some(line.split(',').map(str::trim).collect());
            continue;
        };
        for (c, cell) in line.split(',').enumerate() {
            if non_finite(cell) {
                let column = names
                    .get(c)
                    .map_or_else(|| format!("{}", c + 1), |n| n.to_string());
                return Err(NonFinite {
                    location: format!("line {}, column {column}", k + 1),
                    value: cell.trim().to_string(),
                });
            }
        }
    }
    Ok(())
}

fn walk_toml(value: &toml::Value, key: &str) -> Result<(), NonFinite> {
    match value {
        toml::Value::Float(v) if !v.is_finite() => Err(NonFinite {
            location: format!("key {key}"),
            value: format!("{v}"),
        }),
        toml::Value::Array(items) => items
            .iter()
            .enumerate()
            .try_for_each(|(i, v)| walk_toml(v, &format!("{key}[{i}]"))),
        toml::Value::Table(t) => t.iter().try_for_each(|(k, v)| {
            let key = if key.is_empty() {
                k.clone()
            } else {
                format!("{key}.{k}")
            };
            walk_toml(v, &key)
        }),
        _ => Ok(()),
    }
}

fn check_toml(text: &str) -> Result<(), NonFinite> {
    // a text TOML cannot parse has nothing a reader would take as a number; the writers' own
    // tests read their output back
    match text.parse::<toml::Table>() {
        Ok(t) => walk_toml(&toml::Value::Table(t), ""),
        Err(_) => Ok(()),
    }
}

fn check_xml(text: &str) -> Result<(), NonFinite> {
    const NAMES: [&str; 5] = ["name", "link", "joint", "type", "filename"];
    let Ok(doc) = roxmltree::Document::parse(text) else {
        return Ok(());
    };
    for node in doc.descendants().filter(|n| n.is_element()) {
        for a in node.attributes().filter(|a| !NAMES.contains(&a.name())) {
            if let Some(bad) = a
                .value()
                .split(|c: char| c.is_whitespace() || c == ',')
                .find(|t| non_finite(t))
            {
                let owner = node
                    .ancestors()
                    .find_map(|n| n.attribute("name"))
                    .map_or_else(String::new, |n| format!(" of `{n}`"));
                let line = doc.text_pos_at(node.range().start).row;
                return Err(NonFinite {
                    location: format!(
                        "line {line}, <{} {}>{owner}",
                        node.tag_name().name(),
                        a.name()
                    ),
                    value: bad.to_string(),
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_texts_pass() {
        assert!(check_text(TextFormat::Csv, "x_mm,name\n1.5,nanometre\n-2e300,inf_x\n").is_ok());
        assert!(check_text(TextFormat::Toml, "name = \"nan\"\nvalue = 1e300\n").is_ok());
        assert!(check_text(
            TextFormat::Xml,
            "<robot name=\"inf\"><joint name=\"nan\"><origin xyz=\"0 1e-300 2\"/></joint></robot>"
        )
        .is_ok());
    }

    /// Each text holds one non-finite number: where it is reported and as what.
    #[test]
    fn a_non_finite_number_is_named_with_its_place() {
        let cases = [
            (TextFormat::Csv, "# c\nid,x_mm\n1,2\n2,NaN\n", "line 4, column x_mm", "NaN"),
            (TextFormat::Csv, "a\n1,-inf\n", "line 2, column 2", "-inf"),
            (
                TextFormat::Toml,
                "name = \"m\"\n[[chain]]\nvalue = 1.0\n[[chain]]\nvalue = inf\n",
                "key chain[1].value",
                "inf",
            ),
            (TextFormat::Toml, "[params]\nx = nan\n", "key params.x", "NaN"),
            (
                TextFormat::Xml,
                "<robot name=\"r\">\n<joint name=\"j2\">\n<origin xyz=\"0 NaN 0\"/></joint></robot>",
                "line 3, <origin xyz> of `j2`",
                "NaN",
            ),
        ];
        for (format, text, location, value) in cases {
            let e = check_text(format, text).unwrap_err();
            assert_eq!(
                (e.location.as_str(), e.value.as_str()),
                (location, value),
                "{text}"
            );
        }
    }
}
