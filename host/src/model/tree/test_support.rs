//! Building blocks of the small trees the unit tests of `model` and `calib` write by hand.

use super::{TreeElem, TreeJoint, TreeMass};
use crate::model::{Axis, Motion};

/// One constant elementary transform.
pub(crate) fn elem(motion: Motion, axis: Axis, name: &str, value: f64) -> TreeElem {
    TreeElem {
        motion,
        axis,
        name: name.into(),
        value,
    }
}

/// Revolute joint `name`: `Rx(al) Tx(a) Tz(d) Rz(q + offset)` from its parent's frame (`row` =
/// `[al, a, d]`, deg and mm), limits +-170 deg, `kg` at `com_mm` in its frame.
pub(crate) fn dh_joint(
    name: &str,
    parent: Option<usize>,
    row: [f64; 3],
    offset: f64,
    kg: f64,
    com_mm: [f64; 3],
) -> TreeJoint {
    use Axis::{X, Z};
    use Motion::{Rot, Trans};
    TreeJoint {
        name: name.into(),
        parent,
        before: vec![
            elem(Rot, X, &format!("al_{name}"), row[0]),
            elem(Trans, X, &format!("a_{name}"), row[1]),
            elem(Trans, Z, &format!("d_{name}"), row[2]),
        ],
        prismatic: false,
        offset_name: format!("off_{name}"),
        offset,
        limits: [-170.0, 170.0],
        masses: vec![TreeMass {
            mass_kg: kg,
            com_mm,
        }],
        compliance_deg_per_kgfm: 0.0,
        lateral_compliance_deg_per_kgfm: 0.0,
    }
}
