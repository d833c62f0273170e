//! How pixels become sheet mm: the camera fitted on the printed marks (fiducial mapping) or a
//! plain scale about the image centre.

use super::paper::PaperMap;
use super::raster::CoarseMap;
use super::stages::centreline::Occluders;
use super::{
    fiducials, flatness, CameraModel, Fiducials, FitQuality, Homography, Mapping, TraceError,
    TraceOptions,
};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, ring_dots_mm, FIDUCIAL_SPACING_MM,
    RING_DOT_DIAMETER_MM,
};
use image::RgbImage;

/// The camera, its fit on the marks, the orientation dot's residual (mm) and the marks'
/// residual pattern.
pub(crate) type CameraFit = (
    CameraModel,
    Option<FitQuality>,
    f64,
    Option<flatness::Flatness>,
);

/// The camera of a fiducial mapping: fitted on all marks with the ring, else the corners'
/// homography. Returns the model, the fit (ring), the orientation dot's residual, mm, and the
/// marks' residual pattern (ring; [`flatness`]). A pattern over
/// `opts.max_bend_pattern_mm` is [`TraceError::NotFlat`].
pub(crate) fn fit_camera(
    img: &RgbImage,
    fid: &Fiducials,
    spacing_mm: f64,
    opts: &TraceOptions,
) -> Result<CameraFit, TraceError> {
    let size = [img.width() as f64, img.height() as f64];
    let expected = orientation_dot_mm(spacing_mm);
    if fid.ring.len() >= 8 {
        let mut mm: Vec<[f64; 2]> = fiducial_centres_mm(spacing_mm).to_vec();
        let mut px: Vec<[f64; 2]> = fid.corners.iter().map(|d| d.centre_px).collect();
        mm.push(expected);
        px.push(fid.dot.centre_px);
        for (d, m) in &fid.ring {
            mm.push(*m);
            px.push(d.centre_px);
        }
        let (cam, q) = CameraModel::fit(&mm, &px, size, &opts.params.camera)
            .ok_or(TraceError::DegenerateFiducials)?;
        let flat = flatness_of(&cam, &mm, &px);
        let limit_mm = opts.max_camera_rms_mm * spacing_mm / FIDUCIAL_SPACING_MM;
        if !(q.rms_mm <= limit_mm && q.max_mm <= 4.0 * limit_mm) {
            return Err(TraceError::CameraCheck {
                rms_mm: q.rms_mm,
                max_mm: q.max_mm,
                used: q.used,
                found: q.found,
                limit_mm,
            });
        }
        if let Some(f) = flat.filter(|f| f.is_bent(opts.max_bend_pattern_mm)) {
            return Err(TraceError::NotFlat {
                pattern_mm: f.pattern_mm,
                pattern_max_mm: f.pattern_max_mm,
                scatter_mm: f.scatter_mm,
                limit_mm: opts.max_bend_pattern_mm,
            });
        }
        let dot = cam.to_mm(fid.dot.centre_px);
        let residual = (dot[0] - expected[0]).hypot(dot[1] - expected[1]);
        return Ok((cam, Some(q), residual, flat));
    }
    let px: Vec<[f64; 2]> = fid.corners.iter().map(|d| d.centre_px).collect();
    let to_px = Homography::fit(&fiducial_centres_mm(spacing_mm), &px)
        .ok_or(TraceError::DegenerateFiducials)?;
    let cam = CameraModel::from_homography(&to_px, size).ok_or(TraceError::DegenerateFiducials)?;
    let dot = cam.to_mm(fid.dot.centre_px);
    let residual_mm = (dot[0] - expected[0]).hypot(dot[1] - expected[1]);
    if residual_mm.is_nan() || residual_mm > 1.0 {
        return Err(TraceError::FiducialResidual { residual_mm });
    }
    Ok((cam, None, residual_mm, None))
}

/// The residual pattern of the marks under the camera (marks off the fit by more than five
/// times the median left out, as the fit leaves them out; the corners and the dot kept).
fn flatness_of(cam: &CameraModel, mm: &[[f64; 2]], px: &[[f64; 2]]) -> Option<flatness::Flatness> {
    let res: Vec<[f64; 2]> = mm
        .iter()
        .zip(px)
        .map(|(m, p)| {
            let q = cam.to_mm(*p);
            [q[0] - m[0], q[1] - m[1]]
        })
        .collect();
    let mut len: Vec<f64> = res.iter().map(|r| r[0].hypot(r[1])).collect();
    len.sort_by(f64::total_cmp);
    let med = len.get(len.len() / 2).copied()?;
    let keep: Vec<usize> = (0..res.len())
        .filter(|&i| i < 5 || res[i][0].hypot(res[i][1]) <= (5.0 * med).max(0.05))
        .collect();
    let s: Vec<[f64; 2]> = keep.iter().map(|&i| mm[i]).collect();
    let r: Vec<[f64; 2]> = keep.iter().map(|&i| res[i]).collect();
    flatness::measure(&s, &r)
}

/// A pixel -> sheet mm map.
pub(crate) type ToMm = Box<dyn Fn([f64; 2]) -> [f64; 2]>;

/// Sheet mm -> image pixels: through the camera model (fiducial mapping), or the plain scale
/// `px_per_mm` about the image centre, y up (the inverse of [`map_pixels`]'s map).
#[derive(Clone, Copy)]
pub(crate) struct SheetToPx {
    pub camera: Option<CameraModel>,
    pub px_per_mm: f64,
    /// Image width and height, px.
    pub size_px: [f64; 2],
}

impl SheetToPx {
    pub fn px(&self, p: [f64; 2]) -> [f64; 2] {
        match &self.camera {
            Some(cam) => cam.to_px(p),
            None => [
                p[0] * self.px_per_mm + 0.5 * self.size_px[0],
                0.5 * self.size_px[1] - p[1] * self.px_per_mm,
            ],
        }
    }
}

/// The mapping of one image and what was measured to find it.
pub(crate) struct Mapped {
    pub to_mm: ToMm,
    pub fiducials: Option<Fiducials>,
    pub camera: Option<CameraModel>,
    pub camera_fit: Option<FitQuality>,
    pub dot_residual_mm: Option<f64>,
    /// The marks' residual pattern under the camera (ring).
    pub flatness: Option<flatness::Flatness>,
    /// Image scale, pixels per mm.
    pub px_per_mm: f64,
    /// The ring dots, which the pencil may cross.
    pub occluders: Occluders,
}

/// Margin around a printed ring dot inside which the pencil is not read (its blurred edge), mm.
const OCCLUDER_MARGIN_MM: f64 = 0.3;

/// The sheet-v2 ring dots the mark search did not find, placed by the fitted camera: a dot the
/// pencil runs over merges with the graphite and is no disc any more, yet its ink is there and
/// would pull the centreline into it. `(centre, radius)` in pixels, the radius the printed
/// one's largest extent in the image plus the margin.
fn dots_not_found(fid: &Fiducials, cam: &CameraModel, spacing_mm: f64) -> Vec<([f64; 2], f64)> {
    let radius_mm = 0.5 * RING_DOT_DIAMETER_MM * spacing_mm / FIDUCIAL_SPACING_MM;
    ring_dots_mm(spacing_mm)
        .into_iter()
        .filter(|m| {
            !fid.ring
                .iter()
                .any(|(_, n)| (n[0] - m[0]).hypot(n[1] - m[1]) < 1e-6)
        })
        .map(|m| {
            let c = cam.to_px(m);
            let reach_px = [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]
                .iter()
                .map(|u| {
                    let q = cam.to_px([m[0] + radius_mm * u[0], m[1] + radius_mm * u[1]]);
                    (q[0] - c[0]).hypot(q[1] - c[1]) * (radius_mm + OCCLUDER_MARGIN_MM) / radius_mm
                })
                .fold(0.0, f64::max);
            (c, reach_px)
        })
        .collect()
}

/// Finds the marks and fits the camera (fiducial mapping), or sets up the plain scale.
pub(crate) fn map_pixels(
    img: &RgbImage,
    map: &CoarseMap,
    paper: &PaperMap,
    opts: &TraceOptions,
) -> Result<Mapped, TraceError> {
    let (w_px, h_px) = (img.width() as f64, img.height() as f64);
    let mut occluders = Occluders::default();
    match opts.mapping {
        Mapping::Fiducials { spacing_mm } => {
            let fid = fiducials::find(img, map, paper, spacing_mm, &opts.params.fiducials)?;
            let (cam, fit, residual, flat) = fit_camera(img, &fid, spacing_mm, opts)?;
            let ppmm = fid.side_px() / spacing_mm;
            for (d, _) in &fid.ring {
                occluders
                    .discs
                    .push((d.centre_px, 0.5 * d.diameter_px + OCCLUDER_MARGIN_MM * ppmm));
            }
            if fit.is_some() {
                occluders
                    .discs
                    .extend(dots_not_found(&fid, &cam, spacing_mm));
            }
            Ok(Mapped {
                to_mm: Box::new(move |p| cam.to_mm(p)),
                fiducials: Some(fid),
                camera: Some(cam),
                camera_fit: fit,
                dot_residual_mm: Some(residual),
                flatness: flat,
                px_per_mm: ppmm,
                occluders,
            })
        }
        Mapping::Scale { mm_per_px } => Ok(Mapped {
            to_mm: Box::new(move |p: [f64; 2]| {
                [
                    (p[0] - w_px / 2.0) * mm_per_px,
                    (h_px / 2.0 - p[1]) * mm_per_px,
                ]
            }),
            fiducials: None,
            camera: None,
            camera_fit: None,
            dot_residual_mm: None,
            flatness: None,
            px_per_mm: 1.0 / mm_per_px,
            occluders,
        }),
    }
}
