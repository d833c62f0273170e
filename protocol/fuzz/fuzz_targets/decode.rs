//! Arbitrary bytes into both decoders, whole and split at a fuzzer-chosen point: must never
//! panic, the split and whole event streams must be equal, counters must add up, and
//! re-encoding any decoded message must decode to itself. No allocation per input (the two
//! event streams are compared in lockstep), so the fuzzer runs at full speed.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rig_protocol::{encode_device, encode_host, Decoded, DeviceDecoder, HostDecoder};
use rig_protocol::{DEVICE_FRAME_MAX, HOST_FRAME_MAX};

fn check_device(event: &Decoded<rig_protocol::DeviceMsg>) {
    if let Decoded::Frame(msg) = event {
        let mut buf = [0u8; DEVICE_FRAME_MAX];
        let frame = encode_device(msg, &mut buf).expect("decoded message re-encodes");
        let mut again = DeviceDecoder::new();
        assert_eq!(again.feed(frame).next().as_ref(), Some(event));
    }
}

fuzz_target!(|data: &[u8]| {
    let split = data.first().map_or(0, |&b| b as usize).min(data.len());

    let mut device = DeviceDecoder::new();
    let mut whole = DeviceDecoder::new();
    {
        let mut whole_events = whole.feed(data);
        for part in [&data[..split], &data[split..]] {
            for event in device.feed(part) {
                assert_eq!(whole_events.next().as_ref(), Some(&event));
                check_device(&event);
            }
        }
        assert!(whole_events.next().is_none());
    }
    let s = device.stats();
    assert_eq!(s.bytes, data.len() as u64);
    assert_eq!(
        s.corrupt,
        s.cobs_errors + s.crc_errors + s.postcard_errors + s.overlong
    );

    let mut host = HostDecoder::new();
    for event in host.feed(data) {
        if let Decoded::Frame(msg) = event {
            let mut buf = [0u8; HOST_FRAME_MAX];
            let frame = encode_host(&msg, &mut buf).expect("decoded message re-encodes");
            let mut again = HostDecoder::new();
            assert_eq!(again.feed(frame).next(), Some(Decoded::Frame(msg)));
        }
    }
});
