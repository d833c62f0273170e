//! The camera stage's tuned numbers ([`super::camera`]) in one place, each with its unit and
//! what it trades off.

/// The numbers of the camera fit: the prior on the distortion centre and the test that keeps it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::trace) struct CameraParams {
    /// How well a printed mark is located, pixels: the scale of the residuals the prior on the
    /// distortion centre is weighed against. Larger: the prior holds the centre harder.
    pub(in crate::trace) mark_sigma_px: f64,
    /// The prior's standard deviation for the distortion centre, in half diagonals of
    /// the image. Smaller: the centre stays nearer the image centre where the marks tell little.
    pub(in crate::trace) centre_sigma_half_diagonals: f64,
    /// The F statistic (reduction of the squared residuals per added parameter, over the residual
    /// variance) above which the fitted distortion centre is kept: F(2, 90) is 7.4 at p = 0.001.
    /// Higher: fewer images get a centre of their own, fewer fit the marks' noise with one.
    pub(in crate::trace) centre_f: f64,
}

/// The tuned values.
pub(in crate::trace) const CAMERA: CameraParams = CameraParams {
    mark_sigma_px: 0.3,
    centre_sigma_half_diagonals: 0.25,
    centre_f: 10.0,
};
