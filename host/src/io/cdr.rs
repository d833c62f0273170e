//! CDR (OMG XCDR1, as ROS 2 serialises messages) decoding of `sensor_msgs/msg/JointState`.
//!
//! Layout: a 4-byte encapsulation header (`00 00` big endian, `00 01` little endian, two option
//! bytes), then the fields, each primitive aligned to its size counted from the end of the
//! header:
//!
//! ```text
//! std_msgs/Header header
//!   builtin_interfaces/Time stamp { int32 sec; uint32 nanosec }
//!   string frame_id                 uint32 length incl. NUL, bytes, NUL
//! string[] name                     uint32 count, then count strings (each aligned to 4)
//! float64[] position                uint32 count, then (aligned to 8 when count > 0) f64s
//! float64[] velocity, effort        (not needed here, not read)
//! ```
//!
//! Every length is checked against the bytes that remain before anything is allocated, so a
//! damaged or hostile message is an error ([`CdrError`]), never a panic or a huge allocation.

/// A `JointState` message, the fields a joint log needs.
#[derive(Debug, Clone, PartialEq)]
pub struct JointState {
    /// `header.stamp.sec`.
    pub sec: i32,
    /// `header.stamp.nanosec`.
    pub nanosec: u32,
    /// `header.frame_id`.
    pub frame_id: String,
    /// `name[]`.
    pub names: Vec<String>,
    /// `position[]` (rad, m for prismatic joints).
    pub position: Vec<f64>,
}

impl JointState {
    /// The header stamp in nanoseconds.
    pub fn stamp_ns(&self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }
}

/// Why a message does not decode.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    #[error("{len} bytes: too short for the CDR encapsulation header")]
    NoHeader { len: usize },
    #[error("encapsulation {0:#06x} is not plain CDR (0x0000 big endian, 0x0001 little endian)")]
    Encapsulation(u16),
    #[error("field `{field}`: needs {need} bytes at offset {offset}, the message has {len}")]
    Short {
        field: &'static str,
        need: usize,
        offset: usize,
        len: usize,
    },
    #[error("field `{field}`: string of length 0 (a CDR string holds at least its NUL)")]
    EmptyString { field: &'static str },
    #[error("field `{field}`: string is not NUL-terminated UTF-8")]
    BadString { field: &'static str },
    #[error("nanosec {0} is not below 1e9")]
    Nanosec(u32),
}

struct Cursor<'a> {
    /// The bytes after the encapsulation header.
    data: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, field: &'static str, align: usize, n: usize) -> Result<&'a [u8], CdrError> {
        let start = self.pos.div_ceil(align) * align;
        let short = CdrError::Short {
            field,
            need: n,
            offset: start + 4,
            len: self.data.len() + 4,
        };
        let end = start.checked_add(n).ok_or(short.clone())?;
        let bytes = self.data.get(start..end).ok_or(short)?;
        self.pos = end;
        Ok(bytes)
    }

    fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        let b: [u8; 4] = self
            .take(field, 4, 4)?
            .try_into()
            .map_err(|_| CdrError::BadString { field })?;
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        let b: [u8; 8] = self
            .take(field, 8, 8)?
            .try_into()
            .map_err(|_| CdrError::BadString { field })?;
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }

    fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let len = self.u32(field)? as usize;
        if len == 0 {
            return Err(CdrError::EmptyString { field });
        }
        let bytes = self.take(field, 1, len)?;
        match bytes.split_last() {
            Some((0, text)) => std::str::from_utf8(text)
                .map(str::to_string)
                .map_err(|_| CdrError::BadString { field }),
            _ => Err(CdrError::BadString { field }),
        }
    }

    /// A sequence count, checked against the bytes left (each element needs `min_size`).
    fn count(&mut self, field: &'static str, min_size: usize) -> Result<usize, CdrError> {
        let n = self.u32(field)? as usize;
        let left = self.data.len().saturating_sub(self.pos);
        if n.saturating_mul(min_size) > left {
            return Err(CdrError::Short {
                field,
                need: n.saturating_mul(min_size),
                offset: self.pos + 4,
                len: self.data.len() + 4,
            });
        }
        Ok(n)
    }
}

/// Decodes the header, names and positions of a CDR-serialised `sensor_msgs/msg/JointState`.
pub fn decode_joint_state(msg: &[u8]) -> Result<JointState, CdrError> {
    if msg.len() < 4 {
        return Err(CdrError::NoHeader { len: msg.len() });
    }
    let little = match u16::from_be_bytes([msg[0], msg[1]]) {
        0x0000 => false,
        0x0001 => true,
        other => return Err(CdrError::Encapsulation(other)),
    };
    let mut c = Cursor {
        data: &msg[4..],
        pos: 0,
        little,
    };
    let sec = c.u32("header.stamp.sec")? as i32;
    let nanosec = c.u32("header.stamp.nanosec")?;
    if nanosec >= 1_000_000_000 {
        return Err(CdrError::Nanosec(nanosec));
    }
    let frame_id = c.string("header.frame_id")?;
    // A string needs at least its 4-byte length and its NUL.
    let n_names = c.count("name", 5)?;
    let mut names = Vec::with_capacity(n_names);
    for _ in 0..n_names {
        names.push(c.string("name")?);
    }
    let n_pos = c.count("position", 8)?;
    let mut position = Vec::with_capacity(n_pos);
    for _ in 0..n_pos {
        position.push(c.f64("position")?);
    }
    Ok(JointState {
        sec,
        nanosec,
        frame_id,
        names,
        position,
    })
}

/// Encodes a `JointState` as little-endian CDR with empty `velocity` and `effort` (the inverse
/// of [`decode_joint_state`]; for tests and tools that write bags).
pub fn encode_joint_state(m: &JointState) -> Vec<u8> {
    fn pad(out: &mut Vec<u8>, align: usize) {
        while !(out.len() - 4).is_multiple_of(align) {
            out.push(0);
        }
    }
    fn u32le(out: &mut Vec<u8>, v: u32) {
        pad(out, 4);
        out.extend_from_slice(&v.to_le_bytes());
    }
    fn string(out: &mut Vec<u8>, s: &str) {
        u32le(out, s.len() as u32 + 1);
        out.extend_from_slice(s.as_bytes());
        out.push(0);
    }
    let mut out = vec![0, 1, 0, 0];
    u32le(&mut out, m.sec as u32);
    u32le(&mut out, m.nanosec);
    string(&mut out, &m.frame_id);
    u32le(&mut out, m.names.len() as u32);
    for n in &m.names {
        string(&mut out, n);
    }
    u32le(&mut out, m.position.len() as u32);
    if !m.position.is_empty() {
        pad(&mut out, 8);
    }
    for p in &m.position {
        out.extend_from_slice(&p.to_le_bytes());
    }
    u32le(&mut out, 0); // velocity
    u32le(&mut out, 0); // effort
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Little endian, as rclcpp / rosbags write it: stamp 7 s 500 ns, frame "b", names "j1",
    /// "arm" (odd lengths: padding before the next length), positions 0.5 and -1.25, empty
    /// velocity and effort.
    const GOLDEN_LE: &[u8] = &[
        0x00, 0x01, 0x00, 0x00, // encapsulation CDR_LE
        0x07, 0x00, 0x00, 0x00, // sec = 7
        0xf4, 0x01, 0x00, 0x00, // nanosec = 500
        0x02, 0x00, 0x00, 0x00, b'b', 0x00, // frame_id "b" (len 2 with NUL)
        0x00, 0x00, // pad to 4
        0x02, 0x00, 0x00, 0x00, // 2 names
        0x03, 0x00, 0x00, 0x00, b'j', b'1', 0x00, // "j1"
        0x00, // pad
        0x04, 0x00, 0x00, 0x00, b'a', b'r', b'm', 0x00, // "arm"
        0x02, 0x00, 0x00, 0x00, // 2 positions; the doubles start at offset 40: aligned
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, // 0.5
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xf4, 0xbf, // -1.25
        0x00, 0x00, 0x00, 0x00, // velocity: 0
        0x00, 0x00, 0x00, 0x00, // effort: 0
    ];

    /// The same message big endian.
    const GOLDEN_BE: &[u8] = &[
        0x00, 0x00, 0x00, 0x00, // encapsulation CDR_BE
        0x00, 0x00, 0x00, 0x07, // sec
        0x00, 0x00, 0x01, 0xf4, // nanosec
        0x00, 0x00, 0x00, 0x02, b'b', 0x00, 0x00, 0x00, // frame_id + pad
        0x00, 0x00, 0x00, 0x02, // 2 names
        0x00, 0x00, 0x00, 0x03, b'j', b'1', 0x00, 0x00, // "j1" + pad
        0x00, 0x00, 0x00, 0x04, b'a', b'r', b'm', 0x00, // "arm"
        0x00, 0x00, 0x00, 0x02, // 2 positions
        0x3f, 0xe0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // 0.5
        0xbf, 0xf4, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // -1.25
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // velocity, effort
    ];

    /// One name of 7 characters: the position count ends 4 bytes past an 8-byte boundary, so
    /// 4 bytes of padding come before the double.
    const GOLDEN_PADDED: &[u8] = &[
        0x00, 0x01, 0x00, 0x00, // CDR_LE
        0x07, 0x00, 0x00, 0x00, 0xf4, 0x01, 0x00, 0x00, // stamp
        0x02, 0x00, 0x00, 0x00, b'b', 0x00, 0x00, 0x00, // frame_id + pad
        0x01, 0x00, 0x00, 0x00, // 1 name
        0x08, 0x00, 0x00, 0x00, b'a', b'b', b'c', b'd', b'e', b'f', b'g', 0x00, // "abcdefg"
        0x01, 0x00, 0x00, 0x00, // 1 position, ends at offset 36
        0x00, 0x00, 0x00, 0x00, // pad to 40
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xe0, 0x3f, // 0.5
        0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, // velocity, effort
    ];

    #[test]
    fn golden_padding_before_the_doubles() {
        let m = JointState {
            names: vec!["abcdefg".into()],
            position: vec![0.5],
            ..expected()
        };
        assert_eq!(decode_joint_state(GOLDEN_PADDED).unwrap(), m);
        assert_eq!(encode_joint_state(&m), GOLDEN_PADDED);
    }

    fn expected() -> JointState {
        JointState {
            sec: 7,
            nanosec: 500,
            frame_id: "b".into(),
            names: vec!["j1".into(), "arm".into()],
            position: vec![0.5, -1.25],
        }
    }

    #[test]
    fn golden_little_endian() {
        assert_eq!(decode_joint_state(GOLDEN_LE).unwrap(), expected());
    }

    #[test]
    fn golden_big_endian() {
        assert_eq!(decode_joint_state(GOLDEN_BE).unwrap(), expected());
    }

    #[test]
    fn encoder_writes_the_golden_bytes() {
        assert_eq!(encode_joint_state(&expected()), GOLDEN_LE);
    }

    #[test]
    fn stamp_in_nanoseconds() {
        assert_eq!(expected().stamp_ns(), 7_000_000_500);
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        // Velocity and effort are not read: the message is complete after the positions.
        let complete = GOLDEN_LE.len() - 8;
        for n in 0..complete {
            assert!(decode_joint_state(&GOLDEN_LE[..n]).is_err(), "{n} bytes");
        }
        for n in complete..=GOLDEN_LE.len() {
            assert_eq!(decode_joint_state(&GOLDEN_LE[..n]).unwrap(), expected());
        }
    }

    #[test]
    fn huge_counts_are_refused_before_allocating() {
        let mut m = GOLDEN_LE.to_vec();
        m[20..24].copy_from_slice(&u32::MAX.to_le_bytes()); // name count
        assert!(matches!(
            decode_joint_state(&m),
            Err(CdrError::Short { field: "name", .. })
        ));
        let mut m = GOLDEN_LE.to_vec();
        m[40..44].copy_from_slice(&0x1000_0000u32.to_le_bytes()); // position count
        assert!(matches!(
            decode_joint_state(&m),
            Err(CdrError::Short {
                field: "position",
                ..
            })
        ));
        let mut m = GOLDEN_LE.to_vec();
        m[12..16].copy_from_slice(&u32::MAX.to_le_bytes()); // frame_id length
        assert!(decode_joint_state(&m).is_err());
    }

    #[test]
    fn bad_encapsulation_string_and_stamp() {
        let mut m = GOLDEN_LE.to_vec();
        m[1] = 0x02; // PL_CDR_BE
        assert_eq!(decode_joint_state(&m), Err(CdrError::Encapsulation(2)));
        let mut m = GOLDEN_LE.to_vec();
        m[17] = b'x'; // frame_id without its NUL
        assert_eq!(
            decode_joint_state(&m),
            Err(CdrError::BadString {
                field: "header.frame_id"
            })
        );
        let mut m = GOLDEN_LE.to_vec();
        m[8..12].copy_from_slice(&1_000_000_000u32.to_le_bytes());
        assert_eq!(
            decode_joint_state(&m),
            Err(CdrError::Nanosec(1_000_000_000))
        );
    }

    #[test]
    fn every_single_byte_change_decodes_or_errs() {
        for i in 0..GOLDEN_LE.len() {
            for v in [0x00, 0x7f, 0x80, 0xff] {
                let mut m = GOLDEN_LE.to_vec();
                m[i] = v;
                let _ = decode_joint_state(&m);
            }
        }
    }
}
