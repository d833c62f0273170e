//! The enum flags clap parses as `ValueEnum`s (`calibrate --method --select`, `simulate
//! --session`, `plan --criterion --sheet-rows`): the values clap accepts are the library's names
//! (FORMATS.md), `-h` lists them, and a bad value is a usage error (exit 2).

use clap::ValueEnum;
use rigctl::calib::calibrate_general::Select;
use rigctl::calib::Method;
use rigctl::plan::sheets::SheetRows;
use rigctl::plan::Criterion;
use rigctl::sim::session::SessionPath;

use super::common::spawn::{output, text};

/// The values clap accepts for `E`, in order.
fn values<E: ValueEnum>() -> Vec<String> {
    E::value_variants()
        .iter()
        .map(|v| {
            v.to_possible_value()
                .expect("no value is skipped")
                .get_name()
                .to_string()
        })
        .collect()
}

#[test]
fn the_values_clap_accepts_are_the_library_names() {
    let methods = [Method::Standard, Method::Influence, Method::Tilting];
    assert_eq!(values::<Method>(), methods.map(Method::as_str));
    for m in methods {
        assert_eq!(m.as_str().parse::<Method>(), Ok(m));
    }
    assert_eq!(values::<Select>(), ["all", "press"]);
    for (name, s) in ["all", "press"]
        .into_iter()
        .zip([Select::All, Select::Press])
    {
        assert_eq!(name.parse::<Select>(), Ok(s));
    }
    let paths = [SessionPath::Circle, SessionPath::Line];
    assert_eq!(values::<SessionPath>(), paths.map(SessionPath::as_str));
    for p in paths {
        assert_eq!(p.as_str().parse::<SessionPath>(), Ok(p));
    }
    let criteria = [Criterion::D, Criterion::A, Criterion::G, Criterion::I];
    assert_eq!(values::<Criterion>(), criteria.map(Criterion::letter));
    for c in criteria {
        assert_eq!(Criterion::parse(c.letter()), Some(c));
    }
    let rows = [SheetRows::Fused, SheetRows::Trace, SheetRows::Plane];
    assert_eq!(values::<SheetRows>(), rows.map(SheetRows::as_str));
    for r in rows {
        assert_eq!(SheetRows::parse(r.as_str()), Some(r));
    }
}

#[test]
fn help_lists_the_values_and_a_bad_value_exits_2() {
    for (command, flag, listed) in [
        ("calibrate", "--method", "standard, influence, tilting"),
        ("calibrate", "--select", "all, press"),
        ("simulate", "--session", "circle, line"),
        ("plan", "--criterion", "d, a, g, i"),
        ("plan", "--sheet-rows", "fused, trace, plane"),
    ] {
        let help = output(&[command, "-h"]);
        assert!(
            help.status.success(),
            "{command} -h: {}",
            text(&help.stderr)
        );
        let help = text(&help.stdout);
        assert!(
            help.contains(&format!("[possible values: {listed}]")),
            "{command} -h does not list {flag} {listed}:\n{help}"
        );
        let bad = output(&[command, flag, "magic"]);
        let err = text(&bad.stderr);
        assert_eq!(bad.status.code(), Some(2), "{command} {flag} magic: {err}");
        assert!(
            err.contains("'magic'") && err.contains(flag) && err.contains(listed),
            "{command} {flag} magic: {err}"
        );
    }
    // the criterion's letter is taken in either case
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.csv");
    let out = out.to_str().expect("a UTF-8 temporary path");
    let upper = output(&[
        "plan",
        "--criterion",
        "A",
        "--robot",
        "no-such-robot",
        "--n",
        "5",
        "--out",
        out,
    ]);
    let err = text(&upper.stderr);
    assert!(!err.contains("invalid value"), "{err}");
    assert!(err.contains("unknown robot `no-such-robot`"), "{err}");
}
