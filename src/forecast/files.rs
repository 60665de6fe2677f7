//! A forecast's files beside its pictures: the bands as CSV.

use super::ensemble::{Forecast, QUANTILES};
use crate::error::Result;
use crate::render::Outputs;

/// The bands as CSV: per coordinate the model's quantiles and a measurement's, the lower
/// bob's spread and the FTLE.
pub fn write_bands(
    files: &mut Outputs,
    path: &std::path::Path,
    f: &Forecast,
    command: &str,
) -> Result<()> {
    files.write(path, |w| {
        use std::io::Write;
        writeln!(w, "# {command}")?;
        writeln!(
            w,
            "# quantiles {QUANTILES:?} of the members' positions (m) and of a measurement's (obs: with the tracking error); spread_lower (m): RMS distance of the lower bob from the members' mean; ftle (1/s) along the fitted orbit from the window's end"
        )?;
        let mut header = vec!["t".to_string()];
        for c in ["x1", "y1", "x2", "y2"] {
            for kind in ["", "obs_"] {
                for q in ["p05", "p25", "median", "p75", "p95"] {
                    header.push(format!("{c}_{kind}{q}"));
                }
            }
        }
        header.extend(["spread_lower".into(), "ftle".into()]);
        writeln!(w, "{}", header.join(","))?;
        for (j, &t) in f.times.iter().enumerate() {
            let mut row = vec![format!("{t}")];
            for c in 0..4 {
                for band in [&f.model[j][c], &f.observed[j][c]] {
                    row.extend(band.iter().map(|v| format!("{v}")));
                }
            }
            row.push(format!("{}", f.spread[j]));
            row.push(format!("{}", f.ftle[j]));
            writeln!(w, "{}", row.join(","))?;
        }
        Ok(())
    })
}
