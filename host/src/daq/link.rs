//! The host's end of the link: opening the serial port, and cutting the received byte stream
//! into frames while keeping each good frame's raw bytes (what a recording stores).

use rig_protocol::{CorruptReason, Decoded, DeviceDecoder, DeviceMsg, DELIMITER, DEVICE_FRAME_MAX};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Baud rate asked for when opening the port. The board is a USB CDC device (and the virtual
/// board a pseudo-terminal), where the rate is ignored; a real UART would use it.
pub const BAUD_RATE: u32 = 115_200;

/// What can go wrong opening the port.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    #[error("cannot open serial port {path}: {source}")]
    Open {
        path: PathBuf,
        #[source]
        source: serialport::Error,
    },
    #[error("cannot list serial ports: {0}")]
    List(#[source] serialport::Error),
}

impl crate::error::Classify for LinkError {
    fn kind(&self) -> crate::error::ErrorKind {
        match self {
            // A port that does not exist is a wrong argument.
            Self::Open { source, .. } if source.kind() == serialport::ErrorKind::NoDevice => {
                crate::error::ErrorKind::BadInput
            }
            Self::Open { source, .. }
                if matches!(
                    source.kind(),
                    serialport::ErrorKind::Io(std::io::ErrorKind::NotFound)
                ) =>
            {
                crate::error::ErrorKind::BadInput
            }
            _ => crate::error::ErrorKind::Failure,
        }
    }
}

/// Opens `path` (a serial device or a pseudo-terminal) in raw 8N1 mode, reads returning after
/// at most `read_timeout`, and discards whatever was waiting in its input buffer.
pub fn open_port(
    path: &Path,
    read_timeout: Duration,
) -> Result<Box<dyn serialport::SerialPort>, LinkError> {
    let name = path.to_string_lossy();
    let port = serialport::new(name.as_ref(), BAUD_RATE)
        .timeout(read_timeout)
        .open()
        .map_err(|source| LinkError::Open {
            path: path.to_path_buf(),
            source,
        })?;
    // Stale bytes from before we opened would only show up as one corrupt frame.
    let _ = port.clear(serialport::ClearBuffer::Input);
    Ok(port)
}

/// One serial port as `rigctl ports` shows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PortInfo {
    /// Path to pass to `--port`.
    pub path: String,
    /// "usb VID:PID manufacturer product serial", "pci", "bluetooth" or "unknown".
    pub description: String,
}

/// Lists the serial ports the OS knows (on Linux without libudev: from `/sys/class/tty`).
pub fn list_ports() -> Result<Vec<PortInfo>, LinkError> {
    let ports = serialport::available_ports().map_err(LinkError::List)?;
    Ok(ports
        .into_iter()
        .map(|p| PortInfo {
            path: p.port_name,
            description: describe(&p.port_type),
        })
        .collect())
}

fn describe(kind: &serialport::SerialPortType) -> String {
    match kind {
        serialport::SerialPortType::UsbPort(usb) => {
            let mut s = format!("usb {:04x}:{:04x}", usb.vid, usb.pid);
            for part in [&usb.manufacturer, &usb.product, &usb.serial_number]
                .into_iter()
                .flatten()
            {
                s.push(' ');
                s.push_str(part);
            }
            s
        }
        serialport::SerialPortType::PciPort => "pci".into(),
        serialport::SerialPortType::BluetoothPort => "bluetooth".into(),
        serialport::SerialPortType::Unknown => "unknown".into(),
    }
}

/// An event out of a [`FrameReader`].
#[derive(Debug, PartialEq)]
pub enum LinkEvent<'a> {
    /// A frame that passed every check, with its bytes as received (delimiter excluded).
    Frame { msg: DeviceMsg, raw: &'a [u8] },
    /// A frame that was thrown away.
    Corrupt(CorruptReason),
}

/// Host-side stream decoder: [`rig_protocol::DeviceDecoder`] plus the raw bytes of the frame in
/// flight, so a good frame can be stored exactly as it arrived.
#[derive(Debug, Default)]
pub struct FrameReader {
    decoder: DeviceDecoder,
    raw: Vec<u8>,
    /// The decoder condemned the frame in flight as overlong; ignore bytes to the delimiter.
    skipping: bool,
}

impl FrameReader {
    /// A reader waiting for the first frame.
    pub fn new() -> Self {
        Self {
            decoder: DeviceDecoder::new(),
            raw: Vec::with_capacity(DEVICE_FRAME_MAX),
            skipping: false,
        }
    }

    /// Pushes received bytes; `on_event` sees each completed (or condemned) frame in order.
    pub fn push_slice(&mut self, bytes: &[u8], mut on_event: impl FnMut(LinkEvent<'_>)) {
        for &byte in bytes {
            let event = self.decoder.push(byte);
            if byte == DELIMITER {
                if let Some(event) = event {
                    on_event(match event {
                        Decoded::Frame(msg) => LinkEvent::Frame {
                            msg,
                            raw: &self.raw,
                        },
                        Decoded::CorruptFrame { reason } => LinkEvent::Corrupt(reason),
                    });
                }
                self.raw.clear();
                self.skipping = false;
                continue;
            }
            if let Some(Decoded::CorruptFrame { reason }) = event {
                // Only `Overlong` is reported before the delimiter.
                on_event(LinkEvent::Corrupt(reason));
                self.raw.clear();
                self.skipping = true;
            } else if !self.skipping {
                self.raw.push(byte);
            }
        }
    }

    /// The decoder's counters: `frames` decoded, `corrupt` thrown away (by reason).
    pub fn stats(&self) -> rig_protocol::DecoderStats {
        self.decoder.stats()
    }
}

/// Decodes one stored frame (bytes as received, no delimiter).
pub fn decode_stored(raw: &[u8]) -> Result<DeviceMsg, CorruptReason> {
    if raw.contains(&DELIMITER) {
        // A delimiter inside a stored frame: it cannot be one frame.
        return Err(CorruptReason::Cobs);
    }
    let mut decoder = DeviceDecoder::new();
    for &byte in raw {
        if let Some(Decoded::CorruptFrame { reason }) = decoder.push(byte) {
            return Err(reason);
        }
    }
    match decoder.push(DELIMITER) {
        Some(Decoded::Frame(msg)) => Ok(msg),
        Some(Decoded::CorruptFrame { reason }) => Err(reason),
        // An empty frame.
        None => Err(CorruptReason::Cobs),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig_protocol::{encode_device, PotBatch, Status};

    fn encoded(msg: &DeviceMsg) -> Vec<u8> {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        encode_device(msg, &mut buf).unwrap().to_vec()
    }

    fn messages() -> Vec<DeviceMsg> {
        let mut samples = heapless::Vec::new();
        for i in 0..40u16 {
            samples.push(i * 100).unwrap();
        }
        vec![
            DeviceMsg::Pong { nonce: 0 },
            DeviceMsg::Pot(PotBatch {
                seq: 3,
                t0_us: 1_000_000,
                period_us: 1000,
                samples,
            }),
            DeviceMsg::Status(Status::default()),
        ]
    }

    #[test]
    fn raw_bytes_are_the_frame_without_delimiter_and_decode_again() {
        let msgs = messages();
        let stream: Vec<u8> = msgs.iter().flat_map(encoded).collect();
        // Every split of the stream into two pushes gives the same events.
        for split in 0..stream.len() {
            let mut reader = FrameReader::new();
            let mut got = Vec::new();
            for part in [&stream[..split], &stream[split..]] {
                reader.push_slice(part, |e| match e {
                    LinkEvent::Frame { msg, raw } => got.push((msg, raw.to_vec())),
                    LinkEvent::Corrupt(r) => panic!("corrupt {r:?}"),
                });
            }
            assert_eq!(got.len(), 3);
            for ((msg, raw), expected) in got.iter().zip(&msgs) {
                assert_eq!(msg, expected);
                let mut frame = encoded(expected);
                frame.pop();
                assert_eq!(raw, &frame);
                assert_eq!(decode_stored(raw).as_ref(), Ok(expected));
            }
        }
    }

    #[test]
    fn a_flipped_byte_costs_exactly_its_frame() {
        let msgs = messages();
        let frames: Vec<Vec<u8>> = msgs.iter().map(encoded).collect();
        for victim in 0..frames.len() {
            for pos in 0..frames[victim].len() - 1 {
                let mut stream = Vec::new();
                for (i, f) in frames.iter().enumerate() {
                    let mut f = f.clone();
                    if i == victim {
                        // Any non-zero value other than the original (keeps the delimiters).
                        f[pos] = if f[pos] == 0x55 { 0xAA } else { 0x55 };
                    }
                    stream.extend_from_slice(&f);
                }
                let mut reader = FrameReader::new();
                let (mut good, mut bad) = (Vec::new(), 0);
                reader.push_slice(&stream, |e| match e {
                    LinkEvent::Frame { msg, .. } => good.push(msg),
                    LinkEvent::Corrupt(_) => bad += 1,
                });
                assert_eq!(bad, 1, "victim {victim} pos {pos}");
                let mut expected = msgs.clone();
                expected.remove(victim);
                assert_eq!(good, expected);
                assert_eq!(reader.stats().corrupt, 1);
            }
        }
    }

    #[test]
    fn overlong_garbage_is_one_corrupt_frame_then_resync() {
        let mut stream = vec![0x01; 3 * DEVICE_FRAME_MAX];
        stream.push(0);
        stream.extend(encoded(&DeviceMsg::Pong { nonce: 9 }));
        let mut reader = FrameReader::new();
        let mut events = Vec::new();
        reader.push_slice(&stream, |e| {
            events.push(match e {
                LinkEvent::Frame { msg, raw } => Ok((msg, raw.len())),
                LinkEvent::Corrupt(r) => Err(r),
            })
        });
        let pong_len = encoded(&DeviceMsg::Pong { nonce: 9 }).len() - 1;
        assert_eq!(
            events,
            vec![
                Err(CorruptReason::Overlong),
                Ok((DeviceMsg::Pong { nonce: 9 }, pong_len))
            ]
        );
    }

    #[test]
    fn decode_stored_rejects_damage() {
        let mut frame = encoded(&DeviceMsg::Pong { nonce: 1 });
        frame.pop();
        frame[2] ^= 0x10;
        assert!(decode_stored(&frame).is_err());
        assert!(decode_stored(&[]).is_err());
        assert!(decode_stored(&[0x01; 1000]).is_err());
        let mut with_zero = encoded(&DeviceMsg::Pong { nonce: 1 });
        with_zero.pop();
        with_zero[1] = 0;
        assert_eq!(decode_stored(&with_zero), Err(CorruptReason::Cobs));
    }
}
