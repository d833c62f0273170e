//! Unit tests of `board_sim.rs`.

use super::*;
use crate::daq::link::{FrameReader, LinkEvent};
use rig_protocol::{encode_host, CommandKind, DeviceMsg};

fn host_bytes(msg: HostMsg) -> Vec<u8> {
    let mut buf = [0u8; HOST_FRAME_MAX];
    encode_host(&msg, &mut buf).unwrap().to_vec()
}

fn drain(board: &mut VirtualBoard, reader: &mut FrameReader) -> Vec<DeviceMsg> {
    let mut out = Vec::new();
    let bytes = board.tx_peek().to_vec();
    board.tx_consume(bytes.len());
    reader.push_slice(&bytes, |e| match e {
        LinkEvent::Frame { msg, .. } => out.push(msg),
        LinkEvent::Corrupt(r) => panic!("corrupt {r:?}"),
    });
    out
}

/// Runs a board for `secs` of board time after `Start` at `start_us`, draining every 1 ms.
fn run(cfg: SimConfig, start_us: u64, secs: u64) -> (VirtualBoard, Vec<DeviceMsg>) {
    let mut board = VirtualBoard::new(cfg);
    let mut reader = FrameReader::new();
    board.advance_to(start_us);
    board.receive(&host_bytes(HostMsg::Start {
        pot_rate_hz: 1000,
        tilt_rate_hz: 100,
    }));
    let mut msgs = drain(&mut board, &mut reader);
    for ms in 1..=secs * 1000 {
        board.advance_to(start_us + ms * 1000);
        msgs.extend(drain(&mut board, &mut reader));
    }
    (board, msgs)
}

#[test]
fn samples_are_the_seeded_signals_on_an_exact_grid() {
    let cfg = SimConfig {
        seed: 11,
        ..SimConfig::default()
    };
    let (board, msgs) = run(cfg, 123_457, 2);
    assert!(matches!(msgs[0], DeviceMsg::Hello(_)));
    assert_eq!(msgs[1], DeviceMsg::Ack(CommandKind::Start));
    let mut next_t = 123_457u64;
    let mut tilt = [0u64; 3];
    for msg in &msgs {
        match msg {
            DeviceMsg::Pot(b) => {
                assert_eq!(b.t0_us, next_t);
                for (i, &raw) in b.samples.iter().enumerate() {
                    let t = b.t0_us + i as u64 * 1000;
                    assert_eq!(raw, signals::pot_raw(11, t));
                }
                next_t += 1000 * b.samples.len() as u64;
            }
            DeviceMsg::Tilt(r) => {
                let raw = signals::tilt_raw(11, r.sensor, r.t_us);
                assert_eq!((r.x, r.y, r.z, r.temp), (raw.x, raw.y, raw.z, raw.temp));
                tilt[usize::from(r.sensor)] += 1;
            }
            _ => {}
        }
    }
    // 2 s at 1 kHz: samples at start + 0..=2000 ms, the last batch still open.
    let (samples, readings, status) = board.counts();
    assert_eq!(samples, 2001);
    assert!(next_t > 123_457 + 1_900_000, "batches sent up to {next_t}");
    // 3 sensors at 100 Hz for 2 s: 200 reads each (+1 at the very end at most).
    for n in tilt {
        assert!((200..=201).contains(&n), "{tilt:?}");
    }
    assert_eq!(readings, tilt.iter().sum::<u64>());
    assert_eq!(status.dropped_samples, 0);
}

#[test]
fn duration_stops_the_run_with_status_and_ack() {
    let cfg = SimConfig {
        duration: Some(Duration::from_millis(500)),
        ..SimConfig::default()
    };
    let (board, msgs) = run(cfg, 0, 1);
    assert_eq!(board.ended(), Some(SimEnd::DurationElapsed));
    assert_eq!(msgs.last(), Some(&DeviceMsg::Ack(CommandKind::Stop)));
    assert!(matches!(msgs[msgs.len() - 2], DeviceMsg::Status(_)));
    let samples: usize = msgs
        .iter()
        .map(|m| match m {
            DeviceMsg::Pot(b) => b.samples.len(),
            _ => 0,
        })
        .sum();
    // Samples at 0, 1, ..., 500 ms.
    assert_eq!(samples, 501);
    assert_eq!(board.counts().0, 501);
}

#[test]
fn start_above_the_hardware_limit_is_refused() {
    let mut board = VirtualBoard::new(SimConfig::default());
    let mut reader = FrameReader::new();
    board.receive(&host_bytes(HostMsg::Start {
        pot_rate_hz: 2000,
        tilt_rate_hz: 100,
    }));
    let msgs = drain(&mut board, &mut reader);
    assert!(matches!(
        msgs.last(),
        Some(DeviceMsg::Nack {
            command: CommandKind::Start,
            reason: rig_protocol::NackReason::RateOutOfRange
        })
    ));
    assert!(!board.is_running());
}

#[test]
fn corruptor_never_touches_delimiters_and_counts_frames() {
    let mut c = Corruptor::new(200_000, 5);
    let frames: Vec<u8> = (0..1000)
        .flat_map(|i| {
            let mut f: Vec<u8> = (1..=20u8).map(|b| b.wrapping_add(i as u8) | 1).collect();
            f.push(0);
            f
        })
        .collect();
    let mut out = Vec::new();
    let mut pos = 0;
    while pos < frames.len() {
        // A link that takes at most 37 bytes at a time.
        let n = c
            .write::<()>(&frames[pos..], |b| {
                let n = b.len().min(37);
                out.extend_from_slice(&b[..n]);
                Ok(n)
            })
            .unwrap();
        pos += n;
    }
    assert_eq!(out.len(), frames.len());
    let r = c.report();
    assert_eq!(r.frames_sent, 1000);
    let mut hit_frames = 0;
    for (sent, orig) in out.chunks(21).zip(frames.chunks(21)) {
        assert_eq!(sent[20], 0);
        assert!(sent[..20].iter().all(|&b| b != 0));
        hit_frames += u64::from(sent != orig);
    }
    assert_eq!(r.frames_corrupted, hit_frames);
    let changed = out.iter().zip(&frames).filter(|(a, b)| a != b).count() as u64;
    assert_eq!(r.bytes_corrupted, changed);
    // 20 000 bytes at 20 %: 4000 +- 5 sigma (283).
    assert!((changed as i64 - 4000).abs() < 283, "{changed}");
}
