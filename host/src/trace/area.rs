//! Checks of the options and the parts of the image where strokes are read: the sheet's trace
//! area without its printed marks, and the coarse blocks that may seed a stroke.

use super::paper::PaperMap;
use super::{raster, Mapping, TraceError, TraceOptions};
use crate::sheet::{
    fiducial_centres_mm, orientation_dot_mm, FIDUCIAL_DIAMETER_MM, FIDUCIAL_SPACING_MM,
    ORIENTATION_DOT_DIAMETER_MM, TRACE_AREA_HALF_HEIGHT_MM, TRACE_AREA_HALF_WIDTH_MM,
};

pub(crate) fn check_options(opts: &TraceOptions) -> Result<(), TraceError> {
    let bad = |name, value, reason| {
        Err(TraceError::BadOption {
            name,
            value,
            reason,
        })
    };
    match opts.mapping {
        Mapping::Fiducials { spacing_mm }
            if !(spacing_mm.is_finite() && (10.0..=1000.0).contains(&spacing_mm)) =>
        {
            return bad(
                "--fiducial-spacing-mm",
                spacing_mm,
                "expected 10..1000 mm (nominally 180)",
            );
        }
        Mapping::Scale { mm_per_px }
            if !(mm_per_px.is_finite() && mm_per_px > 0.0 && mm_per_px < 100.0) =>
        {
            return bad(
                "--mm-per-px",
                mm_per_px,
                "expected a positive scale below 100 mm per pixel",
            );
        }
        _ => {}
    }
    if !(opts.spacing_mm > 0.0 && opts.spacing_mm <= 0.5) {
        return bad("spacing_mm", opts.spacing_mm, "expected (0, 0.5] mm");
    }
    if !(opts.min_darkness > 0.0 && opts.min_darkness < 1.0) {
        return bad("min_darkness", opts.min_darkness as f64, "expected (0, 1)");
    }
    Ok(())
}

/// Where strokes are read, in pixel coordinates: the sheet's trace area without the fiducials
/// (fiducial mapping) or the image less a 2-pixel border (scale mapping).
pub(crate) fn roi_predicate<'a>(
    mapping: Mapping,
    to_mm: &'a dyn Fn([f64; 2]) -> [f64; 2],
    w_px: f64,
    h_px: f64,
) -> Box<dyn Fn([f64; 2]) -> bool + 'a> {
    let inside_image =
        move |p: [f64; 2]| p[0] >= 2.0 && p[1] >= 2.0 && p[0] <= w_px - 2.0 && p[1] <= h_px - 2.0;
    match mapping {
        Mapping::Scale { .. } => Box::new(inside_image),
        Mapping::Fiducials { spacing_mm } => {
            let f = spacing_mm / FIDUCIAL_SPACING_MM;
            let mut keep_out: Vec<([f64; 2], f64)> = fiducial_centres_mm(spacing_mm)
                .iter()
                .map(|c| (*c, (0.5 * FIDUCIAL_DIAMETER_MM + 2.0) * f))
                .collect();
            keep_out.push((
                orientation_dot_mm(spacing_mm),
                (0.5 * ORIENTATION_DOT_DIAMETER_MM + 2.0) * f,
            ));
            Box::new(move |p| {
                if !inside_image(p) {
                    return false;
                }
                let s = to_mm(p);
                s[0].abs() <= TRACE_AREA_HALF_WIDTH_MM * f
                    && s[1].abs() <= TRACE_AREA_HALF_HEIGHT_MM * f
                    && keep_out
                        .iter()
                        .all(|(c, r)| (s[0] - c[0]).hypot(s[1] - c[1]) > *r)
            })
        }
    }
}

/// Coarse blocks that may seed a stroke: dark enough (black too: a soft pencil), in the trace
/// area, in a component larger than a speck.
pub(crate) fn seed_mask(
    map: &raster::CoarseMap,
    paper: &PaperMap,
    opts: &TraceOptions,
    roi: &dyn Fn([f64; 2]) -> bool,
    px_per_mm: f64,
) -> Vec<bool> {
    let dark = map.classify(paper, |v, level| {
        let dark_max = (level * (1.0 - opts.min_darkness)).max(0.0);
        (v as f32) <= dark_max
    });
    let mut mask = dark;
    for (i, m) in mask.iter_mut().enumerate() {
        if *m {
            *m = roi(map.block_centre_px(i % map.w, i / map.w));
        }
    }
    let (labels, comps) = raster::components(&mask, map.w, map.h);
    let block_mm = map.k as f64 / px_per_mm;
    let keep: Vec<bool> = comps
        .iter()
        .map(|c| {
            let extent =
                (c.bbox[2] - c.bbox[0] + 1).max(c.bbox[3] - c.bbox[1] + 1) as f64 * block_mm;
            extent >= 0.5 * opts.min_stroke_mm.min(2.0)
        })
        .collect();
    for (m, &l) in mask.iter_mut().zip(&labels) {
        if *m {
            *m = keep[l as usize - 1];
        }
    }
    mask
}
