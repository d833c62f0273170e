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

/// Declares a stage's parameter struct: every number once, with its doc (unit, what raising or
/// lowering it trades off) and its tuned value after `=`. Gives the struct (public fields, the
/// tuned value appended to each field's doc) and its `Default`: the tuned values.
macro_rules! stage_params {
    (
        $(#[doc = $doc:expr])*
        pub struct $name:ident {
            $(
                $(#[doc = $fdoc:expr])*
                $field:ident: $ty:ty = $tuned:expr,
            )*
        }
    ) => {
        $(#[doc = $doc])*
        #[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
        #[serde(default, deny_unknown_fields)]
        pub struct $name {
            $(
                $(#[doc = $fdoc])*
                #[doc = ""]
                #[doc = concat!("Tuned: `", stringify!($tuned), "`.")]
                pub $field: $ty,
            )*
        }

        impl Default for $name {
            /// The tuned values.
            fn default() -> Self {
                Self {
                    $($field: $tuned,)*
                }
            }
        }

        impl $name {
            /// The first number out of [`params_file::Bounded`]'s range, by name.
            pub(crate) fn out_of_range(&self) -> Option<&'static str> {
                use $crate::trace::stages::params_file::Bounded as _;
                $(
                    if !self.$field.in_range() {
                        return Some(stringify!($field));
                    }
                )*
                None
            }
        }
    };
}

pub mod camera;
pub(super) mod centreline;
pub mod fiducials;
pub(super) mod lines;
pub mod link;
pub(crate) mod params_file;
pub(super) mod prepare;

pub use camera::CameraParams;
pub use centreline::CentrelineParams;
pub use fiducials::FiducialParams;
pub use lines::LinesParams;
pub use link::LinkParams;
pub use prepare::PrepareParams;

/// Every stage's numbers, carried by [`crate::trace::TraceOptions::params`] into each stage
/// (`&params.link`, ...). `Default`: the tuned values, written once in each stage's `params.rs`.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TraceParams {
    pub prepare: PrepareParams,
    pub fiducials: FiducialParams,
    pub camera: CameraParams,
    pub centreline: CentrelineParams,
    pub link: LinkParams,
    pub lines: LinesParams,
}
