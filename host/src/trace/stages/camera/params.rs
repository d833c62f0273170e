//! The camera stage's tuned numbers ([`super::camera`]) in one place, each with its unit and
//! what it trades off.

stage_params! {
    /// The numbers of the camera fit: the prior on the distortion centre and the test that keeps
    /// it.
    pub struct CameraParams {
        /// How well a printed mark is located, pixels: the scale of the residuals the prior on the
        /// distortion centre is weighed against. Larger: the prior holds the centre harder.
        mark_sigma_px: f64 = 0.3,
        /// The prior's standard deviation for the distortion centre, in half diagonals of the
        /// image. Smaller: the centre stays nearer the image centre where the marks tell little.
        centre_sigma_half_diagonals: f64 = 0.25,
        /// The F statistic (reduction of the squared residuals per added parameter, over the
        /// residual variance) above which the fitted distortion centre is kept: F(2, 90) is 7.4 at
        /// p = 0.001. Higher: fewer images get a centre of their own, fewer fit the marks' noise
        /// with one.
        centre_f: f64 = 10.0,
    }
}
