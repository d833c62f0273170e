//! File formats at the edges: pose CSV files and atomically written outputs.

pub mod atomic;
pub mod pose_csv;
