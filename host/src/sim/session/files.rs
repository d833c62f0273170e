//! The files a simulated session leaves behind ([`write_session`], see [`super`]): the
//! potentiometer samples as the board stamped them ([`Session::pot_samples`]) and the simulated
//! scan of its sheet ([`render_session_scan`]).

use std::path::Path;

use image::RgbImage;

use crate::daq::recording::{RecordingMeta, RecordingWriter};
use crate::io::atomic::write_bytes_atomic;
#[cfg(feature = "synth")]
use crate::trace::synth::{render_scan, RenderSpec};

use image::ImageEncoder as _;

use super::{Session, SessionConfig, SessionError, SESSION_FORMAT};

impl Session {
    /// The potentiometer samples as the board stamped them.
    pub fn pot_samples(&self) -> Vec<crate::fusion::pot::PotSample> {
        self.pot_raw
            .iter()
            .enumerate()
            .map(|(j, &raw)| crate::fusion::pot::PotSample {
                t_us: self.board_t0_us + j as u64 * u64::from(self.pot_period_us),
                raw,
            })
            .collect()
    }
}

/// The simulated scan of the session's sheet (without the `synth` feature: no renderer, an
/// error).
#[cfg(feature = "synth")]
pub fn render_session_scan(s: &Session, cfg: &SessionConfig) -> Result<RgbImage, SessionError> {
    Ok(render_scan(&RenderSpec {
        dpi: cfg.dpi,
        pencil_mm: s.pencil_mm.clone(),
        pencil_closed: cfg.path == crate::sheet::drawn::SessionPath::Circle,
        reference: Some(cfg.path.reference()),
        rotation_deg: cfg.scan_rotation_deg,
        shift_mm: [1.5, -2.0],
        seed: cfg.seed.wrapping_add(17),
        ..RenderSpec::default()
    }))
}

/// See the `synth` build: this one has no sheet renderer.
#[cfg(not(feature = "synth"))]
pub fn render_session_scan(_s: &Session, _cfg: &SessionConfig) -> Result<RgbImage, SessionError> {
    Err(SessionError::NoRenderer)
}

/// Writes the session's files into `dir` (created if missing); see the module documentation.
pub fn write_session(dir: &Path, s: &Session, cfg: &SessionConfig) -> Result<(), SessionError> {
    // The scan first: without a renderer (no `synth` feature) nothing is written.
    let img = render_session_scan(s, cfg)?;
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| SessionError::Write { path, source }
    };
    // the files of one session, never a mix of concurrent runs into the same directory
    let _lock = crate::io::atomic::lock_dir(dir)?;
    // written as one commit (crate::io::file_set)
    let set = crate::io::file_set::begin(dir, crate::sim::output::sim_file)?;
    let nj = s.q_deg.first().map_or(0, Vec::len);
    let qhead: Vec<String> = (1..=nj).map(|j| format!("q{j}")).collect();
    let mut joints = format!("t,{}\n", qhead.join(","));
    let mut truth_path = format!("t,{},x,y,z\n", qhead.join(","));
    for ((t, q), p) in s.t_s.iter().zip(&s.q_deg).zip(&s.truth_mm) {
        let qs: Vec<String> = q.iter().map(|v| format!("{v:.6}")).collect();
        joints.push_str(&format!("{t:.3},{}\n", qs.join(",")));
        truth_path.push_str(&format!(
            "{t:.3},{},{:.9},{:.9},{:.9}\n",
            qs.join(","),
            p.x,
            p.y,
            p.z
        ));
    }
    let csv = crate::io::finite::TextFormat::Csv;
    crate::io::atomic::check_text_for(&dir.join("joints.csv"), csv, &joints)?;
    crate::io::atomic::check_text_for(&dir.join("truth_path.csv"), csv, &truth_path)?;
    write_bytes_atomic(&dir.join("joints.csv"), joints.as_bytes())?;
    write_bytes_atomic(&dir.join("truth_path.csv"), truth_path.as_bytes())?;
    let mut jig =
        String::from("# gauge-block jig: mean counts of 100 readings per gauge\nraw,travel_mm\n");
    for p in &s.jig {
        jig.push_str(&format!("{:.2},{}\n", p.raw, p.travel_mm));
    }
    crate::io::atomic::write_text_atomic(&dir.join("potjig.csv"), csv, &jig)?;
    s.placement.write(&dir.join("placement.toml"))?;
    s.truth.write_file(&dir.join("truth.toml"))?;
    // the recording: written under a temporary name, renamed when complete
    let rec = dir.join("pot.rec");
    let tmp = crate::io::atomic::temp_path(&rec);
    crate::io::interrupt::register_temp(&tmp);
    let meta = RecordingMeta {
        protocol_version: rig_protocol::PROTOCOL_VERSION,
        port: "simulated".into(),
        start_time_unix_us: 0,
        pot_rate_hz: cfg.pot_rate_hz,
        tilt_rate_hz: 0,
        hello: None,
        rigctl_version: env!("CARGO_PKG_VERSION").into(),
    };
    let mut w = RecordingWriter::create(&tmp, &meta, true)?;
    for (rx, f) in &s.frames {
        w.append(*rx, f)?;
    }
    w.finish()?;
    if !crate::io::file_set::stage(&tmp, &rec) {
        std::fs::rename(&tmp, &rec).map_err(io(&rec))?;
        crate::io::interrupt::unregister_temp(&tmp);
    }
    // the scan
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| SessionError::Image(e.to_string()))?;
    write_bytes_atomic(&dir.join("scan.png"), &png)?;
    let errors: serde_json::Map<String, serde_json::Value> = s
        .geometric_errors
        .iter()
        .map(|(k, v)| (k.clone(), serde_json::json!(v)))
        .collect();
    let json = serde_json::json!({
        "format": SESSION_FORMAT,
        "path": cfg.path.as_str(),
        "seed": cfg.seed,
        "clock_offset_s": cfg.clock_offset_s,
        "clock_drift_ppm": cfg.clock_drift_ppm,
        "counts_at_zero": cfg.counts_at_zero,
        "counts_per_mm": cfg.counts_per_mm,
        "pot_noise_counts": cfg.pot_noise_counts,
        "pencil_stop_mm": cfg.pencil_stop_mm,
        "draw_duration_s": cfg.draw_duration_s,
        "dpi": cfg.dpi,
        "scan_rotation_deg": cfg.scan_rotation_deg,
        "geometric_errors_deg": errors,
        "effects": cfg
            .effects
            .iter()
            .map(|e| serde_json::json!({"id": e.id, "values": e.values}))
            .collect::<Vec<_>>(),
    });
    let text = serde_json::to_string_pretty(&json).unwrap_or_default();
    write_bytes_atomic(&dir.join("session.json"), format!("{text}\n").as_bytes())?;
    set.commit()?;
    Ok(())
}
