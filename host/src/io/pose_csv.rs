//! Pose CSV files (FORMATS.md). (being written)
