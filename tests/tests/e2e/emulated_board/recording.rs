//! One recording from the emulated board, `rigctl record` then `rigctl export`, checked against
//! the emulated sensors' known signal: every frame and sample accounted for, potentiometer
//! timestamps exact, inclinometer readings within one slot of theirs (skipped slots counted by
//! the board), the board's clock against the host's.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Output;

use rig_protocol::device::known_signal::{pot_raw, tilt_reading};
use rig_protocol::DeviceMsg;
use rig_tests::rigctl;

use super::{CLOCK_RATE_TOLERANCE, SAMPLE_COUNT_TOLERANCE, TILT_SKIPPED_MAX};

fn record(link: &Path, out: &Path, duration_s: u64, pot_hz: u32, tilt_hz: u32) -> Output {
    rigctl()
        .args(["record", "--port"])
        .arg(link)
        .arg("--out")
        .arg(out)
        .args([
            "--duration",
            &duration_s.to_string(),
            "--pot-hz",
            &pot_hz.to_string(),
            "--tilt-hz",
            &tilt_hz.to_string(),
        ])
        .output()
        .expect("run rigctl record")
}

/// `frames, samples, dropped, crc_errors` from record's summary line.
fn summary(stdout: &[u8]) -> [u64; 4] {
    let text = String::from_utf8_lossy(stdout);
    let line = text.lines().last().expect("record printed nothing");
    let names = ["frames", "samples", "dropped", "crc_errors"];
    let mut values = [0u64; 4];
    for (value, name) in values.iter_mut().zip(names) {
        *value = line
            .split(", ")
            .find_map(|part| part.strip_prefix(name)?.strip_prefix(' ')?.parse().ok())
            .unwrap_or_else(|| panic!("no `{name} N` in {line:?}"));
    }
    values
}

fn csv_rows(path: &Path, header: &str) -> Vec<Vec<i64>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    lines
        .map(|l| {
            l.split(',')
                .map(|f| f.parse().unwrap_or_else(|e| panic!("{l:?}: {e}")))
                .collect()
        })
        .collect()
}

/// What one recording showed.
pub(super) struct RunCheck {
    pub(super) frames: u64,
    pub(super) pot_samples: usize,
    pub(super) tilt_readings: usize,
    /// Tilt read lateness after its slot (relative to the earliest), microseconds: median,
    /// 99th percentile, largest.
    pub(super) tilt_late_us: [i64; 3],
    /// Tilt slots skipped (and counted by the board as overruns).
    pub(super) tilt_skipped: u64,
    /// Board clock rate against the host clock.
    pub(super) clock_rate: f64,
}

/// Records `duration_s` at the given rates and checks everything the recording can show.
pub(super) fn record_and_check(
    link: &Path,
    dir: &Path,
    name: &str,
    duration_s: u64,
    pot_hz: u32,
    tilt_hz: u32,
) -> RunCheck {
    let rec = dir.join(format!("{name}.rigrec"));
    let out = record(link, &rec, duration_s, pot_hz, tilt_hz);
    assert!(
        out.status.success(),
        "record {name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let [frames, samples, dropped, crc_errors] = summary(&out.stdout);
    assert_eq!(crc_errors, 0, "record {name}: corrupt frames");

    // The recording itself: the emulated board's Hello, the run's acknowledgements.
    let recording = rigctl::daq::recording::read_recording(&rec).expect("read the recording");
    assert_eq!(recording.truncated_tail_bytes, 0);
    let msgs: Vec<DeviceMsg> = recording
        .records
        .iter()
        .map(|r| rigctl::daq::link::decode_stored(&r.frame).expect("stored frame decodes"))
        .collect();
    assert_eq!(msgs.len() as u64, frames);
    let hello = msgs
        .iter()
        .find_map(|m| match m {
            DeviceMsg::Hello(h) => Some(*h),
            _ => None,
        })
        .expect("a Hello");
    assert_eq!(&hello.board_id, b"QEMU-AN386\0\0");
    assert_eq!(hello.tilt_sensors, 3);
    assert!(
        msgs.contains(&DeviceMsg::Ack(rig_protocol::CommandKind::Start)),
        "Start acknowledged"
    );
    assert_eq!(
        msgs.last(),
        Some(&DeviceMsg::Ack(rig_protocol::CommandKind::Stop)),
        "the run ends with Ack(Stop)"
    );
    let mut seqs = msgs.iter().filter_map(|m| match m {
        DeviceMsg::Pot(b) => Some((b.seq, b.period_us)),
        _ => None,
    });
    let period_us = 1_000_000 / pot_hz;
    for (expected, (seq, period)) in (0u32..).zip(seqs.by_ref()) {
        assert_eq!(seq, expected, "{name}: pot batches in sequence from 0");
        assert_eq!(period, period_us, "{name}: the commanded pot period");
    }

    let csv = dir.join(format!("{name}-csv"));
    let export = rigctl()
        .arg("export")
        .arg(&rec)
        .arg("--csv")
        .arg(&csv)
        .output()
        .expect("run rigctl export");
    assert!(
        export.status.success(),
        "export {name}: {}",
        String::from_utf8_lossy(&export.stderr)
    );

    // Every potentiometer sample: on the commanded grid without a gap, equal to the ramp.
    let pot = csv_rows(&csv.join("pot.csv"), "seq,t_us,raw");
    assert_eq!(pot.len() as u64, samples);
    for pair in pot.windows(2) {
        assert_eq!(
            pair[1][1] - pair[0][1],
            i64::from(period_us),
            "{name}: pot samples {:?} -> {:?}",
            pair[0],
            pair[1]
        );
    }
    for row in &pot {
        assert_eq!(
            row[2],
            i64::from(pot_raw(row[1] as u64)),
            "{name}: pot sample at {} us",
            row[1]
        );
    }
    let expected_samples = (duration_s * u64::from(pot_hz)) as f64;
    let ratio = pot.len() as f64 / expected_samples;
    assert!(
        (ratio - 1.0).abs() <= SAMPLE_COUNT_TOLERANCE,
        "{name}: {} pot samples in {duration_s} s at {pot_hz} Hz",
        pot.len()
    );

    // Every inclinometer reading: the table's row for its sensor and time; each sensor read
    // at the commanded rate, none skipped.
    let tilt = csv_rows(&csv.join("tilt.csv"), "sensor,t_us,x,y,z,temp");
    let mut by_sensor: BTreeMap<i64, Vec<i64>> = BTreeMap::new();
    for row in &tilt {
        let r = tilt_reading(row[0] as u8, row[1] as u64);
        assert_eq!(
            &row[2..],
            &[r.x, r.y, r.z, r.temp].map(i64::from),
            "{name}: sensor {} at {} us",
            row[0],
            row[1]
        );
        by_sensor.entry(row[0]).or_default().push(row[1]);
    }
    assert_eq!(
        by_sensor.keys().copied().collect::<Vec<_>>(),
        [0, 1, 2],
        "{name}: all three sensors read"
    );
    // The board's schedule (`rig_protocol::device::TiltScheduler`): read slot `k` is for
    // sensor `k % 3` at `start + ceil(k * 1e6 / (rate * 3))`; the first read (sensor 0) is due
    // at `Start`, so its time stands for `start`. Each reading belongs to the nearest slot of
    // its sensor; it is at most one slot interval after it (`start` itself may be late).
    let sensors = by_sensor.len() as i64;
    let slots_per_s = i64::from(tilt_hz) * sensors;
    let slot_us = |k: i64| (k * 1_000_000 + slots_per_s - 1) / slots_per_s;
    let start = by_sensor[&0][0];
    let mut lateness = Vec::with_capacity(tilt.len());
    let mut skipped = 0u64;
    for (&sensor, times) in &by_sensor {
        let mut last_k: Option<i64> = None;
        let mut sensor_skipped = 0u64;
        for &t in times {
            let approx = ((t - start) * slots_per_s) as f64 / 1e6;
            let k = ((approx - sensor as f64) / sensors as f64).round() as i64 * sensors + sensor;
            let late = t - start - slot_us(k);
            assert!(
                late * slots_per_s <= 1_000_000,
                "{name}: sensor {sensor} read at {t} us, {late} us after its slot {k}"
            );
            lateness.push(late);
            if let Some(prev) = last_k {
                assert!(k > prev, "{name}: sensor {sensor} read twice in slot {k}");
                sensor_skipped += ((k - prev) / sensors - 1) as u64;
            } else {
                assert_eq!(
                    k, sensor,
                    "{name}: sensor {sensor}'s first read is in its first slot"
                );
            }
            last_k = Some(k);
        }
        skipped += sensor_skipped;
        // Its slots (read or skipped) at the commanded rate over the run.
        let expected = (duration_s * u64::from(tilt_hz)) as f64;
        let ratio = (times.len() as u64 + sensor_skipped) as f64 / expected;
        assert!(
            (ratio - 1.0).abs() <= SAMPLE_COUNT_TOLERANCE,
            "{name}: sensor {sensor}: {} readings and {sensor_skipped} skipped slots in \
             {duration_s} s at {tilt_hz} Hz",
            times.len()
        );
    }
    let earliest = lateness.iter().copied().min().unwrap_or(0);
    let mut lateness: Vec<i64> = lateness.iter().map(|l| l - earliest).collect();
    lateness.sort_unstable();
    let pick = |q: f64| lateness[((lateness.len() - 1) as f64 * q) as usize];
    let tilt_late_us = [pick(0.5), pick(0.99), pick(1.0)];
    let slots = tilt.len() as u64 + skipped;
    assert!(
        skipped as f64 <= TILT_SKIPPED_MAX * slots as f64,
        "{name}: {skipped} of {slots} tilt slots skipped (QEMU woke late; lateness p50/p99/max \
         {tilt_late_us:?} us)"
    );
    // Record's `dropped` is its estimate of the missing pot samples (none: checked above and
    // here) plus the tilt readings missing from each sensor's grid, which it takes as the
    // smallest interval seen: read jitter makes that grid finer than the slots, so it may
    // count a skipped slot twice, never miss one.
    let mut tally = rigctl::daq::tally::Tally::new();
    for msg in &msgs {
        tally.on_message(msg);
    }
    assert_eq!(tally.dropped(), dropped, "{name}: the recording's tally");
    assert_eq!(
        (tally.gap_samples, tally.gap_batches, tally.first_seq),
        (0, 0, Some(0)),
        "{name}: pot samples missing"
    );
    assert!(
        tally.tilt_gap_readings >= skipped && dropped == tally.tilt_gap_readings,
        "{name}: record's dropped {dropped} vs {skipped} skipped tilt slots"
    );

    // Health: the board's own counters; its clock against the host's.
    let status = csv_rows(
        &csv.join("status.csv"),
        "host_rx_us,uptime_us,dropped_samples,dropped_frames,overruns,sensor_errors,rx_errors",
    );
    assert!(
        status.len() as u64 >= duration_s,
        "{name}: a Status a second"
    );
    // dropped samples, dropped frames, sensor errors, rx errors: none; overruns: exactly the
    // skipped tilt slots (the last Status is the one sent at Stop).
    for row in &status {
        assert_eq!(
            [row[2], row[3], row[5], row[6]],
            [0, 0, 0, 0],
            "{name}: status {row:?}"
        );
    }
    assert_eq!(
        status[status.len() - 1][4] as u64,
        skipped,
        "{name}: the board counted every skipped tilt slot as an overrun"
    );
    let (first, last) = (&status[0], &status[status.len() - 1]);
    let clock_rate = (last[1] - first[1]) as f64 / (last[0] - first[0]) as f64;
    assert!(
        (clock_rate - 1.0).abs() <= CLOCK_RATE_TOLERANCE,
        "{name}: board clock runs at {clock_rate:.4} of the host's"
    );

    RunCheck {
        frames,
        pot_samples: pot.len(),
        tilt_readings: tilt.len(),
        tilt_late_us,
        tilt_skipped: skipped,
        clock_rate,
    }
}
