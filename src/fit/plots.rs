//! The fit's plots (plotters on an RGB buffer, written atomically as PNG).

use std::path::Path;

use plotters::prelude::*;

use crate::error::Result;
use crate::render::Outputs;
use crate::render::chart::{err, plot, range, time_grid, titled};

pub(crate) const MEASURED: RGBColor = RGBColor(30, 30, 30);
const SIMULATED: RGBColor = RGBColor(214, 39, 40);
const FIT_A: RGBColor = RGBColor(31, 119, 180);
const FIT_B: RGBColor = RGBColor(44, 160, 44);

/// Measured (dots) and simulated (line) x1, y1, x2, y2 over time up to `t_end`, one panel
/// each.
pub fn positions(
    out: &mut Outputs,
    path: &Path,
    t: &[f64],
    measured: &[[f64; 4]],
    simulated: &[(f64, [f64; 4])],
    t0: f64,
    t_end: f64,
) -> Result<()> {
    let n = t.iter().take_while(|&&x| x <= t_end).count();
    let (t, measured) = (&t[..n], &measured[..n]);
    let last = t.last().copied().unwrap_or(t_end);
    let simulated: Vec<(f64, [f64; 4])> =
        simulated.iter().copied().filter(|s| s.0 <= last).collect();
    plot(
        out,
        path,
        (1200, 800),
        &titled("measured and simulated positions"),
        |root| {
            let panels = root.split_evenly((2, 2));
            let names = ["x1 (m)", "y1 (m)", "x2 (m)", "y2 (m)"];
            for (k, area) in panels.iter().enumerate() {
                let yr = range(
                    measured
                        .iter()
                        .map(|m| m[k])
                        .chain(simulated.iter().map(|s| s.1[k])),
                    0.08,
                );
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!(
                            "{} — measured (dots), model fitted at t = {t0} s (line)",
                            names[k]
                        ),
                        ("sans-serif", 16),
                    )
                    .margin(10)
                    .x_label_area_size(30)
                    .y_label_area_size(50)
                    .build_cartesian_2d(range(t.iter().copied(), 0.02), yr)
                    .map_err(err)?;
                time_grid(&mut chart)?;
                chart
                    .draw_series(
                        t.iter()
                            .zip(measured)
                            .map(|(&x, m)| Circle::new((x, m[k]), 3, MEASURED.filled())),
                    )
                    .map_err(err)?;
                chart
                    .draw_series(LineSeries::new(
                        simulated.iter().map(|s| (s.0, s.1[k])),
                        SIMULATED.stroke_width(2),
                    ))
                    .map_err(err)?;
            }
            Ok(())
        },
    )
}

/// Energy with error bars and both decay fits.
pub fn energy(
    out: &mut Outputs,
    path: &Path,
    energies: &super::Energies,
    exponential: (f64, f64),
    inverse_square: (f64, f64),
    unit: EnergyUnit,
) -> Result<()> {
    // The rows with an energy (none beside a gap in the rows).
    let kept = |v: &[f64]| -> Vec<f64> {
        (0..energies.t.len())
            .filter(|&i| energies.e[i].is_finite() && energies.de[i].is_finite())
            .map(|i| v[i])
            .collect()
    };
    let (t, e, de) = (&kept(&energies.t), &kept(&energies.e), &kept(&energies.de));
    let u = unit.symbol();
    plot(
        out,
        path,
        (1000, 650),
        &titled("energy and decay fits"),
        |root| {
            let yr = range(e.iter().zip(de).flat_map(|(v, d)| [v - d, v + d]), 0.05);
            let xr = range(t.iter().copied(), 0.02);
            let mut chart = ChartBuilder::on(root)
                .caption(
                    format!(
                        "Tracked energy ({}), error bars, two decay laws",
                        unit.name()
                    ),
                    ("sans-serif", 20),
                )
                .margin(15)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(xr.clone(), yr)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("t (s)")
                .y_desc(unit.axis())
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(err)?;
            chart
                .draw_series(t.iter().zip(e).zip(de).map(|((&x, &y), &d)| {
                    ErrorBar::new_vertical(x, y - d, y, y + d, MEASURED.filled(), 6)
                }))
                .map_err(err)?;
            let curve = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
                (0..=300)
                    .map(|i| {
                        let x = xr.start + (xr.end - xr.start) * i as f64 / 300.0;
                        (x, f(x))
                    })
                    .collect()
            };
            let (a, b) = exponential;
            chart
                .draw_series(LineSeries::new(
                    curve(&|x| a * (b * x).exp()),
                    FIT_A.stroke_width(2),
                ))
                .map_err(err)?
                .label(format!("a exp(b t): a = {a:.3} {u}, b = {b:.4} 1/s"))
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], FIT_A.stroke_width(2))
                });
            let (a2, b2) = inverse_square;
            chart
                .draw_series(LineSeries::new(
                    curve(&|x| a2 * (b2 * x + 1.0).powi(-2)),
                    FIT_B.stroke_width(2),
                ))
                .map_err(err)?
                .label(format!("a (b t + 1)^-2: a = {a2:.3} {u}, b = {b2:.4} 1/s"))
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], FIT_B.stroke_width(2))
                });
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(180, 180, 180))
                .draw()
                .map_err(err)?;
            Ok(())
        },
    )
}

/// The unit of an energy plot: joules (a model with masses given), or the upper arm's
/// gravity moment P (a model found from the motion, which cannot see the masses' scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EnergyUnit {
    Joule,
    GravityMoment,
}

impl EnergyUnit {
    fn symbol(self) -> &'static str {
        match self {
            EnergyUnit::Joule => "J",
            EnergyUnit::GravityMoment => "P",
        }
    }

    fn name(self) -> &'static str {
        match self {
            EnergyUnit::Joule => "J",
            EnergyUnit::GravityMoment => "over P, the upper arm's gravity moment",
        }
    }

    fn axis(self) -> &'static str {
        match self {
            EnergyUnit::Joule => "E (J)",
            EnergyUnit::GravityMoment => "E / P",
        }
    }
}

/// How often rows come, as a title says it: "every 1/3 s", "400 times a second".
pub fn cadence(t: &[f64]) -> String {
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        return "once".into();
    }
    let mid = steps.len() / 2;
    let step = *steps.select_nth_unstable_by(mid, f64::total_cmp).1;
    // Three significant figures, no trailing zeros.
    let figures = |x: f64| {
        let decimals = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        let text = format!("{x:.decimals$}");
        match text.contains('.') {
            true => text.trim_end_matches('0').trim_end_matches('.').to_string(),
            false => text,
        }
    };
    match 1.0 / step {
        r if r >= 1.5 => format!("{} times a second", figures(r)),
        _ => format!("every {} s", figures(step)),
    }
}

/// omega against theta for both arms, as measured (central differences), `cadence` as
/// [`cadence`] says it.
pub fn phase(
    out: &mut Outputs,
    path: &Path,
    arms: [&[(f64, f64)]; 2],
    cadence: &str,
) -> Result<()> {
    plot(
        out,
        path,
        (1200, 550),
        &titled("measured phase portraits"),
        |root| {
            let panels = root.split_evenly((1, 2));
            for (k, area) in panels.iter().enumerate() {
                let pts = arms[k];
                let mut chart = ChartBuilder::on(area)
                    .caption(
                        format!(
                            "Arm {}: ω{} (rad/s) against θ{} (rad), measured {cadence}",
                            k + 1,
                            k + 1,
                            k + 1
                        ),
                        ("sans-serif", 18),
                    )
                    .margin(12)
                    .x_label_area_size(35)
                    .y_label_area_size(50)
                    .build_cartesian_2d(
                        range(pts.iter().map(|p| p.0), 0.05),
                        range(pts.iter().map(|p| p.1), 0.05),
                    )
                    .map_err(err)?;
                chart
                    .configure_mesh()
                    .x_desc(format!("θ{} (rad)", k + 1))
                    .y_desc(format!("ω{} (rad/s)", k + 1))
                    .light_line_style(RGBColor(235, 235, 235))
                    .draw()
                    .map_err(err)?;
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, FIT_A.filled())))
                    .map_err(err)?;
            }
            Ok(())
        },
    )
}
