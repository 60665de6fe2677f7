//! The forecast's picture: x1, y1, x2, y2 against time with the measured points, the median
//! forecast, its 50 % and 90 % bands and the fit window shaded (the report's figures 13-17),
//! the horizons, and the lower bob's spread on a log scale below.

use std::path::Path;

use plotters::prelude::*;

use super::ensemble::{Forecast, Slope};
use crate::error::Result;
use crate::fit::plots::MEASURED;
use crate::render::Outputs;
use crate::render::chart::{err, plot, range, time_grid, titled};

const BAND: RGBColor = RGBColor(31, 119, 180);
const TRUTH: RGBColor = RGBColor(44, 160, 44);
/// The marks' words for the spread's horizon and the data's, as the twin experiments show them.
pub const SPREAD_MARK: &str = "spread horizon: the spread passes the tolerance";
pub const DATA_MARK: &str = "data horizon: the measurements leave their 90 % band";

const SPREAD_HORIZON: RGBColor = RGBColor(214, 39, 40);
const DATA_HORIZON: RGBColor = RGBColor(255, 127, 14);

/// What the picture shows besides the forecast.
pub struct Marks<'a> {
    /// Measured (time, positions) rows.
    pub measured: (&'a [f64], &'a [[f64; 4]]),
    /// The hidden truth at the forecast's times (twin experiments).
    pub truth: Option<&'a [[f64; 4]]>,
    /// The two times marked (s) and what each means: the forecast's own horizon (red), and
    /// where the data showed it (orange).
    pub horizon: (Option<f64>, &'static str),
    pub on_data: (Option<f64>, &'static str),
    pub tolerance: f64,
    /// Last time shown (s).
    pub until: f64,
    pub title: String,
}

pub fn forecast(out: &mut Outputs, path: &Path, f: &Forecast, marks: &Marks) -> Result<()> {
    let shown: Vec<usize> = (0..f.times.len())
        .filter(|&k| f.times[k] <= marks.until + 1e-9)
        .collect();
    let (t, data) = marks.measured;
    let rows: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] >= f.t0 - 1e-9 && t[i] <= marks.until + 1e-9)
        .collect();
    let x_range = f.t0..marks.until;
    // Camera-rate data would hide the bands under the dots.
    let dot = if rows.len() > 100 { 1 } else { 3 };
    plot(
        out,
        path,
        (1200, 1050),
        &titled("ensemble forecast of tracked positions"),
        |root| {
            let (title, rest) = root.split_vertically(34);
            title
                .titled(&marks.title, ("sans-serif", 20))
                .map_err(err)?;
            let (top, bottom) = rest.split_vertically(740);
            let names = ["x1 (m)", "y1 (m)", "x2 (m)", "y2 (m)"];
            let lines = [
                (marks.horizon.0, SPREAD_HORIZON),
                (marks.on_data.0, DATA_HORIZON),
            ];
            for (k, area) in top.split_evenly((2, 2)).iter().enumerate() {
                let yr = range(
                    shown
                        .iter()
                        .flat_map(|&j| [f.observed[j][k][0], f.observed[j][k][4]])
                        .chain(rows.iter().map(|&i| data[i][k])),
                    0.05,
                );
                let (lo, hi) = (yr.start, yr.end);
                let mut chart = ChartBuilder::on(area)
                    .caption(names[k], ("sans-serif", 16))
                    .margin(8)
                    .x_label_area_size(28)
                    .y_label_area_size(52)
                    .build_cartesian_2d(x_range.clone(), yr)
                    .map_err(err)?;
                time_grid(&mut chart)?;
                // The fit window.
                chart
                    .draw_series([Rectangle::new(
                        [(f.t0, lo), (f.window_end, hi)],
                        RGBColor(225, 225, 225).filled(),
                    )])
                    .map_err(err)?;
                // Bands (a measurement's: the model's with the tracking error), then the median.
                for (a, b, alpha) in [(0, 4, 0.18), (1, 3, 0.35)] {
                    let upper = shown.iter().map(|&j| (f.times[j], f.observed[j][k][b]));
                    let lower = shown
                        .iter()
                        .rev()
                        .map(|&j| (f.times[j], f.observed[j][k][a]));
                    chart
                        .draw_series([Polygon::new(
                            upper.chain(lower).collect::<Vec<_>>(),
                            BAND.mix(alpha).filled(),
                        )])
                        .map_err(err)?;
                }
                chart
                    .draw_series(LineSeries::new(
                        shown.iter().map(|&j| (f.times[j], f.model[j][k][2])),
                        BAND.stroke_width(2),
                    ))
                    .map_err(err)?;
                if let Some(truth) = marks.truth {
                    chart
                        .draw_series(LineSeries::new(
                            shown.iter().map(|&j| (f.times[j], truth[j][k])),
                            TRUTH.stroke_width(1),
                        ))
                        .map_err(err)?;
                }
                chart
                    .draw_series(
                        rows.iter()
                            .map(|&i| Circle::new((t[i], data[i][k]), dot, MEASURED.filled())),
                    )
                    .map_err(err)?;
                horizons(&mut chart, &lines, marks.until, lo, hi)?;
            }
            // The lower bob's spread, log scale, with the tolerance.
            let spread: Vec<(f64, f64)> = shown
                .iter()
                .map(|&j| (f.times[j], f.spread[j].max(1e-7)))
                .collect();
            let top_spread = spread.iter().map(|s| s.1).fold(marks.tolerance, f64::max) * 2.0;
            let low_spread = spread
                .iter()
                .map(|s| s.1)
                .fold(f64::INFINITY, f64::min)
                .max(1e-7)
                / 2.0;
            let mut chart = ChartBuilder::on(&bottom)
                .caption(
                    "spread of the lower bob (m, RMS about the members' mean)",
                    ("sans-serif", 16),
                )
                .margin(8)
                .x_label_area_size(28)
                .y_label_area_size(52)
                .build_cartesian_2d(x_range.clone(), (low_spread..top_spread).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("t (s)")
                .y_labels(6)
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(err)?;
            chart
            .draw_series(LineSeries::new(spread, BAND.stroke_width(2)))
            .map_err(err)?
            .label("the lower bob's spread; above: the members' median, their 50 % and 90 % bands (a measurement's)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BAND.stroke_width(2)));
            chart
                .draw_series(DashedLineSeries::new(
                    [(f.t0, marks.tolerance), (marks.until, marks.tolerance)],
                    6,
                    4,
                    BLACK.stroke_width(1),
                ))
                .map_err(err)?
                .label(format!("the tolerance, {:.3} m", marks.tolerance))
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1))
                });
            horizons(&mut chart, &lines, marks.until, low_spread, top_spread)?;
            // What every mark means, once: the legend of all five panels.
            let key = |colour: RGBColor| {
                move |(x, y): (i32, i32)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                }
            };
            for (label, colour) in [
                (marks.horizon.1, SPREAD_HORIZON),
                (marks.on_data.1, DATA_HORIZON),
                ("measured (dots); grey: the fit window", MEASURED),
            ] {
                chart
                    .draw_series(LineSeries::new(Vec::<(f64, f64)>::new(), colour))
                    .map_err(err)?
                    .label(label)
                    .legend(key(colour));
            }
            if marks.truth.is_some() {
                chart
                    .draw_series(LineSeries::new(Vec::<(f64, f64)>::new(), TRUTH))
                    .map_err(err)?
                    .label("the truth (a twin experiment)")
                    .legend(key(TRUTH));
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .label_font(("sans-serif", 13))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .draw()
                .map_err(err)?;
            Ok(())
        },
    )
}

/// The horizons as dashed vertical lines from `lo` to `hi`.
fn horizons<Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<BitMapBackend, Cartesian2d<plotters::coord::types::RangedCoordf64, Y>>,
    lines: &[(Option<f64>, RGBColor)],
    until: f64,
    lo: f64,
    hi: f64,
) -> Result<()> {
    for &(t, colour) in lines {
        if let Some(t) = t.filter(|&t| t <= until) {
            chart
                .draw_series(DashedLineSeries::new(
                    [(t, lo), (t, hi)],
                    6,
                    4,
                    colour.stroke_width(2),
                ))
                .map_err(err)?;
        }
    }
    Ok(())
}

/// The twin experiments' horizons (s after the window) against the noise (log scale), per
/// sampling rate: each experiment, the fitted line, and the line of slope -1/lambda through
/// the same centre (dashed). `series`: (rate, [(sigma, horizon)]).
pub fn twin(
    out: &mut Outputs,
    path: &Path,
    series: &[(f64, Vec<(f64, f64)>)],
    slopes: &[Slope],
) -> Result<()> {
    const COLOURS: [RGBColor; 4] = [BAND, SPREAD_HORIZON, TRUTH, DATA_HORIZON];
    let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.1.iter().copied()).collect();
    let xs = range(all.iter().map(|p| p.0.ln()), 0.1);
    let ys = range(all.iter().map(|p| p.1).chain([0.0]), 0.08);
    plot(
        out,
        path,
        (900, 640),
        &titled("twin experiments: horizon against noise"),
        |root| {
            let mut chart = ChartBuilder::on(root)
                .caption(
                    "twin experiments: horizon against noise (dashed: slope -1/lambda)",
                    ("sans-serif", 18),
                )
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(56)
                .build_cartesian_2d((xs.start.exp()..xs.end.exp()).log_scale(), ys)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("position noise sigma (m)")
                .y_desc("spread horizon after the window (s)")
                .x_label_formatter(&|v| format!("{:.0} mm", v * 1e3))
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(err)?;
            for (i, (rate, points)) in series.iter().enumerate() {
                let colour = COLOURS[i % COLOURS.len()];
                chart
                    .draw_series(
                        points
                            .iter()
                            .map(|&(s, h)| Circle::new((s, h), 3, colour.filled())),
                    )
                    .map_err(err)?
                    .label(format!("{rate} Hz"))
                    .legend(move |(x, y)| Circle::new((x, y), 4, colour.filled()));
                let Some(&Slope {
                    slope: b,
                    minus_one_over_lambda: reference,
                    ..
                }) = slopes.iter().find(|s| s.rate == *rate)
                else {
                    continue;
                };
                if points.len() < 2 || !b.is_finite() {
                    continue;
                }
                let n = points.len() as f64;
                let mx = points.iter().map(|p| p.0.ln()).sum::<f64>() / n;
                let my = points.iter().map(|p| p.1).sum::<f64>() / n;
                let (lo, hi) = (xs.start, xs.end);
                let line = |slope: f64| {
                    [
                        (lo.exp(), my + slope * (lo - mx)),
                        (hi.exp(), my + slope * (hi - mx)),
                    ]
                };
                chart
                    .draw_series(LineSeries::new(line(b), colour.stroke_width(2)))
                    .map_err(err)?;
                if reference.is_finite() {
                    chart
                        .draw_series(DashedLineSeries::new(
                            line(reference),
                            6,
                            4,
                            colour.stroke_width(1),
                        ))
                        .map_err(err)?;
                }
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(err)?;
            Ok(())
        },
    )
}
