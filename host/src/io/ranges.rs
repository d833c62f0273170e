//! Physical ranges of input values: finite numbers far outside anything a robot cell can
//! produce (a position of 1e300 mm) are refused as bad input instead of flowing into the
//! numerics as infinities. The limits are deliberately generous (orders of magnitude beyond any
//! real value) so that no real measurement is ever refused:
//!
//! | kind | columns (by name) | limit |
//! |---|---|---|
//! | position / length | `x y z`, `nom_*`, `dev_*`, `dp*`, `*_mm`, `ax ay az` | 100 m |
//! | angle | `q<i>`, `phi theta psi`, `*_deg` | +-10 000 deg |
//! | time | `t`, `*_s` | a century (3.16e9 s) |
//! | unit-vector component | `u_x`.. `n_z` | 1 000 |
//! | raw counts | `raw` | 2^32 |
//! | anything else | | 1e12 |

/// Largest position or length, mm (100 m).
pub const MAX_POSITION_MM: f64 = 1e5;
/// Largest angle, deg.
pub const MAX_ANGLE_DEG: f64 = 1e4;
/// Largest time, s (one century).
pub const MAX_TIME_S: f64 = 100.0 * 365.25 * 86_400.0;
/// Largest raw ADC count.
pub const MAX_RAW_COUNTS: f64 = 4_294_967_296.0;
/// Largest magnitude for a column of no known kind.
pub const MAX_OTHER: f64 = 1e12;
const MAX_DIRECTION: f64 = 1e3;

/// A number for a message: plain when of a readable size, else in exponent form (`1e308`, not
/// 309 digits).
pub fn show(v: f64) -> String {
    if v == 0.0 || (1e-4..1e9).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The kind of quantity a column holds, from its name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    PositionMm,
    AngleDeg,
    TimeS,
    Direction,
    RawCounts,
    Other,
}

impl Quantity {
    /// Classifies a column name.
    pub fn of_column(name: &str) -> Self {
        let is_joint = name.len() > 1
            && name.starts_with('q')
            && name[1..].bytes().all(|b| b.is_ascii_digit());
        match name {
            "x" | "y" | "z" | "ax" | "ay" | "az" => Self::PositionMm,
            "phi" | "theta" | "psi" => Self::AngleDeg,
            "t" => Self::TimeS,
            "raw" => Self::RawCounts,
            "u_x" | "u_y" | "u_z" | "n_x" | "n_y" | "n_z" => Self::Direction,
            _ if is_joint || name.ends_with("_deg") => Self::AngleDeg,
            _ if name.ends_with("_mm")
                || name.starts_with("nom_")
                || name.starts_with("dev_")
                || name.starts_with("dp") =>
            {
                Self::PositionMm
            }
            _ if name.ends_with("_s") => Self::TimeS,
            _ => Self::Other,
        }
    }

    /// The largest magnitude accepted and its description.
    pub fn limit(self) -> (f64, &'static str) {
        match self {
            Self::PositionMm => (MAX_POSITION_MM, "a position beyond 100 m"),
            Self::AngleDeg => (MAX_ANGLE_DEG, "an angle beyond +-10000 deg"),
            Self::TimeS => (MAX_TIME_S, "a time beyond a century"),
            Self::Direction => (MAX_DIRECTION, "a direction component beyond 1000"),
            Self::RawCounts => (MAX_RAW_COUNTS, "a raw count beyond 2^32"),
            Self::Other => (MAX_OTHER, "a value beyond 1e12"),
        }
    }

    /// `Some(problem)` when `v` is outside the physical range of this quantity.
    pub fn check(self, v: f64) -> Option<String> {
        let (limit, what) = self.limit();
        (v.abs() > limit).then(|| format!("out of physical range: {what}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_classified_by_name() {
        assert_eq!(Quantity::of_column("x"), Quantity::PositionMm);
        assert_eq!(Quantity::of_column("nom_z"), Quantity::PositionMm);
        assert_eq!(Quantity::of_column("travel_mm"), Quantity::PositionMm);
        assert_eq!(Quantity::of_column("q12"), Quantity::AngleDeg);
        assert_eq!(Quantity::of_column("incl_x_deg"), Quantity::AngleDeg);
        assert_eq!(Quantity::of_column("t"), Quantity::TimeS);
        assert_eq!(Quantity::of_column("start_s"), Quantity::TimeS);
        assert_eq!(Quantity::of_column("raw"), Quantity::RawCounts);
        assert_eq!(Quantity::of_column("payload_kg"), Quantity::Other);
    }

    #[test]
    fn limits_refuse_absurd_values_only() {
        assert!(Quantity::PositionMm.check(99_999.0).is_none());
        assert!(Quantity::PositionMm.check(1e300).is_some());
        assert!(Quantity::AngleDeg.check(-10_001.0).is_some());
        assert!(Quantity::TimeS.check(1.7e9).is_none());
        assert!(Quantity::TimeS.check(1e300).is_some());
    }
}
