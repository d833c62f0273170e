use super::*;
use crate::model::unknown::Unknown;
use crate::model::{katana450, ur5, KATANA_TOOL_MM};

const ALL: Offers = Offers {
    approach: true,
    time: true,
};

#[test]
fn every_listed_id_reads_back_and_frees_values_of_its_model() {
    for model in [katana450(KATANA_TOOL_MM).unwrap(), ur5().unwrap()] {
        let ids = library(&model, ALL);
        assert!(ids.len() > 40, "{}", ids.len());
        for id in &ids {
            let text = id.to_string();
            assert_eq!(text.parse::<EffectId>().as_ref(), Ok(id), "{text}");
            let row = id.row();
            // a change within the session sizes the model's last change of its kind
            let mut with_slot = model.clone();
            if id.is_change() {
                assert!(id.unknowns(&model).iter().all(Option::is_none), "{text}");
                let change = match id {
                    EffectId::ToolChange => id.change(&[0.0, 0.0, 0.0, 10.0]),
                    _ => id.change(&[0.0, 10.0]),
                };
                if let Ok(Change::Step(step)) = change {
                    with_slot.time_terms_mut().changes.push(step);
                }
            }
            let u = id.unknowns(&with_slot);
            assert!(u.iter().all(Option::is_some), "{text}: {u:?}");
            assert!(text.starts_with(row.family), "{text} vs {}", row.family);
            if row.report == Report::Step {
                assert_eq!(
                    u.len() + 1,
                    row.labels.len(),
                    "{text}: labels {:?}",
                    row.labels
                );
            } else if row.report != Report::Harmonic && row.report != Report::ValueAndDelta {
                assert_eq!(u.len(), row.labels.len(), "{text}: labels {:?}", row.labels);
            }
        }
    }
}

#[test]
fn the_katana_library_lists_kinds_in_table_order() {
    let model = katana450(KATANA_TOOL_MM).unwrap();
    let ids: Vec<String> = library(&model, ALL).iter().map(|i| i.to_string()).collect();
    let pos = |s: &str| ids.iter().position(|i| i == s).unwrap();
    assert!(pos("link_length:d5") < pos("encoder_harmonic:j1:h1"));
    assert!(pos("tool_offset") + 1 == pos("tool_length"));
    assert!(pos("tool_length") + 1 == pos("base_offset"));
    // the tilting values of a joint together, joint by joint
    assert_eq!(pos("stiffness:j2") + 1, pos("backlash:j2"));
    assert_eq!(pos("backlash:j2") + 1, pos("clearance:j2"));
    assert_eq!(pos("clearance:j2") + 1, pos("stiffness:j3"));
    assert!(!ids.iter().any(|i| i.starts_with("compliance")), "{ids:?}");
    assert!(pos("thermal") + 1 == pos("tool_change"));
    assert!(pos("payload_change") == ids.len() - 1);
    let none = library(&model, Offers::default());
    assert!(!none.iter().any(|i| i.row().path != Path::Pose), "{none:?}");
}

#[test]
fn malformed_ids_are_refused_naming_the_grammar() {
    for bad in [
        "",
        "tool",
        "link_length:mount_x",
        "link_length:a",
        "encoder_harmonic:j2:h4",
        "encoder_harmonic:j0:h1",
        "encoder_harmonic:j2",
        "stiffness:j0",
        "stiffness:j+1",
        "stiffness",
        "joint_coupling:j2:j2",
        "joint_coupling:j2",
        "thermal:j1",
        "tool_offset:j1",
        "payload:",
    ] {
        let err = bad.parse::<EffectId>().unwrap_err();
        assert!(
            err.to_string().contains("encoder_harmonic:j<i>:h<n>"),
            "{err}"
        );
    }
    assert_eq!(
        "time_drift:j3".parse::<EffectId>(),
        Ok(EffectId::JointDrift(2))
    );
    assert_eq!("time_drift".parse::<EffectId>(), Ok(EffectId::TimeDrift));
}

#[test]
fn a_joint_beyond_the_chain_frees_nothing() {
    let model = ur5().unwrap();
    for id in [
        "compliance:j7",
        "joint_coupling:j1:j9",
        "encoder_harmonic:j8:h1",
    ] {
        let id: EffectId = id.parse().unwrap();
        assert!(id.unknowns(&model).iter().all(Option::is_none), "{id}");
    }
}

#[test]
fn changes_take_the_rows_value_counts_and_ranges() {
    let id = EffectId::ToolLength;
    assert_eq!(
        id.change(&[0.5]),
        Ok(Change::Params(vec![("tool_dz".into(), 0.5)]))
    );
    assert!(id.change(&[0.5, 1.0]).is_err());
    assert!(EffectId::Thermal.change(&[30.0, 0.0]).is_err());
    assert!(EffectId::JointScale(1).change(&[2.0]).is_err());
    let h = EffectId::EncoderHarmonic { joint: 1, order: 1 }
        .change(&[0.03, 90.0])
        .unwrap();
    let Change::Params(p) = h else {
        panic!("{h:?}")
    };
    assert_eq!(p[0].0, "enc_j2_h1_sin");
    assert!(p[0].1.abs() < 1e-12 && (p[1].1 - 0.03).abs() < 1e-12);
}

#[test]
fn bounds_hold_negative_physical_values() {
    let model = katana450(KATANA_TOOL_MM).unwrap();
    let tp = model.tilt_params().unwrap()[1];
    let k = bound(Unknown::Param(tp.stiffness), &model).unwrap();
    assert!(k.below(0.0) && !k.below(1e-9) && k.hold == RIGID_STIFFNESS_KGFM_PER_DEG);
    let c = bound(Unknown::Param(tp.clearance), &model).unwrap();
    assert!(c.admits(0.0) && !c.admits(-1e-12) && c.hold == 0.0);
    assert!(bound(Unknown::Param(model.payload_param()), &model).is_some());
    assert!(bound(Unknown::Compliance(0), &model).unwrap().below(-1e-9));
    assert_eq!(
        bound(Unknown::ThermalTauMin, &model).unwrap().clamp(-3.0),
        1e-3
    );
    let a3 = model.param_index("a3").unwrap();
    assert!(bound(Unknown::Param(a3), &model).is_none());
}

#[test]
fn a_payload_is_at_most_the_robots_own_link_masses() {
    let model = katana450(KATANA_TOOL_MM).unwrap();
    // the Katana's moving links, thesis table 4.2: 1.03 + 0.90 + 1.00 + 0.80 kg
    let links_kg: f64 = model.masses().iter().map(|m| m.mass_kg).sum();
    assert!((links_kg - 3.73).abs() < 1e-9, "{links_kg}");
    let b = bound(Unknown::Param(model.payload_param()), &model).unwrap();
    assert_eq!(b.max, PAYLOAD_MAX_PER_LINK_MASS * links_kg);
    assert_eq!(b.outside(0.5), None, "the Katana's rated payload");
    assert_eq!(b.outside(8.0), Some(b.max), "above: held at the bound");
    assert_eq!(b.outside(-0.1), Some(0.0), "below: held at zero");
    // a model without link masses gives nothing to judge a payload by
    let mut b = crate::model::builder::ModelBuilder::new("bare");
    b.dh_row(1, 0.0, 100.0, 200.0, 0.0, [-180.0, 180.0], None)
        .unwrap();
    let bare = b.build().unwrap();
    assert!(bare.masses().is_empty());
    let open = bound(Unknown::Param(bare.payload_param()), &bare).unwrap();
    assert!(open.max.is_infinite() && open.outside(50.0).is_none());
    // a payload the user declared heavier than the links widens the range to admit it
    let mut declared = model.clone();
    let p = declared.payload_param();
    declared.set_param_at(p, 5.0).unwrap();
    let wide = bound_declared(Unknown::Param(p), &model, &declared).unwrap();
    assert_eq!(wide.max, 5.0);
    assert_eq!(wide.outside(5.0), None);
    assert_eq!(wide.outside(6.0), Some(5.0));
    // and leaves every other bound as it was
    let tp = model.tilt_params().unwrap()[0];
    assert_eq!(
        bound_declared(Unknown::Param(tp.clearance), &model, &declared),
        bound(Unknown::Param(tp.clearance), &model)
    );
}

/// Effect ids are spelled in this table only: no other library file holds a string literal
/// that is an effect id or begins one (`"payload"`, `"compliance:j{}"`); test modules and the
/// documentation comments may.
#[test]
fn no_other_file_spells_an_effect_id() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    // an id with a joint or a name begins `"family:`; one without is the family itself, except
    // `time_drift`, which is also the key of the simulated truth's drift object (truth.json)
    let mut families: Vec<&str> = TABLE.iter().map(|r| r.family).collect();
    families.dedup();
    let whole: Vec<&str> = TABLE
        .iter()
        .filter(|r| !r.grammar.contains(':') && r.kind != Kind::TimeDrift)
        .map(|r| r.family)
        .collect();
    let mut files = vec![root.clone()];
    let mut offenders = Vec::new();
    while let Some(p) = files.pop() {
        if p.is_dir() {
            for e in std::fs::read_dir(&p).unwrap() {
                files.push(e.unwrap().path());
            }
            continue;
        }
        let rel = p
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        if p.extension().is_none_or(|e| e != "rs")
            || rel == "model/effect.rs"
            || rel.starts_with("model/effect/")
        {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        for (n, line) in code.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue;
            }
            for f in &families {
                // the URDF's `<mesh scale="..">` attribute is XML, not the effect `scale`
                if rel == "urdf/collision.rs" && *f == "scale" {
                    continue;
                }
                if line.contains(&format!("\"{f}:"))
                    || (whole.contains(f) && line.contains(&format!("\"{f}\"")))
                {
                    offenders.push(format!("{rel}:{}: {}", n + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "effect ids spelled outside model/effect.rs:\n{}",
        offenders.join("\n")
    );
}
