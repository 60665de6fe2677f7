//! The charts' common frame (plotters on an RGB buffer, written atomically as PNG): the fit's,
//! the forecast's and the boundary's plots are each one `plot` call.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::Outputs;
use crate::error::{Error, Result};

/// A plotters error as ours.
pub(crate) fn err<E: std::fmt::Debug>(e: E) -> Error {
    Error::plot(e)
}

/// Every chart's background.
pub(crate) const BG: RGBColor = RGBColor(255, 255, 255);

/// An axis range over the finite `values`, padded by `pad` of its span; 0..1 when there are
/// none or their span overflows (plotters never ends on a non-finite range).
pub(crate) fn range(values: impl Iterator<Item = f64>, pad: f64) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let m = ((hi - lo) * pad).max(1e-9 * (1.0 + lo.abs().max(hi.abs())));
    if (lo - m).is_finite() && (hi + m).is_finite() && lo <= hi {
        (lo - m)..(hi + m)
    } else {
        0.0..1.0
    }
}

/// A plot of `size` pixels drawn by `draw` on a white area, written as `path` (PNG with the
/// tEXt chunks `text`, [`titled`] at least) into `out`: every chart's frame.
pub(crate) fn plot(
    out: &mut Outputs,
    path: &Path,
    (w, h): (u32, u32),
    text: &[(String, String)],
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    super::register_font();
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        root.fill(&BG).map_err(err)?;
        draw(&root)?;
        root.present().map_err(err)?;
    }
    out.png(path, w, h, &rgb, text)
}

/// A chart's Title text (PNG tEXt is Latin-1: say it in ASCII).
pub(crate) fn titled(title: &str) -> [(String, String); 1] {
    [("Title".into(), title.into())]
}

/// A panel of positions over time: `t (s)` along x under a light grid.
pub(crate) fn time_grid(
    chart: &mut ChartContext<'_, BitMapBackend<'_>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
) -> Result<()> {
    chart
        .configure_mesh()
        .x_desc("t (s)")
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)
}
