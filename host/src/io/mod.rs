//! File formats at the edges: the shared CSV table reader, pose CSV files, output files (atomic
//! for regular files, direct for devices and FIFOs) and the process's interruption handling.

pub mod atomic;
pub mod interrupt;
pub mod pose_csv;
pub mod ranges;
pub mod table;
