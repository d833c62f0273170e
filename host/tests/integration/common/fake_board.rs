//! A scripted board on a real pseudo-terminal, served by a thread of the test: it answers
//! `GetInfo` with its `Hello`, `Start` with `Ack(Start)` (or never), `Stop` with `Ack(Stop)`,
//! and while started writes what its script gives every 10 ms tick.

use std::path::PathBuf;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use rig_protocol::{
    encode_device, CommandKind, Decoded, DeviceMsg, Hello, HostDecoder, HostMsg, PotBatch,
    DEVICE_FRAME_MAX,
};
use rigctl::daq::pty::{MasterEvent, Pty};

/// The bytes to write at tick `k` (from 0 after `Start`).
pub type Script = Box<dyn FnMut(u64) -> Vec<u8> + Send>;

/// A board speaking this build's protocol, with three inclinometers.
pub fn hello() -> Hello {
    Hello {
        protocol_version: rig_protocol::PROTOCOL_VERSION,
        firmware_version: [1, 0, 0],
        board_id: [7; 12],
        schema_hash: rig_protocol::SCHEMA_HASH,
        tilt_sensors: 3,
    }
}

/// `msg` as a frame on the wire.
pub fn frame(msg: &DeviceMsg) -> Vec<u8> {
    let mut buf = [0u8; DEVICE_FRAME_MAX];
    encode_device(msg, &mut buf)
        .expect("a test frame encodes")
        .to_vec()
}

/// Potentiometer batch `seq` of a 1 kHz run: 20 samples from `20 ms x seq`.
pub fn batch(seq: u32) -> DeviceMsg {
    batch_at(seq, u64::from(seq) * 20_000, 1000, &[2048; 20])
}

/// A potentiometer batch with every field given.
pub fn batch_at(seq: u32, t0_us: u64, period_us: u32, samples: &[u16]) -> DeviceMsg {
    DeviceMsg::Pot(PotBatch {
        seq,
        t0_us,
        period_us,
        samples: heapless::Vec::from_slice(samples).expect("at most a batch"),
    })
}

/// Good batches, one per tick.
pub fn good_stream() -> Script {
    Box::new(|k| frame(&batch(k as u32)))
}

/// Serves the board; returns the port (the slave's path) and the thread. `ack_start`: whether
/// `Start` is acknowledged. The thread ends when the host hangs up or after 20 s.
pub fn spawn(ack_start: bool, mut script: Script) -> (PathBuf, JoinHandle<()>) {
    let mut pty = Pty::open().expect("a pseudo-terminal");
    let path = pty.slave_path().to_path_buf();
    let handle = std::thread::spawn(move || {
        let mut decoder = HostDecoder::new();
        let mut buf = [0u8; 512];
        let mut connected = false;
        let mut tick: Option<u64> = None;
        let end = Instant::now() + Duration::from_secs(20);
        let send = |pty: &mut Pty, bytes: &[u8]| {
            let mut rest = bytes;
            let give_up = Instant::now() + Duration::from_secs(2);
            while !rest.is_empty() && Instant::now() < give_up {
                match pty.write(rest) {
                    Ok(n) => rest = &rest[n..],
                    Err(_) => return,
                }
            }
        };
        while Instant::now() < end {
            match pty.wait(Duration::from_millis(10)) {
                Ok(MasterEvent::Readable) => {
                    let Ok(Some(n)) = pty.read(&mut buf) else {
                        return;
                    };
                    if n > 0 && !connected {
                        connected = true;
                        pty.release_slave();
                    }
                    let mut msgs = Vec::new();
                    decoder.push_slice(&buf[..n], |d| {
                        if let Decoded::Frame(m) = d {
                            msgs.push(m);
                        }
                    });
                    for m in msgs {
                        match m {
                            HostMsg::GetInfo => {
                                send(&mut pty, &frame(&DeviceMsg::Hello(hello())));
                            }
                            HostMsg::Start { .. } if ack_start => {
                                send(&mut pty, &frame(&DeviceMsg::Ack(CommandKind::Start)));
                                tick = Some(0);
                            }
                            HostMsg::Stop => {
                                tick = None;
                                send(&mut pty, &frame(&DeviceMsg::Ack(CommandKind::Stop)));
                            }
                            _ => {}
                        }
                    }
                }
                Ok(MasterEvent::HungUp) if connected => return,
                Ok(_) => {}
                Err(_) => return,
            }
            if let Some(k) = tick.as_mut() {
                let bytes = script(*k);
                send(&mut pty, &bytes);
                *k += 1;
            }
        }
    });
    (path, handle)
}
