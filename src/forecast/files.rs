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

/// The file beside a forecast's bands that holds its pendulum: `tracked`'s model (learned
/// from the rows up to the window's end, or given), for maps and pages of it (`--params`).
pub const MODEL_FILE: &str = "model.toml";

/// The forecast's pendulum as a parameter file any `--params` reads.
pub fn write_model(
    files: &mut Outputs,
    path: &std::path::Path,
    tracked: &crate::fit::pendulum::Tracked,
    command: &str,
) -> Result<()> {
    let heading = format!(
        "The pendulum `chaoscope forecast` ran ({}), learned from the rows up to its window's end (or given):\n{command}\nRead it back as a parameter file (the maps, trajectory, web).",
        tracked.source.describe()
    );
    let text = crate::fit::model_toml::model_file(&tracked.params, &tracked.source, &heading, None);
    files.write(path, |w| Ok(std::io::Write::write_all(w, text.as_bytes())?))
}
