//! The guard of the JSON writers: `serde_json` writes a non-finite number as `null`, which a
//! reader of FORMATS.md takes for "not available", so a `NaN` computed by mistake would leave a
//! command as a quiet `null` with exit 0. [`check_json`] walks a value through serde before it
//! is serialised and names the first non-finite number by its key path
//! (`effects[0].validation_mean_mm_after`). Values that may be unknown are `Option`s (`None`
//! is written `null` and is not checked).

use std::fmt;

use serde::ser::{self, Serialize};

use super::finite::NonFinite;

/// The first non-finite number of `value`, by its key path.
pub fn check_json<T: Serialize + ?Sized>(value: &T) -> Result<(), NonFinite> {
    let mut walker = Walker { path: Vec::new() };
    match value.serialize(&mut walker) {
        Ok(()) => Ok(()),
        Err(Found::NonFinite { path, value }) => Err(NonFinite {
            location: if path.is_empty() {
                "the document".to_string()
            } else {
                format!("key {path}")
            },
            value,
        }),
        // a value serde itself cannot serialise is serde_json's to report
        Err(Found::Other(_)) => Ok(()),
    }
}

#[derive(Debug)]
enum Found {
    NonFinite { path: String, value: String },
    Other(String),
}

impl fmt::Display for Found {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Found::NonFinite { path, value } => write!(f, "{path}: {value}"),
            Found::Other(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Found {}

impl ser::Error for Found {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Found::Other(msg.to_string())
    }
}

/// Walks a value, keeping the key path; serialises nothing.
struct Walker {
    path: Vec<String>,
}

impl Walker {
    fn float(&self, v: f64) -> Result<(), Found> {
        if v.is_finite() {
            return Ok(());
        }
        let mut path = String::new();
        for p in &self.path {
            if !p.starts_with('[') && !path.is_empty() {
                path.push('.');
            }
            path.push_str(p);
        }
        Err(Found::NonFinite {
            path,
            value: if v.is_nan() {
                "NaN".into()
            } else if v > 0.0 {
                "inf".into()
            } else {
                "-inf".into()
            },
        })
    }

    fn nested<T: Serialize + ?Sized>(&mut self, key: String, value: &T) -> Result<(), Found> {
        self.path.push(key);
        let r = value.serialize(&mut *self);
        self.path.pop();
        r
    }
}

/// Compound values: element `index` of a sequence, or field `key` of a map or struct.
struct Compound<'a> {
    walker: &'a mut Walker,
    index: usize,
    key: Option<String>,
}

impl<'a> Compound<'a> {
    fn new(walker: &'a mut Walker) -> Self {
        Self {
            walker,
            index: 0,
            key: None,
        }
    }

    fn element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Found> {
        let key = format!("[{}]", self.index);
        self.index += 1;
        self.walker.nested(key, value)
    }
}

macro_rules! ok_scalars {
    ($($name:ident: $t:ty),*) => {
        $(fn $name(self, _v: $t) -> Result<(), Found> { Ok(()) })*
    };
}

impl<'a> ser::Serializer for &'a mut Walker {
    type Ok = ();
    type Error = Found;
    type SerializeSeq = Compound<'a>;
    type SerializeTuple = Compound<'a>;
    type SerializeTupleStruct = Compound<'a>;
    type SerializeTupleVariant = Compound<'a>;
    type SerializeMap = Compound<'a>;
    type SerializeStruct = Compound<'a>;
    type SerializeStructVariant = Compound<'a>;

    ok_scalars!(
        serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32,
        serialize_i64: i64, serialize_u8: u8, serialize_u16: u16, serialize_u32: u32,
        serialize_u64: u64, serialize_char: char, serialize_str: &str, serialize_bytes: &[u8]
    );

    fn serialize_f32(self, v: f32) -> Result<(), Found> {
        self.float(f64::from(v))
    }
    fn serialize_f64(self, v: f64) -> Result<(), Found> {
        self.float(v)
    }
    fn serialize_none(self) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<(), Found> {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_unit_struct(self, _name: &'static str) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_unit_variant(
        self,
        _name: &'static str,
        _index: u32,
        _variant: &'static str,
    ) -> Result<(), Found> {
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        value: &T,
    ) -> Result<(), Found> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _name: &'static str,
        _index: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<(), Found> {
        self.nested(variant.to_string(), value)
    }
    fn serialize_seq(self, _len: Option<usize>) -> Result<Compound<'a>, Found> {
        Ok(Compound::new(self))
    }
    fn serialize_tuple(self, _len: usize) -> Result<Compound<'a>, Found> {
        Ok(Compound::new(self))
    }
    fn serialize_tuple_struct(
        self,
        _name: &'static str,
        _len: usize,
    ) -> Result<Compound<'a>, Found> {
        Ok(Compound::new(self))
    }
    fn serialize_tuple_variant(
        self,
        _name: &'static str,
        _index: u32,
        _variant: &'static str,
        _len: usize,
    ) -> Result<Compound<'a>, Found> {
        Ok(Compound::new(self))
    }
    fn serialize_map(self, _len: Option<usize>) -> Result<Compound<'a>, Found> {
        Ok(Compound::new(self))
    }
    fn serialize_struct(self, _name: &'static str, _len: usize) -> Result<Compound<'a>, Found> {
        Ok(Compound::new(self))
    }
    fn serialize_struct_variant(
        self,
        name: &'static str,
        index: u32,
        variant: &'static str,
        len: usize,
    ) -> Result<Compound<'a>, Found> {
        ser::Serializer::serialize_tuple_variant(self, name, index, variant, len)
    }
}

macro_rules! seq_like {
    ($($tr:ident :: $method:ident),*) => {
        $(impl ser::$tr for Compound<'_> {
            type Ok = ();
            type Error = Found;
            fn $method<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Found> {
                self.element(value)
            }
            fn end(self) -> Result<(), Found> {
                Ok(())
            }
        })*
    };
}

seq_like!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

macro_rules! struct_like {
    ($($tr:ident),*) => {
        $(impl ser::$tr for Compound<'_> {
            type Ok = ();
            type Error = Found;
            fn serialize_field<T: Serialize + ?Sized>(
                &mut self,
                key: &'static str,
                value: &T,
            ) -> Result<(), Found> {
                self.walker.nested(key.to_string(), value)
            }
            fn end(self) -> Result<(), Found> {
                Ok(())
            }
        })*
    };
}

struct_like!(SerializeStruct, SerializeStructVariant);

impl ser::SerializeMap for Compound<'_> {
    type Ok = ();
    type Error = Found;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, key: &T) -> Result<(), Found> {
        // keys are names (strings) in every document rigctl writes
        self.key = Some(
            serde_json::to_value(key)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_else(|| "?".to_string()),
        );
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Found> {
        let key = self.key.take().unwrap_or_else(|| "?".to_string());
        self.walker.nested(key, value)
    }
    fn end(self) -> Result<(), Found> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;
    use std::collections::BTreeMap;

    #[derive(Serialize)]
    struct Effect {
        id: String,
        after_mm: f64,
        sigma: Option<f64>,
    }

    #[derive(Serialize)]
    struct Doc {
        effects: Vec<Effect>,
        values: BTreeMap<String, f64>,
        pair: (f64, f32),
    }

    fn doc() -> Doc {
        Doc {
            effects: vec![
                Effect {
                    id: "a".into(),
                    after_mm: 0.1,
                    sigma: None,
                },
                Effect {
                    id: "b".into(),
                    after_mm: 0.2,
                    sigma: Some(0.01),
                },
            ],
            values: [("x".to_string(), 1.0)].into_iter().collect(),
            pair: (1.0, 2.0),
        }
    }

    #[test]
    fn finite_documents_and_nones_pass() {
        assert!(check_json(&doc()).is_ok());
        assert!(check_json(&serde_json::json!({"a": null, "b": [1, 2.5]})).is_ok());
    }

    #[test]
    fn a_non_finite_number_is_named_by_its_path() {
        let mut d = doc();
        d.effects[1].after_mm = f64::NAN;
        let e = check_json(&d).unwrap_err();
        assert_eq!(e.location, "key effects[1].after_mm");
        assert_eq!(e.value, "NaN");

        let mut d = doc();
        d.effects[0].sigma = Some(f64::INFINITY);
        assert_eq!(check_json(&d).unwrap_err().location, "key effects[0].sigma");

        let mut d = doc();
        d.values.insert("y".into(), f64::NEG_INFINITY);
        let e = check_json(&d).unwrap_err();
        assert_eq!(
            (e.location.as_str(), e.value.as_str()),
            ("key values.y", "-inf")
        );

        let mut d = doc();
        d.pair.1 = f32::NAN;
        assert_eq!(check_json(&d).unwrap_err().location, "key pair[1]");
        assert!(check_json(&f64::NAN).unwrap_err().location == "the document");
    }
}
