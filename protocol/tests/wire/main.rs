//! The wire crate's tests: one test binary, a module per area (`cargo test -p rig-protocol --test wire <area>`).

mod common;

mod decoder;
mod frozen_vectors;
mod random_streams;
mod round_trip;
mod schema;
