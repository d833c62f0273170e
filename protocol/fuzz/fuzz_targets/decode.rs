//! Arbitrary bytes into both decoders, whole and split at a fuzzer-chosen point: must never
//! panic, counters must add up, and re-encoding any decoded message must decode to itself.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rig_protocol::{encode_device, encode_host, Decoded, DeviceDecoder, HostDecoder};
use rig_protocol::{DEVICE_FRAME_MAX, HOST_FRAME_MAX};

fuzz_target!(|data: &[u8]| {
    let split = data.first().map_or(0, |&b| b as usize).min(data.len());

    let mut device = DeviceDecoder::new();
    let mut whole = DeviceDecoder::new();
    let mut events = Vec::new();
    events.extend(device.feed(&data[..split]));
    events.extend(device.feed(&data[split..]));
    let whole_events: Vec<_> = whole.feed(data).collect();
    assert_eq!(events, whole_events);
    let s = device.stats();
    assert_eq!(s.bytes, data.len() as u64);
    assert_eq!(
        s.corrupt,
        s.cobs_errors + s.crc_errors + s.postcard_errors + s.overlong
    );
    for event in events {
        if let Decoded::Frame(msg) = event {
            let mut buf = [0u8; DEVICE_FRAME_MAX];
            let frame = encode_device(&msg, &mut buf).expect("decoded message re-encodes");
            let mut again = DeviceDecoder::new();
            assert_eq!(again.feed(frame).next(), Some(Decoded::Frame(msg)));
        }
    }

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
