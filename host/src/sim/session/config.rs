//! The settings of a simulated session ([`SessionConfig`], the default sheet placement of a
//! path) and why a session fails ([`SessionError`]).

use nalgebra::Vector3;

use crate::daq::recording::RecordingError;
use crate::fusion::{FusionError, SheetPlacement};
use crate::io::atomic::AtomicWriteError;
use crate::model::dynamics::Inertia;
use crate::model::ik::IkError;
use crate::model::ModelError;
use crate::sheet::drawn::{SessionPath, SESSION_SHEET_ORIGIN_MM};
use crate::sim::effects::Effect;
use crate::sim::simulate::SimError;

impl SessionPath {
    /// The default sheet placement of this path: the 45-degree plane of
    /// [`SheetPlacement::thesis_plane`] through [`SESSION_SHEET_ORIGIN_MM`] (the circle), or 30 mm
    /// up the slope from it (the line).
    pub fn default_placement(self) -> SheetPlacement {
        let c = Vector3::from(SESSION_SHEET_ORIGIN_MM);
        let base = SheetPlacement::thesis_plane(c);
        match self {
            Self::Circle => base,
            Self::Line => SheetPlacement::thesis_plane(c + base.y_axis * 30.0),
        }
    }
}

/// Settings of a simulated session (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct SessionConfig {
    pub path: SessionPath,
    /// Seed of the truth errors and of the noise (the same seed gives the same robot).
    pub seed: u64,
    /// Standard deviation of the geometric errors, deg.
    pub geometric_sigma_deg: f64,
    /// Drawing time, s.
    pub draw_duration_s: f64,
    /// Joint log rate, Hz (divides 1000).
    pub robot_rate_hz: u32,
    /// Potentiometer sample rate, Hz (divides 1e6).
    pub pot_rate_hz: u32,
    /// Board time at robot time 0, s.
    pub clock_offset_s: f64,
    /// Board clock rate error, ppm.
    pub clock_drift_ppm: f64,
    /// Counts at zero travel.
    pub counts_at_zero: f64,
    /// Counts per mm of travel (negative: counts fall as the pencil extends).
    pub counts_per_mm: f64,
    /// Potentiometer noise, counts (standard deviation).
    pub pot_noise_counts: f64,
    /// Travel at the pencil's stop (off the paper), mm.
    pub pencil_stop_mm: f64,
    /// Height of the tool point above the paper before and after drawing, mm.
    pub lift_mm: f64,
    /// Depth of the marker dips, mm.
    pub dip_mm: f64,
    /// Scan resolution, dpi.
    pub dpi: f64,
    /// Rotation of the sheet on the scanner, deg.
    pub scan_rotation_deg: f64,
    /// Link inertia for the moments in motion.
    pub inertia: Inertia,
    /// Sheet placement (`None`: the path's default).
    pub placement: Option<SheetPlacement>,
    /// Pencil (tool) axis while drawing, unit, frame R (`None`: [`default_pencil_axis`]).
    pub pencil_axis: Option<Vector3<f64>>,
    /// Effects the declared model lacks, applied to the truth (model-parameter effects only:
    /// a session lasts seconds, so time drifts are refused).
    pub effects: Vec<Effect>,
}

impl Default for SessionConfig {
    fn default() -> Self {
        Self {
            path: SessionPath::Circle,
            seed: 1,
            geometric_sigma_deg: 0.05,
            draw_duration_s: 8.0,
            robot_rate_hz: 100,
            pot_rate_hz: 1000,
            clock_offset_s: 12.345_678_9,
            clock_drift_ppm: 0.0,
            counts_at_zero: 2000.0,
            counts_per_mm: -380.0,
            pot_noise_counts: 1.0,
            pencil_stop_mm: 2.0,
            lift_mm: 5.0,
            dip_mm: 1.5,
            dpi: 600.0,
            scan_rotation_deg: 1.2,
            inertia: Inertia::default(),
            placement: None,
            pencil_axis: None,
            effects: Vec::new(),
        }
    }
}

/// Why a session could not be simulated or written.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// A setting out of range.
    #[error("{0}")]
    Config(String),
    /// A target the nominal arm cannot reach.
    #[error(transparent)]
    Ik(#[from] IkError),
    /// The model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The truth could not be built.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The pencil would leave its travel range (the arm is too far off).
    #[error("the pencil travel {travel_mm:.2} mm at robot time {t_s:.3} s is beyond its range")]
    PencilRange { travel_mm: f64, t_s: f64 },
    /// A frame could not be encoded.
    #[error("cannot encode a potentiometer frame: {0}")]
    Encode(String),
    /// The scan could not be encoded.
    #[error("cannot encode the scan: {0}")]
    Image(String),
    /// This build has no sheet renderer (the host crate's `synth` feature is off).
    #[error(
        "this rigctl was built without the sheet renderer (cargo feature `synth`): a session's \
         scan.png cannot be drawn; nothing written (build with default features)"
    )]
    NoRenderer,
    /// The recording could not be written.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// An output directory or file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An atomic write failed.
    #[error(transparent)]
    Atomic(#[from] AtomicWriteError),
    /// The placement file could not be written.
    #[error(transparent)]
    Fusion(#[from] FusionError),
}

impl crate::error::Classify for SessionError {
    fn kind(&self) -> crate::error::ErrorKind {
        use crate::error::ErrorKind;
        match self {
            Self::Config(_) | Self::NoRenderer => ErrorKind::BadInput,
            Self::Ik(e) => e.kind(),
            Self::Model(e) => e.kind(),
            Self::Sim(e) => e.kind(),
            Self::Fusion(e) => e.kind(),
            _ => ErrorKind::Failure,
        }
    }
}
