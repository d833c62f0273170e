//! File formats at the edges: the shared CSV table reader, pose CSV files (several measured
//! points per pose, joint columns by name, units converted at the edge: [`units`]), output files (atomic
//! for regular files, direct for devices and FIFOs) and the process's interruption handling.

pub mod atomic;
pub mod cdr;
pub mod dialect;
pub mod file_set;
pub mod files;
pub mod finite;
pub mod finite_json;
pub mod interrupt;
pub mod markup;
pub mod pose_csv;
pub mod ranges;
pub mod read;
pub mod rosbag;
pub mod shown;
pub mod table;
pub mod units;
