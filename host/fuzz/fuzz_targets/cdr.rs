//! Arbitrary bytes as a CDR `sensor_msgs/msg/JointState` (the messages of a ROS 2 bag): no
//! panic and no allocation beyond the input's size; what decodes re-encodes and decodes alike.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rigctl::io::cdr::{decode_joint_state, encode_joint_state};

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = decode_joint_state(data) {
        assert!(m.names.len() <= data.len() && m.position.len() <= data.len());
        let again = decode_joint_state(&encode_joint_state(&m)).expect("its own encoding decodes");
        assert_eq!(again.names, m.names);
        assert_eq!(again.position.len(), m.position.len());
    }
});
