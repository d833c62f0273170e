//! The stages of a trace, in the order [`super::trace_prepared`] runs them, each with its tuned
//! numbers in one documented parameter struct (defaults in one place):
//!
//! 1. [`prepare`]: the whole-image maps (paper level, coarse darkness), band by band;
//! 2. [`fiducials`]: the printed discs, the corner square and the orientation dot;
//! 3. [`camera`]: homography and radial lens distortion on the printed marks;
//! 4. [`centreline`]: the pencil tracked across its stroke, pieces in pixels;
//! 5. [`link`]: pieces linked end to end into the drawn path (or a plotter's passes), skips
//!    bridged, what is left out judged;
//! 6. [`lines`]: a drawing's drawn lines followed through the band of ink their passes leave.

pub mod camera;
pub(super) mod centreline;
pub mod fiducials;
pub(super) mod lines;
pub mod link;
pub(super) mod prepare;
