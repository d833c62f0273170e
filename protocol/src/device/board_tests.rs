//! Unit tests of [`Board`]: the command state machine, counters and queue policy.

use super::*;
use crate::frame::{encode_host, Decoded, DeviceDecoder, HOST_FRAME_MAX};
use crate::messages::{CommandKind, DeviceMsg, HostMsg, NackReason, TiltReading};
use crate::schema::SCHEMA_HASH;

extern crate std;
use std::vec::Vec;

const INFO: BoardInfo = BoardInfo {
    firmware_version: [1, 2, 3],
    board_id: [7; 12],
    tilt_sensors: 3,
};

/// Drains the board's queue through a real decoder; fails on any corrupt frame.
fn drain(board: &mut Board, rx: &mut DeviceDecoder) -> Vec<DeviceMsg> {
    let mut out = Vec::new();
    let mut chunk = [0u8; 61]; // odd size: frames straddle chunks
    loop {
        let n = board.tx_pop_into(&mut chunk);
        if n == 0 {
            return out;
        }
        for event in rx.feed(&chunk[..n]) {
            match event {
                Decoded::Frame(msg) => out.push(msg),
                Decoded::CorruptFrame { reason } => {
                    panic!("board sent a corrupt frame: {reason:?}")
                }
            }
        }
    }
}

fn start(pot_rate_hz: u32, tilt_rate_hz: u32) -> HostMsg {
    HostMsg::Start {
        pot_rate_hz,
        tilt_rate_hz,
    }
}

#[test]
fn boot_sends_hello_with_schema_hash() {
    let mut board = Board::new(INFO);
    let mut rx = DeviceDecoder::new();
    board.boot(0);
    let msgs = drain(&mut board, &mut rx);
    assert_eq!(msgs.len(), 1);
    let DeviceMsg::Hello(hello) = &msgs[0] else {
        panic!("expected Hello, got {msgs:?}");
    };
    assert_eq!(hello.schema_hash, SCHEMA_HASH);
    assert_eq!(hello.protocol_version, crate::PROTOCOL_VERSION);
    assert_eq!(hello.firmware_version, [1, 2, 3]);
    assert_eq!(hello.tilt_sensors, 3);
    assert_eq!(crate::check_hello(hello), Ok(()));
}

#[test]
fn command_state_machine() {
    let mut board = Board::new(INFO);
    let mut rx = DeviceDecoder::new();

    assert_eq!(board.handle_command(0, HostMsg::Stop), Action::None);
    assert_eq!(board.handle_command(0, start(99, 10)), Action::None);
    assert_eq!(board.handle_command(0, start(1000, 1001)), Action::None);
    assert!(!board.is_running());
    let cfg = RunConfig::new(1000, 10).unwrap();
    assert_eq!(
        board.handle_command(0, start(1000, 10)),
        Action::StartSampling(cfg)
    );
    assert_eq!(board.handle_command(1, start(2000, 10)), Action::None);
    assert_eq!(board.run_config(), Some(cfg));
    assert_eq!(
        board.handle_command(2, HostMsg::Ping { nonce: 0xDEAD }),
        Action::None
    );
    assert_eq!(board.handle_command(3, HostMsg::GetInfo), Action::None);
    assert_eq!(board.handle_command(4, HostMsg::Stop), Action::StopSampling);

    let msgs = drain(&mut board, &mut rx);
    let expected_prefix = [
        DeviceMsg::Nack {
            command: CommandKind::Stop,
            reason: NackReason::NotRunning,
        },
        DeviceMsg::Nack {
            command: CommandKind::Start,
            reason: NackReason::RateOutOfRange,
        },
        DeviceMsg::Nack {
            command: CommandKind::Start,
            reason: NackReason::RateOutOfRange,
        },
        DeviceMsg::Ack(CommandKind::Start),
        DeviceMsg::Nack {
            command: CommandKind::Start,
            reason: NackReason::AlreadyRunning,
        },
        DeviceMsg::Pong { nonce: 0xDEAD },
        DeviceMsg::Hello(board.hello()),
    ];
    assert_eq!(&msgs[..7], &expected_prefix[..]);
    // Stop with no samples: no batch, then Status, then Ack(Stop) last.
    assert!(matches!(msgs[7], DeviceMsg::Status(s) if s.uptime_us == 4));
    assert_eq!(msgs[8], DeviceMsg::Ack(CommandKind::Stop));
    assert_eq!(msgs.len(), 9);
}

#[test]
fn a_drained_run_loses_nothing_and_ends_with_ack() {
    let mut board = Board::new(INFO);
    let mut rx = DeviceDecoder::new();
    board.handle_command(0, start(1000, 10));
    let mut msgs = Vec::new();
    let mut next_sample = 0u64;
    let mut tilt_reads = 0;
    // 1.5 s, stepped in 100 us like a busy firmware loop, draining every ms.
    for t in (0..1_500_000u64).step_by(100) {
        if t >= next_sample {
            board.on_pot_sample(t, (t / 1000) as u16);
            next_sample += 1000;
        }
        if let Some(sensor) = board.tilt_due(t) {
            tilt_reads += 1;
            board.on_tilt_reading(TiltReading {
                sensor,
                t_us: t,
                x: 1,
                y: 2,
                z: 6000,
                temp: 5000,
                status: 0,
            });
        }
        board.poll(t);
        if t % 1000 == 0 {
            msgs.extend(drain(&mut board, &mut rx));
        }
    }
    board.handle_command(1_500_000, HostMsg::Stop);
    msgs.extend(drain(&mut board, &mut rx));

    let batches: Vec<_> = msgs
        .iter()
        .filter_map(|m| match m {
            DeviceMsg::Pot(b) => Some(b),
            _ => None,
        })
        .collect();
    let samples: usize = batches.iter().map(|b| b.samples.len()).sum();
    assert_eq!(samples, 1500);
    for (k, b) in batches.iter().enumerate() {
        assert_eq!(b.seq, k as u32);
        assert_eq!(b.period_us, 1000);
        assert_eq!(
            b.samples[0] as u64,
            b.t0_us / 1000,
            "t0 matches first sample"
        );
    }
    // 10 Hz x 3 sensors for 1.5 s = 45 reads, each sensor 15 times.
    assert_eq!(tilt_reads, 45);
    let tilts = msgs
        .iter()
        .filter(|m| matches!(m, DeviceMsg::Tilt(_)))
        .count();
    assert_eq!(tilts, 45);
    let statuses: Vec<_> = msgs
        .iter()
        .filter_map(|m| match m {
            DeviceMsg::Status(s) => Some(*s),
            _ => None,
        })
        .collect();
    assert_eq!(statuses.len(), 2, "one periodic at 1 s, one at Stop");
    assert_eq!(statuses[0].uptime_us, 1_000_000);
    assert_eq!(statuses[1].dropped_frames, 0);
    assert_eq!(statuses[1].overruns, 0);
    assert_eq!(msgs.last(), Some(&DeviceMsg::Ack(CommandKind::Stop)));
}

#[test]
fn busy_link_drops_whole_frames_counts_them_and_still_answers() {
    let mut board = Board::new(INFO);
    let mut rx = DeviceDecoder::new();
    board.handle_command(0, start(10_000, 1));
    let _ = drain(&mut board, &mut rx);
    // 1 s at 10 kHz with the link stalled: never drained.
    let n = 10_000u64;
    for i in 0..n {
        board.on_pot_sample(i * 100, 2048);
    }
    let status = board.status(n * 100);
    assert!(status.dropped_frames > 0);
    assert_eq!(status.dropped_samples as usize % crate::POT_BATCH_MAX, 0);
    assert!(board.tx_len() <= TX_QUEUE_BYTES - CONTROL_RESERVE);
    // Replies still get through the reserve.
    board.handle_command(n * 100, HostMsg::Stop);
    let msgs = drain(&mut board, &mut rx);
    assert_eq!(msgs.last(), Some(&DeviceMsg::Ack(CommandKind::Stop)));
    let DeviceMsg::Status(final_status) = msgs[msgs.len() - 2] else {
        panic!("Status must precede Ack(Stop)");
    };
    // Every sample is accounted for: received + dropped (+ 0 pending after Stop).
    let mut received = 0usize;
    let mut seqs = Vec::new();
    for m in &msgs {
        if let DeviceMsg::Pot(b) = m {
            received += b.samples.len();
            seqs.push(b.seq);
        }
    }
    assert_eq!(received + final_status.dropped_samples as usize, n as usize);
    // seq gaps: the batches that were dropped (all full ones).
    let last_seq = *seqs.last().unwrap();
    let dropped_batches = last_seq as usize + 1 - seqs.len();
    assert_eq!(dropped_batches, final_status.dropped_frames as usize);
    assert_eq!(
        final_status.dropped_samples as usize,
        dropped_batches * crate::POT_BATCH_MAX
    );
}

#[test]
fn receive_decodes_commands_counts_rx_errors_and_reports_net_action() {
    let mut board = Board::new(INFO);
    let mut rx = DeviceDecoder::new();
    let mut wire = Vec::new();
    let mut buf = [0u8; HOST_FRAME_MAX];
    wire.extend_from_slice(&[0x13, 0x37, 0x00]); // garbage frame
    wire.extend_from_slice(encode_host(&start(500, 50), &mut buf).unwrap());
    assert_eq!(
        board.receive(0, &wire),
        Action::StartSampling(RunConfig::new(500, 50).unwrap())
    );
    // Start zeroed the counters, so the garbage before it no longer shows.
    assert_eq!(board.status(0).rx_errors, 0);
    let mut corrupted: Vec<u8> = encode_host(&HostMsg::Ping { nonce: 1 }, &mut buf)
        .unwrap()
        .to_vec();
    corrupted[2] ^= 0x40;
    assert_eq!(board.receive(1, &corrupted), Action::None);
    assert_eq!(board.status(1).rx_errors, 1);

    // Stop + Start in one chunk with other rates: a restart.
    let mut wire = Vec::new();
    wire.extend_from_slice(encode_host(&HostMsg::Stop, &mut buf).unwrap());
    wire.extend_from_slice(encode_host(&start(200, 20), &mut buf).unwrap());
    assert_eq!(
        board.receive(2, &wire),
        Action::StartSampling(RunConfig::new(200, 20).unwrap())
    );
    // Stop + Start with the same rates: the sampling hardware has nothing to change.
    let mut wire = Vec::new();
    wire.extend_from_slice(encode_host(&HostMsg::Stop, &mut buf).unwrap());
    wire.extend_from_slice(encode_host(&start(200, 20), &mut buf).unwrap());
    assert_eq!(board.receive(3, &wire), Action::None);
    assert_eq!(
        board.receive(4, encode_host(&HostMsg::Stop, &mut buf).unwrap()),
        Action::StopSampling
    );
    let msgs = drain(&mut board, &mut rx);
    let acks = msgs
        .iter()
        .filter(|m| matches!(m, DeviceMsg::Ack(_)))
        .count();
    assert_eq!(acks, 6);
}

#[test]
fn idle_board_ignores_data_and_has_no_deadline() {
    let mut board = Board::new(INFO);
    board.on_pot_sample(0, 1);
    board.on_tilt_reading(TiltReading {
        sensor: 0,
        t_us: 0,
        x: 0,
        y: 0,
        z: 0,
        temp: 0,
        status: 0,
    });
    board.poll(10_000_000);
    assert_eq!(board.tilt_due(10_000_000), None);
    assert_eq!(board.next_deadline_us(), None);
    assert_eq!(board.tx_len(), 0);
}

#[test]
fn late_tilt_polls_count_as_overruns_and_deadlines_track_work() {
    let mut board = Board::new(INFO);
    board.handle_command(0, start(100, 100)); // 300 tilt slots/s
    assert_eq!(board.next_deadline_us(), Some(0));
    assert_eq!(board.tilt_due(0), Some(0));
    assert_eq!(board.next_deadline_us(), Some(3334));
    // Poll 10 ms late: slots 1..=3 passed, slot 3 is served, 2 are skipped.
    assert_eq!(board.tilt_due(10_000), Some(0));
    assert_eq!(board.status(10_000).overruns, 2);
    board.on_overrun();
    board.on_sensor_error();
    let s = board.status(10_000);
    assert_eq!((s.overruns, s.sensor_errors), (3, 1));
    // An open pot batch brings the deadline to its latency limit.
    board.on_pot_sample(20_000, 5);
    assert!(board.next_deadline_us().unwrap() <= 20_000 + POT_MAX_LATENCY_US);
}

#[test]
fn low_rate_batches_are_flushed_by_latency() {
    let mut board = Board::new(INFO);
    let mut rx = DeviceDecoder::new();
    board.handle_command(0, start(100, 1));
    let _ = drain(&mut board, &mut rx);
    for i in 0..30u64 {
        let t = i * 10_000;
        board.on_pot_sample(t, i as u16);
        board.poll(t);
    }
    let msgs = drain(&mut board, &mut rx);
    let sizes: Vec<usize> = msgs
        .iter()
        .filter_map(|m| match m {
            DeviceMsg::Pot(b) => Some(b.samples.len()),
            _ => None,
        })
        .collect();
    // 100 Hz with a 100 ms latency bound: 11 samples (0..=100 ms) per batch.
    assert_eq!(sizes, [11, 11]);
}
