//! The joint-log arguments of the commands that read a robot's joint log (`fk --joints`,
//! `fuse --joints`): a CSV, or a ROS 2 bag (`.mcap` file or rosbag2 directory) with
//! `sensor_msgs/msg/JointState` on `--joint-topic`, the model's joints by name
//! (`--joint-names` or the model's names); `rigctl::io::rosbag` reads it.

use std::path::Path;

use rigctl::fusion::JointSamples;
use rigctl::io::rosbag::{
    is_bag, read_joint_log, BagError, BagSummary, JointLogSpec, JointReading, DEFAULT_JOINT_TOPIC,
};
use rigctl::model::Model;

use super::out::errln;
use super::CliError;

/// Where a bag's joints are.
#[derive(clap::Args, Debug, Clone)]
pub struct JointLogArgs {
    /// With a ROS 2 bag as the joint log: the topic of its sensor_msgs/msg/JointState messages.
    #[arg(long, value_name = "TOPIC", default_value = DEFAULT_JOINT_TOPIC)]
    pub joint_topic: String,
    /// With a ROS 2 bag: the names of the model's joints in the messages, in model order
    /// (default: the model's joint names, from urdf2model).
    #[arg(long, value_name = "N1,N2,...", value_delimiter = ',')]
    pub joint_names: Vec<String>,
}

impl JointLogArgs {
    /// Refuses the bag options with a CSV joint log (they would be silently unused).
    pub fn check_for(&self, path: &Path) -> Result<bool, CliError> {
        let bag = is_bag(path);
        if !bag && (!self.joint_names.is_empty() || self.joint_topic != DEFAULT_JOINT_TOPIC) {
            return Err(CliError::bad_input(format!(
                "{}: --joint-topic and --joint-names apply to a ROS 2 bag (.mcap file or rosbag2 \
                 directory), not to a CSV",
                path.display()
            )));
        }
        Ok(bag)
    }

    /// The joint names to take from the messages, in model order.
    pub fn names(&self, model: &Model) -> Result<Vec<String>, CliError> {
        let names = if self.joint_names.is_empty() {
            model.joint_names().to_vec()
        } else {
            self.joint_names.clone()
        };
        if names.is_empty() {
            return Err(CliError::bad_input(format!(
                "the model names no joints: give the {} joint names of the bag's messages with \
                 --joint-names N1,...",
                model.n_joints()
            )));
        }
        if names.len() != model.n_joints()
            || names
                .iter()
                .enumerate()
                .any(|(i, n)| names[..i].contains(n))
        {
            return Err(CliError::bad_input(format!(
                "--joint-names: {} different names needed (one per model joint), got {}",
                model.n_joints(),
                names.join(",")
            )));
        }
        Ok(names)
    }

    /// Reads the bag at `path` for `model`, handing each used message to `each` (joint limits
    /// checked); prints on stderr what was skipped or lost.
    pub fn read_bag(
        &self,
        path: &Path,
        model: &Model,
        mut each: impl FnMut(JointReading) -> Result<(), CliError>,
    ) -> Result<BagSummary, CliError> {
        let names = self.names(model)?;
        let prismatic: Vec<bool> = model.joints().iter().map(|j| j.prismatic).collect();
        let limits = model.joint_limits();
        let spec = JointLogSpec {
            topic: &self.joint_topic,
            names: &names,
            prismatic: &prismatic,
        };
        let summary = read_joint_log(path, &spec, |r: JointReading| {
            for (k, (v, [lo, hi])) in r.q.iter().zip(&limits).enumerate() {
                if !(lo <= v && v <= hi) {
                    // in the bag's own units (JointState: rad, m), the model's beside them
                    let (unit, file_unit, per) = if prismatic[k] {
                        ("mm", "m", 1e3)
                    } else {
                        ("deg", "rad", 180.0 / std::f64::consts::PI)
                    };
                    return Err(CliError::bad_input(format!(
                        "{}: message {} on `{}`: joint `{}` = {} {file_unit} is outside its \
                         limits [{}, {}] {file_unit} ({v} {unit}, limits [{lo}, {hi}] {unit})",
                        path.display(),
                        r.message,
                        self.joint_topic,
                        names[k],
                        v / per,
                        lo / per,
                        hi / per
                    )));
                }
            }
            each(r)
        })?;
        for line in summary.notes(path) {
            errln!("rigctl: joint log: {line}");
        }
        Ok(summary)
    }

    /// A bag as the fusion's joint samples (times strictly increasing); with `strict` a damaged
    /// bag is refused.
    pub fn read_samples(
        &self,
        path: &Path,
        model: &Model,
        strict: bool,
    ) -> Result<JointSamples, CliError> {
        let mut out = JointSamples::default();
        let summary = self.read_bag(path, model, |r| {
            if out.t_s.last().is_some_and(|&prev| r.t_s <= prev) {
                return Err(CliError::bad_input(format!(
                    "{}: message {} on `{}`: header stamp {} s after the first does not \
                     increase",
                    path.display(),
                    r.message,
                    self.joint_topic,
                    r.t_s
                )));
            }
            out.t_s.push(r.t_s);
            out.q_deg.push(r.q);
            Ok(())
        })?;
        let damage = summary.damage_notes(path);
        if strict && !damage.is_empty() {
            return Err(BagError::Damaged(damage).into());
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigctl::io::cdr::{encode_joint_state, JointState};
    use rigctl::model::{Axis, ModelBuilder, Motion};

    /// A one-joint model named `a` and a bag of 100 messages in CRC-checked chunks of ~2 kB,
    /// one byte of message 50 flipped (its chunk fails its CRC).
    fn damaged_bag(dir: &Path) -> (Model, std::path::PathBuf) {
        let mut b = ModelBuilder::new("one");
        b.constant(Motion::Trans, Axis::Z, "h", 100.0).unwrap();
        b.joint(false, "o1", 0.0, [-180.0, 180.0], None).unwrap();
        let mut model = b.build().unwrap();
        model.set_joint_names(vec!["a".into()]).unwrap();
        let mut buf = std::io::Cursor::new(Vec::new());
        let mut w = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(2000))
            .create(&mut buf)
            .unwrap();
        let schema = w
            .add_schema("sensor_msgs/msg/JointState", "ros2msg", b"")
            .unwrap();
        let ch = w
            .add_channel(schema, "/joint_states", "cdr", &Default::default())
            .unwrap();
        for k in 0..100u32 {
            let m = JointState {
                sec: 1,
                nanosec: k * 1_000_000,
                frame_id: String::new(),
                names: vec!["a".into()],
                position: vec![0.001 * f64::from(k)],
            };
            let h = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: k,
                log_time: u64::from(k),
                publish_time: u64::from(k),
            };
            w.write_to_known_channel(&h, &encode_joint_state(&m))
                .unwrap();
        }
        w.finish().unwrap();
        drop(w);
        let mut bytes = buf.into_inner();
        let at = bytes
            .windows(8)
            .position(|x| x == 0.05f64.to_le_bytes())
            .unwrap();
        bytes[at] ^= 1;
        let path = dir.join("damaged.mcap");
        std::fs::write(&path, bytes).unwrap();
        (model, path)
    }

    #[test]
    fn strict_refuses_a_damaged_bag_and_the_default_reads_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let (model, path) = damaged_bag(dir.path());
        let args = JointLogArgs {
            joint_topic: DEFAULT_JOINT_TOPIC.into(),
            joint_names: Vec::new(),
        };
        let samples = args.read_samples(&path, &model, false).unwrap();
        assert!(samples.t_s.len() > 50 && samples.t_s.len() < 100);
        let err = args.read_samples(&path, &model, true).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.message.contains("--strict refuses"), "{}", err.message);
        assert!(err.message.contains("CRC"), "{}", err.message);
    }

    /// A bag value outside the limits is quoted in the bag's unit (rad), the model's beside.
    #[test]
    fn a_bag_value_out_of_limits_is_quoted_in_rad() {
        let dir = tempfile::tempdir().unwrap();
        let (model, _) = damaged_bag(dir.path());
        let mut buf = std::io::Cursor::new(Vec::new());
        let mut w = mcap::WriteOptions::new().create(&mut buf).unwrap();
        let schema = w
            .add_schema("sensor_msgs/msg/JointState", "ros2msg", b"")
            .unwrap();
        let ch = w
            .add_channel(schema, "/joint_states", "cdr", &Default::default())
            .unwrap();
        let m = JointState {
            sec: 1,
            nanosec: 0,
            frame_id: String::new(),
            names: vec!["a".into()],
            position: vec![4.0],
        };
        let h = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: 0,
            log_time: 0,
            publish_time: 0,
        };
        w.write_to_known_channel(&h, &encode_joint_state(&m))
            .unwrap();
        w.finish().unwrap();
        drop(w);
        let path = dir.path().join("far.mcap");
        std::fs::write(&path, buf.into_inner()).unwrap();
        let args = JointLogArgs {
            joint_topic: DEFAULT_JOINT_TOPIC.into(),
            joint_names: Vec::new(),
        };
        let err = args.read_samples(&path, &model, false).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(
            err.message
                .contains("joint `a` = 4 rad is outside its limits [-3.14159"),
            "{}",
            err.message
        );
        assert!(
            err.message.contains("limits [-180, 180] deg"),
            "{}",
            err.message
        );
    }

    #[test]
    fn joint_names_must_fit_the_model() {
        let dir = tempfile::tempdir().unwrap();
        let (model, path) = damaged_bag(dir.path());
        let args = JointLogArgs {
            joint_topic: DEFAULT_JOINT_TOPIC.into(),
            joint_names: vec!["a".into(), "b".into()],
        };
        let err = args.read_samples(&path, &model, false).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(
            err.message.contains("1 different names needed"),
            "{}",
            err.message
        );
        // A CSV with the bag options is refused.
        assert!(args.check_for(Path::new("j.csv")).is_err());
    }
}
