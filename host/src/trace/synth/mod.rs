//! Synthetic images of a traced sheet with exact truth, for simulation (`rigctl simulate
//! --session`), tests and benches; nothing here is used to trace.
//!
//! - [`render_scan`] ([`scan`]): a flatbed scan of the A4 sheet, the page placed on the glass
//!   with a small rotation and shift; its drawing primitives and noise are in `draw.rs`, the
//!   desk around the page and the arc length along the pencil in `desk.rs`;
//! - [`render_photo`] ([`photo`]): a phone photo of that sheet through a tilted pinhole camera
//!   with lens distortion, uneven light, blur, noise and JPEG compression ([`jpeg_bytes`]);
//! - a photo's sheet bent ([`Bend`], `bend.rs`: a bow or a lifted edge, a cylinder about an axis
//!   in the sheet plane, the paper unrolled along it);
//! - a hard shadow across a photo's sheet ([`HardShadow`], `shadow.rs`: a phone's rectangle,
//!   sharp-edged); a scan's page edge inside the trace area (`RenderSpec::page_offset_mm`, the
//!   lid beyond it and the edge's shadow on the lid, `desk.rs`);
//! - both written through a device's tone curve ([`DeviceTone`], `device.rs`: sRGB, a gamma, a
//!   phone's S-curve; linear by default).

pub mod bend;
mod desk;
pub mod device;
mod draw;
pub mod photo;
pub mod scan;
pub mod shadow;

pub use bend::{Bend, BendShape};
pub use device::DeviceTone;
pub use photo::{jpeg_bytes, render_photo, Camera, PhotoSpec};
pub use scan::{render_scan, RenderSpec};
pub use shadow::HardShadow;
