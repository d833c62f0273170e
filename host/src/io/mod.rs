//! File formats at the edges: the shared CSV table reader, pose CSV files and atomically written
//! outputs.

pub mod atomic;
pub mod pose_csv;
pub mod table;
