//! A second sheet renderer, written apart from `rigctl::trace::synth`, so that the tracer is
//! measured on images it was not developed with.
//!
//! Model: every output pixel is mapped back to sheet mm (a scanner's rotation + shift, or a
//! pinhole camera with radial distortion `k1` in focal-length units, inverted by fixed-point
//! iteration) and the sheet is *evaluated* there: near ink a pixel is the mean of n x n
//! sub-samples. The pencil is a chain of stamped tip discs (every 0.03 mm, each disc its own
//! radius and pressure, a dome profile) laid on a paper tooth that takes graphite only on its
//! crests; the light is a smooth shading field (and, in photos, a vignette and a soft shadow
//! edge); noise is a hashed triangular distribution; photos are blurred by a 3-tap binomial
//! kernel and JPEG-compressed. Layout: sheet v2 (FORMATS.md): four 6 mm discs at (+-90, +-90),
//! the 3 mm dot at (-90, 75), 43 ring dots of 1.5 mm every 15 mm, the red reference path.
//!
//! Parts: `scene` (what the image shows), `view` (how pixels see the sheet), `strokes` (the
//! pencil), `raster` (the pixels).

#[path = "render2/raster.rs"]
mod raster;
#[path = "render2/scene.rs"]
mod scene;
#[path = "render2/strokes.rs"]
mod strokes;
#[path = "render2/view.rs"]
mod view;

pub use raster::render;
pub use scene::{Hand, Mark, Page, Printed, Scene};
pub use view::{off_centre, photo_view, scan_view, scan_view_wide, Sag};
