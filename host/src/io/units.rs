//! Units of the numbers in an input file (`--units LENGTH,ANGLE`), converted at the edge to the
//! crate's internal convention (mm, deg). Lengths are the measured points and the readings of
//! prismatic joints; angles are the readings of revolute joints. Times stay in seconds.

use std::str::FromStr;

/// Length unit of a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LengthUnit {
    /// Millimetres (the internal unit).
    #[default]
    Mm,
    /// Metres.
    M,
}

/// Angle unit of a file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AngleUnit {
    /// Degrees (the internal unit).
    #[default]
    Deg,
    /// Radians.
    Rad,
}

/// The units of a file: `mm,deg` (default, FORMATS.md) or e.g. `m,rad`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Units {
    pub length: LengthUnit,
    pub angle: AngleUnit,
}

impl Units {
    /// Millimetres per file length unit.
    pub fn mm_per_length(self) -> f64 {
        match self.length {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1e3,
        }
    }

    /// A length in the file's unit, in mm.
    pub fn length_mm(self, v: f64) -> f64 {
        v * self.mm_per_length()
    }

    /// An angle in the file's unit, in deg.
    pub fn angle_deg(self, v: f64) -> f64 {
        match self.angle {
            AngleUnit::Deg => v,
            AngleUnit::Rad => v.to_degrees(),
        }
    }

    /// A joint reading in the file's unit, in model units (mm if `prismatic`, else deg).
    pub fn joint(self, v: f64, prismatic: bool) -> f64 {
        if prismatic {
            self.length_mm(v)
        } else {
            self.angle_deg(v)
        }
    }

    /// Whether these are the internal units (nothing to convert).
    pub fn is_internal(self) -> bool {
        self == Self::default()
    }
}

impl FromStr for Units {
    type Err = String;
    /// `LENGTH,ANGLE` with LENGTH `mm` or `m` and ANGLE `deg` or `rad`.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}`: expected LENGTH,ANGLE with LENGTH mm|m and ANGLE deg|rad");
        let (l, a) = s.split_once(',').ok_or_else(bad)?;
        let length = match l.trim() {
            "mm" => LengthUnit::Mm,
            "m" => LengthUnit::M,
            _ => return Err(bad()),
        };
        let angle = match a.trim() {
            "deg" => AngleUnit::Deg,
            "rad" => AngleUnit::Rad,
            _ => return Err(bad()),
        };
        Ok(Self { length, angle })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_converts() {
        let u: Units = "m,rad".parse().unwrap();
        assert!((u.joint(0.25, true) - 250.0).abs() < 1e-12);
        assert!((u.joint(std::f64::consts::FRAC_PI_2, false) - 90.0).abs() < 1e-12);
        assert!((u.length_mm(1.5) - 1500.0).abs() < 1e-12);
        assert!("mm,deg".parse::<Units>().unwrap().is_internal());
        for bad in ["m", "cm,deg", "m,grad", ""] {
            assert!(bad.parse::<Units>().is_err(), "{bad}");
        }
    }
}
