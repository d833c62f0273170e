//! The CSV table reader of `JOINTS_TILT.csv` and `compensate`'s path files: the crate's shared
//! [`crate::io::table`], re-exported here under its original path.

pub use crate::io::table::{Row, Table, TableError};
