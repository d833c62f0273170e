//! `rigctl plan`: planned poses against random ones on simulated Katana truths, the UR5 and a
//! 7-joint model file through the CLI, `--from-diagnose`, and bad input.

use rigctl::model::{katana450, KATANA_TOOL_MM};
use rigctl::plan::evaluate::planned_vs_random;
use rigctl::plan::metrics::median;
use rigctl::plan::{plan, FromDiagnose, PlanConfig};
use rigctl::sim::simulate::{truth_model, SimConfig};

use crate::common::record::record;
use crate::common::spawn::output;

/// `payload` -> `payload`, `link_length:a3` -> `link_length_a3`: a key for `record`.
fn key_of(id: &str) -> String {
    id.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// N = 12: the planned poses' expected sigmas are well below those of 12 random poses, the plan
/// is within 2 % of the best design possible on its (extended) candidates, and the held-out error
/// after calibration is closer to the noise floor. Default plan (weighted A, structured
/// candidates, continuous refinement, Jacobian with the tilt's contact direction held, 400
/// random draws): median planned / random sigma ratio measured 0.610-0.622 on seeds 1-5
/// (median 0.614; the issue's 0.6 is not reached, and the approximate optimum on the same
/// candidates reaches 0.603-0.623: see the README); the direct reading (median planned sigma
/// over the mean of the random designs' median sigmas) 0.630-0.647.
#[test]
fn twelve_planned_poses_beat_twelve_random_ones() {
    let declared = katana450(KATANA_TOOL_MM).unwrap();
    let cfg = PlanConfig::new(&declared, 12);
    let (mut ratios, mut planned, mut random, mut floor) = (vec![], vec![], vec![], vec![]);
    let mut direct = vec![];
    for seed in 1..=5u64 {
        let mut c = cfg.clone();
        c.seed = seed;
        let p = plan(&declared, &c, None).unwrap();
        assert_eq!(p.poses.len(), 12);
        assert!(
            p.poses.iter().all(|q| q.nominal_mm.z >= 40.0),
            "table clearance"
        );
        assert_eq!(p.unidentifiable, ["dth5+be4", "be5"]);
        assert!(p.structured_candidates > 0 && p.refinement.moves > 0);
        assert!(p.refinement.criterion_after > p.refinement.criterion_before);
        let best = p
            .optimum
            .as_ref()
            .expect("the A criterion has a certified optimum");
        assert!(
            best.efficiency > 0.98 && best.efficiency_bound > 0.97,
            "seed {seed}: efficiency {} (bound {})",
            best.efficiency,
            best.efficiency_bound
        );
        assert!(
            p.median_sigma_ratio < best.median_sigma_ratio + 0.02,
            "seed {seed}: plan {} optimum {}",
            p.median_sigma_ratio,
            best.median_sigma_ratio
        );
        ratios.push(p.median_sigma_ratio);
        direct.push(p.direct.ratio_to_mean());
        let sim = SimConfig {
            seed,
            ..SimConfig::default()
        };
        let (truth, _) = truth_model(&declared, &sim).unwrap();
        let (hp, hr) = planned_vs_random(&declared, &truth, &cfg, 12, 60, seed).unwrap();
        planned.push(hp.mean_mm - hp.floor_mm);
        random.push(hr.mean_mm - hr.floor_mm);
        floor.push(hp.floor_mm);
    }
    let (r, d) = (median(&ratios), median(&direct));
    eprintln!("median sigma ratios {ratios:?}, direct {direct:?}, held-out above floor planned {planned:?} random {random:?}");
    assert!(r <= 0.62, "median planned/random sigma ratio {r}");
    assert!(d <= 0.65, "direct reading {d}");
    assert!(
        median(&planned) < median(&random),
        "planned {planned:?} random {random:?}"
    );
}

const SEVEN_JOINTS: &str = r#"name = "seven"
[[chain]]
op = "dh"
joint = 1
d = 340.0
a = 0.0
alpha = -90.0
[[chain]]
op = "dh"
joint = 2
d = 0.0
a = 0.0
alpha = 90.0
[[chain]]
op = "dh"
joint = 3
d = 400.0
a = 0.0
alpha = 90.0
[[chain]]
op = "dh"
joint = 4
d = 0.0
a = 0.0
alpha = -90.0
[[chain]]
op = "dh"
joint = 5
d = 400.0
a = 0.0
alpha = -90.0
[[chain]]
op = "dh"
joint = 6
d = 0.0
a = 0.0
alpha = 90.0
[[chain]]
op = "dh"
joint = 7
d = 126.0
a = 0.0
alpha = 0.0
[[joint]]
min = -170.0
max = 170.0
[[joint]]
min = -170.0
max = 170.0
[[joint]]
min = -170.0
max = 170.0
[[joint]]
min = -170.0
max = 170.0
[[joint]]
min = -170.0
max = 170.0
[[joint]]
min = -170.0
max = 170.0
[[joint]]
min = -170.0
max = 170.0
"#;

#[test]
fn ur5_and_a_seven_joint_model_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    std::fs::write(p("seven.toml"), SEVEN_JOINTS).unwrap();
    for (model_args, joints) in [
        (vec!["--robot", "ur5"], 6usize),
        (vec!["--model", &p("seven.toml") as &str], 7),
    ] {
        let mut args = vec!["plan"];
        args.extend(model_args.iter().copied());
        let (csv, json, svg) = (p("plan.csv"), p("plan.json"), p("plan.svg"));
        args.extend(["--n", "30", "--out", &csv, "--json", &json, "--plot", &svg]);
        let out = output(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&csv).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        assert_eq!(header.len(), joints + 3);
        assert_eq!(header[0], "q1");
        assert_eq!(&header[joints..], ["nom_x", "nom_y", "nom_z"]);
        assert_eq!(text.lines().count(), 31);
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        for key in [
            "robot",
            "n",
            "criterion",
            "candidates",
            "parameters",
            "expected_sigma",
            "random_sigma",
            "condition_number",
            "random_condition_number",
            "median_sigma_ratio",
            "unidentifiable",
            "from_diagnose",
            "sheets",
        ] {
            assert!(doc.get(key).is_some(), "plan.json lacks {key}");
        }
        assert_eq!(doc["n"], 30);
        let ratio = doc["median_sigma_ratio"].as_f64().unwrap();
        assert!(ratio < 1.0, "{ratio}");
        assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    }
}

/// payload and link_length:d4 given 8 random poses: the 10 extra poses of the plan determine
/// both better than 10 random extra poses.
#[test]
fn from_diagnose_separates_an_aliased_pair() {
    let declared = katana450(KATANA_TOOL_MM).unwrap();
    let json = r#"{"effects": [], "aliased": [{"a": "payload", "b": "link_length:d4",
        "correlation": 0.97, "note": "test"}]}"#;
    let from = FromDiagnose::parse("D.json", json).unwrap();
    let mut cfg = PlanConfig::new(&declared, 10);
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(7);
    cfg.existing_q = rigctl::plan::draw_candidates(&declared, 8, &cfg.workspace, &mut rng)
        .unwrap()
        .into_iter()
        .map(|c| c.q_deg)
        .collect();
    let p = plan(&declared, &cfg, Some(&from)).unwrap();
    let f = p.from_diagnose.unwrap();
    assert_eq!(f.existing_poses, 8);
    let pair = &f.pairs[0];
    eprintln!(
        "correlation {} -> {}",
        pair.correlation_before, pair.correlation_after
    );
    assert_eq!(f.interest.len(), 2, "{:?}", f.interest);
    // the separated columns are better determined than with 10 random extra poses
    for name in &f.interest {
        let k = p.parameters.iter().position(|n| n == name).unwrap();
        let (planned, random) = (p.planned.sigma[k], p.random.sigma[k]);
        eprintln!("{name}: sigma planned {planned} random {random}");
        assert!(planned < 0.8 * random, "{name}: {planned} vs {random}");
        record(&format!("aliased_{}_planned_sigma", key_of(name)), planned);
        record(&format!("aliased_{}_random_sigma", key_of(name)), random);
    }
}

#[test]
fn bad_input_is_exit_2_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_string_lossy().into_owned();
    let out = output(&["plan", "--n", "0", "--out", &p("a.csv")]);
    assert_eq!(out.status.code(), Some(2));
    std::fs::write(
        p("d.json"),
        r#"{"aliased": [{"a": "payload", "b": "no_such_effect"}]}"#,
    )
    .unwrap();
    let out = output(&[
        "plan",
        "--n",
        "10",
        "--out",
        &p("b.csv"),
        "--from-diagnose",
        &p("d.json"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("aliased[0].b") && err.contains("d.json"),
        "{err}"
    );
    assert!(
        !std::path::Path::new(&p("b.csv")).exists(),
        "nothing half-written"
    );
}

/// How the extra poses of [`run_aliased_case`] are chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Extra {
    /// Random poses drawn like the measured ones.
    Random,
    /// `plan --from-diagnose` with its defaults (structured candidates and refinement on).
    Planned,
    /// The same without the structured candidates and the refinement (uniform pool only).
    PlannedPoolOnly,
}

/// End to end: a truth with `payload` and `link_length:a3` measured on 12 random poses; the
/// diagnosis of those poses (with the pair declared aliased) goes to `plan --from-diagnose`;
/// `diagnose` on the 12 + 20 planned poses names both with values within 3 sigma of the truth,
/// with the plan's defaults (structured candidates and continuous refinement, which put the
/// poses where the payload column at zero is singular before the linearity test) and with the
/// uniform pool only. With 20 random extra poses instead the payload is not named.
#[test]
fn diagnose_names_both_effects_after_the_planned_poses() {
    let truth = [
        ("payload", "mass_kg", 0.5),
        ("link_length:a3", "delta_mm", 0.3),
    ];
    let pair = Some(("link_length:a3", "payload"));
    let random = run_aliased_case(&truth, Extra::Random, pair);
    assert!(random[0].1.is_none(), "the case needs the plan: {random:?}");
    for extra in [Extra::Planned, Extra::PlannedPoolOnly] {
        let planned = run_aliased_case(&truth, extra, pair);
        for (id, v, s, want) in &planned {
            let (v, s) = (
                v.unwrap_or_else(|| panic!("{extra:?}: {id} not named: {planned:?}")),
                s.unwrap(),
            );
            assert!(
                (v - want).abs() <= 3.0 * s,
                "{extra:?}: {id}: {v} +- {s}, truth {want}"
            );
            let case = format!(
                "payload_case_{}_{}",
                key_of(&format!("{extra:?}")),
                key_of(id)
            );
            record(&format!("{case}_value"), v);
            record(&format!("{case}_sigma"), s);
        }
    }
}

/// The README's six-seed table of the payload / a3 case (slow: run with `cargo test --release
/// -p rigctl --test plan_sim six_seeds -- --ignored --nocapture`): for each seed pair and each
/// way of choosing the 20 extra poses, whether both effects are named within 3 sigma and the
/// payload's sigma.
#[test]
#[ignore]
fn six_seeds_of_the_payload_case() {
    let truth = [
        ("payload", "mass_kg", 0.5),
        ("link_length:a3", "delta_mm", 0.3),
    ];
    let pair = Some(("link_length:a3", "payload"));
    for extra in [Extra::Random, Extra::Planned, Extra::PlannedPoolOnly] {
        let mut named = 0;
        let mut sigmas = Vec::new();
        for seeds in [(3, 11), (1, 21), (2, 31), (4, 41), (5, 51), (6, 61)] {
            let r = run_aliased_case_seeded(&truth, extra, pair, seeds);
            let ok = r.iter().all(|(_, v, s, want)| match (v, s) {
                (Some(v), Some(s)) => (v - want).abs() <= 3.0 * s,
                _ => false,
            });
            named += usize::from(ok);
            if let Some(s) = r[0].2 {
                sigmas.push(s);
            }
        }
        println!("{extra:?}: both named within 3 sigma on {named} of 6; payload sigma {sigmas:?}");
        // recorded only by this slow run (docs/results.md: compared when present)
        let tag = key_of(&format!("{extra:?}"));
        record(&format!("six_seeds_{tag}_named"), named);
        record(&format!("six_seeds_{tag}_payload_sigma"), sigmas);
    }
}

/// A second case, with the aliased pairs as `diagnose` itself reports them on the 12 random
/// poses (an encoder harmonic of joint 2 that those poses cannot tell from a second harmonic,
/// a joint-2 gear-ratio error, the joint-2 stiffness and a coupling; the stiffness acts through
/// its inverse, the linearity test's common factor absorbs that): after the 20 planned poses
/// (defaults) both truths are named within 3 sigma and the stand-ins are not.
#[test]
fn diagnose_still_names_an_encoder_harmonic_and_a_length_after_its_own_aliased_pairs() {
    let truth = [
        ("encoder_harmonic:j2:h1", "A", 0.05),
        ("link_length:a2", "delta_mm", 0.3),
    ];
    let named = run_aliased_case(&truth, Extra::Planned, None);
    for (id, v, s, want) in &named {
        let (v, s) = (v.unwrap_or_else(|| panic!("{id} not named")), s.unwrap());
        assert!(
            (v - want).abs() <= 3.0 * s,
            "{id}: {v} +- {s}, truth {want}"
        );
        record(&format!("harmonic_case_{}_value", key_of(id)), v);
        record(&format!("harmonic_case_{}_sigma", key_of(id)), s);
    }
}

/// Per effect of `truth_effects` (id, reported key, value): id, value, sigma (None when not
/// named), truth. `pair`: the aliased pair written into the first diagnosis's JSON (`None`:
/// the pairs it reports itself, which must not be empty).
fn run_aliased_case(
    truth_effects: &[(&str, &str, f64)],
    extra: Extra,
    pair: Option<(&str, &str)>,
) -> Vec<(String, Option<f64>, Option<f64>, f64)> {
    run_aliased_case_seeded(truth_effects, extra, pair, (3, 11))
}

/// As [`run_aliased_case`] with (truth seed, pose seed) `seeds`.
fn run_aliased_case_seeded(
    truth_effects: &[(&str, &str, f64)],
    extra: Extra,
    pair: Option<(&str, &str)>,
    seeds: (u64, u64),
) -> Vec<(String, Option<f64>, Option<f64>, f64)> {
    use rigctl::calib::MeasuredSet;
    use rigctl::diagnose::{diagnose, DiagnoseOptions};
    use rigctl::plan::evaluate::measure;
    use rigctl::sim::effects::parse_effect;

    let declared = katana450(KATANA_TOOL_MM).unwrap();
    let sim = SimConfig {
        seed: seeds.0,
        ..SimConfig::default()
    };
    let (mut truth, _) = truth_model(&declared, &sim).unwrap();
    for (id, _, v) in truth_effects {
        parse_effect(&format!("{id}={v}"))
            .unwrap()
            .apply(&mut truth)
            .unwrap();
    }
    let mut cfg = PlanConfig::new(&declared, 20);
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(seeds.1);
    let draw = |n: usize, rng: &mut rand_chacha::ChaCha8Rng| -> Vec<Vec<f64>> {
        rigctl::plan::draw_candidates(&declared, n, &cfg.workspace, rng)
            .unwrap()
            .into_iter()
            .map(|c| c.q_deg)
            .collect()
    };
    let existing = draw(12, &mut rng);
    let val_q = draw(40, &mut rng);
    let first: MeasuredSet = measure(&truth, &existing, 0.01, &mut rng).unwrap();
    let val = measure(&truth, &val_q, 0.01, &mut rng).unwrap();
    let opts = DiagnoseOptions::default();
    // the diagnosis of the 12 random poses, with the pair declared aliased
    let d0 = diagnose(&declared, &first, &val, &opts).unwrap();
    let mut doc = serde_json::to_value(&d0.report).unwrap();
    match pair {
        Some((a, b)) => {
            doc["aliased"] =
                serde_json::json!([{"a": a, "b": b, "correlation": 0.9, "note": "test"}])
        }
        None => assert!(!d0.report.aliased.is_empty(), "no aliased pair reported"),
    }
    let from = FromDiagnose::parse("D.json", &doc.to_string()).unwrap();
    cfg.existing_q = existing.clone();
    if extra == Extra::PlannedPoolOnly {
        cfg.structured = Some(false);
        cfg.refine_sweeps = Some(0);
    }
    let extra_q = if extra == Extra::Random {
        draw(20, &mut rng)
    } else {
        let p = plan(&declared, &cfg, Some(&from)).unwrap();
        if extra == Extra::Planned {
            assert!(
                p.structured_candidates > 0 && p.refinement.moves > 0,
                "defaults on"
            );
        }
        p.poses.iter().map(|c| c.q_deg.clone()).collect()
    };
    let more: MeasuredSet = measure(&truth, &extra_q, 0.01, &mut rng).unwrap();
    // one visit order (not `concat`, which keeps each part's own history of approach)
    let mut cal = first;
    cal.poses.q_deg.extend(more.poses.q_deg);
    cal.poses.xyz_mm.extend(more.poses.xyz_mm);
    let d = diagnose(&declared, &cal, &val, &opts).unwrap();
    let ids: Vec<&str> = d.report.effects.iter().map(|e| e.id.as_str()).collect();
    eprintln!("{extra:?}: effects {ids:?}");
    if pair.is_none() {
        let truths: Vec<&str> = truth_effects.iter().map(|t| t.0).collect();
        assert!(
            ids.iter().all(|i| truths.contains(i)),
            "stand-ins named: {ids:?}"
        );
    }
    truth_effects
        .iter()
        .map(|&(id, key, want)| {
            let e = d.report.effects.iter().find(|e| e.id == id);
            let v = e.and_then(|e| e.parameters.get(key));
            let s = e.map(|e| e.uncertainty.get(key).flatten().unwrap_or(f64::INFINITY));
            eprintln!("{extra:?}: {id}: {v:?} +- {s:?} (truth {want})");
            (id.to_string(), v, s, want)
        })
        .collect()
}
