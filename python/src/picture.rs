//! `picture`: a map's PNG as the command line writes it, byte for byte.

use chaoscope::cli::command_line;
use chaoscope::field::Field;
use chaoscope::render::{MapPicture, PictureSpec};
use chaoscope::spec::{AnyMap, MapSpec};
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::py_err;

/// A map's picture as the command line draws it (PNG bytes): `spec` (the map's JSON),
/// its values and verdict, the colour map, the annotation, the colour range.
#[pyfunction]
#[pyo3(signature = (spec, values, resolved, command, png_text, rule, colormap=None, annotate=false, colour_range=None, show_unresolved=false))]
#[allow(clippy::too_many_arguments)]
pub fn picture<'py>(
    py: Python<'py>,
    spec: &str,
    values: PyReadonlyArray2<'py, f32>,
    resolved: Option<PyReadonlyArray2<'py, u8>>,
    command: String,
    png_text: Vec<(String, String)>,
    rule: String,
    colormap: Option<String>,
    annotate: bool,
    colour_range: Option<(f32, f32)>,
    show_unresolved: bool,
) -> PyResult<Bound<'py, PyBytes>> {
    let map: AnyMap =
        serde_json::from_str(spec).map_err(|e| PyValueError::new_err(format!("spec: {e}")))?;
    let colormap = match colormap {
        None => None,
        Some(name) => Some(
            chaoscope::render::Colormap::ALL
                .into_iter()
                .find(|c| c.name() == name)
                .ok_or_else(|| PyValueError::new_err(format!("colormap: {name:?} is unknown")))?,
        ),
    };
    let pic = PictureSpec { annotate, colormap };
    let g = *map.grid();
    let shape = [g.height as usize, g.width as usize];
    if values.shape() != shape {
        return Err(PyValueError::new_err(format!(
            "values: shape {:?} for a {} x {} map",
            values.shape(),
            g.width,
            g.height
        )));
    }
    let field = Field {
        width: g.width,
        height: g.height,
        data: values.as_array().iter().copied().collect(),
    };
    let resolved: Option<Vec<u8>> = resolved
        .filter(|r| r.shape() == shape)
        .map(|r| r.as_array().iter().copied().collect());
    let shown = resolved.as_deref().filter(|_| show_unresolved);
    let drawn = match &map {
        AnyMap::Flip(s) => s
            .check_picture(&pic, colour_range)
            .and_then(|()| s.draw(&field, &pic, colour_range, shown)),
        AnyMap::Lyapunov(s) => s
            .check_picture(&pic, colour_range)
            .and_then(|()| s.draw(&field, &pic, colour_range, shown)),
    }
    .map_err(py_err)?;
    // The PNG's chunks as the command line writes them: its provenance with the command
    // that draws this picture, where the map sits, the picture's own, the verdict's rule.
    let command = picture_command(&command, pic, colour_range, shown.is_some())?;
    let mut text: Vec<(String, String)> = png_text
        .into_iter()
        .map(|(k, v)| match k.as_str() {
            "chaoscope:command" => (k, command.clone()),
            _ => (k, v),
        })
        .collect();
    text.extend(drawn.picture.metadata());
    text.extend(drawn.text);
    if shown.is_some() {
        text.push(("chaoscope:resolved-rule".into(), rule));
    }
    let p = drawn.picture;
    let png = chaoscope::render::png_bytes(p.width, p.height, &p.rgb, &text).map_err(py_err)?;
    Ok(PyBytes::new(py, &png))
}

/// The command line that draws a map's picture: the map's `command` (parsed back into its
/// job, as a stored command is) with the picture's flags.
fn picture_command(
    command: &str,
    pic: PictureSpec,
    colour_range: Option<(f32, f32)>,
    show_unresolved: bool,
) -> PyResult<String> {
    use chaoscope::cli::{Cli, Job, LyapunovJob};
    let bad = |e: String| PyValueError::new_err(format!("command: {e}"));
    let cli = Cli::parse_args(command.split_whitespace()).map_err(|e| bad(e.to_string()))?;
    match cli.command.job().map_err(|e| bad(e.to_string()))? {
        Some(Job::Flip(mut job)) => {
            job.picture = pic;
            job.files.show_unresolved = show_unresolved;
            Ok(command_line::flip(&job))
        }
        Some(Job::Lyapunov(LyapunovJob::Map(mut job))) => {
            job.picture = pic;
            job.colour_range = colour_range;
            job.files.show_unresolved = show_unresolved;
            Ok(command_line::lyapunov_map(&job))
        }
        _ => Err(bad(format!("{command:?} is not a map's command"))),
    }
}
