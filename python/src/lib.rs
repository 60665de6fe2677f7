//! `chaoscope._chaoscope`: the engine's jobs for the Python package (python/chaoscope/), a
//! second front door beside the command line. Each function takes the keywords of its Python
//! wrapper as one dict (the wrapper's signature refuses unknown keywords), builds the same
//! validated job the command line builds, runs it with the GIL released and Ctrl-C feeding
//! the engine's cancel flag, and hands the arrays to numpy without a copy.

use chaoscope::Error;
use chaoscope::app::MapOutputs;
use chaoscope::app::map::MapJob;
use chaoscope::app::trajectory::TrajectoryJob;
use chaoscope::cli::command_line;
use chaoscope::engine::{Backend, MapKernels};
use chaoscope::field::Field;
use chaoscope::measure::IndicatorAsked;
use chaoscope::model::State;
use chaoscope::render::PictureSpec;
use chaoscope::spec::{FlipMeasure, FlipSpec, Integrator, LyapunovSpec, MapSpec, Method};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod keywords;
mod picture;
mod run;
mod track;
mod tracked;
mod zoom;
use keywords::Keywords;
use run::{engine, engine_in, watched};

/// The Python keyword of a field the library names: the field's own name but where the
/// wrappers take it under another (the Python column beside src/cli/names.rs's flags).
fn keyword(field: &str) -> &str {
    match field {
        "params" => "params_file",
        "colour_by" => "measure",
        "data" => "store",
        "no_symmetry" => "use_symmetry",
        "full" => "early_exit",
        f => f,
    }
}

/// `text` with the settings it names (`chaoscope::error::spell`) as keywords:
/// `precision='f64'`, `t_max=`.
fn spelt(text: &str) -> String {
    chaoscope::error::spell(text, |field, value| match value {
        Some(v) if v.parse::<f64>().is_ok() => format!("{}={v}", keyword(field)),
        Some(v) => format!("{}='{v}'", keyword(field)),
        None => format!("{}=", keyword(field)),
    })
}

/// The library's error as Python's: a bad value is a ValueError naming its keyword (the
/// spec's field), Ctrl-C a KeyboardInterrupt.
pub(crate) fn py_err(e: Error) -> PyErr {
    match e {
        Error::InvalidSpec { field, reason } => {
            PyValueError::new_err(format!("{}: {}", keyword(field), spelt(&reason)))
        }
        Error::StoreDiffers { field, .. } => {
            PyValueError::new_err(format!("{}: {e}", keyword(field)))
        }
        Error::SameFile {
            field,
            other,
            ref path,
            input,
        } => PyValueError::new_err(format!(
            "{}: {} is also the {} file {}",
            keyword(field),
            path.display(),
            keyword(other),
            match input {
                true => "this call reads",
                false => "of this call",
            }
        )),
        Error::Missing { field, path } => PyFileNotFoundError::new_err(format!(
            "{}: {}: no such file",
            keyword(field),
            path.display()
        )),
        Error::Interrupted => PyKeyboardInterrupt::new_err("interrupted"),
        e => PyRuntimeError::new_err(e.to_string()),
    }
}

/// A map's arrays and what describes them: its values (float32, (height, width), row 0 at the
/// top), its verdict (uint8, 1 resolved) when asked, its axes' names, units and pixel centres,
/// the quantity, the reproducing command, the spec (JSON) and where it ran.
fn map_answer<'py, S: MapSpec>(
    py: Python<'py>,
    spec: &S,
    field: Field,
    mask: Option<Vec<u8>>,
    command: String,
    made: (&chaoscope::engine::RunInfo, Vec<String>, String),
) -> PyResult<Bound<'py, PyDict>> {
    let (info, notices, rule) = made;
    let place = info.place().to_string();
    // The PNG's text chunks as the command line writes them (its command is set when a
    // picture is drawn, with the picture's flags): `picture` writes the same bytes.
    let provenance: Vec<(String, String)> = chaoscope::render::provenance(String::new(), info);
    let g = *spec.grid();
    let (h, w) = (g.height as usize, g.width as usize);
    let out = PyDict::new(py);
    out.set_item(
        "values",
        PyArray1::from_vec(py, field.data).reshape([h, w])?,
    )?;
    if let Some(mask) = mask {
        out.set_item("resolved", PyArray1::from_vec(py, mask).reshape([h, w])?)?;
    }
    for (key, axis, values) in [
        (
            "x",
            g.x,
            (0..g.width).map(|c| g.x_at(c)).collect::<Vec<_>>(),
        ),
        ("y", g.y, (0..g.height).map(|r| g.y_at(r)).collect()),
    ] {
        let a = PyDict::new(py);
        a.set_item("name", axis.var.key())?;
        a.set_item("label", axis.var.name())?;
        a.set_item("symbol", axis.var.symbol())?;
        a.set_item("unit", axis.var.unit())?;
        a.set_item("values", PyArray1::from_vec(py, values))?;
        out.set_item(key, a)?;
    }
    let s = g.fixed;
    out.set_item(
        "start",
        [
            ("theta1", s.theta1),
            ("omega1", s.omega1),
            ("theta2", s.theta2),
            ("omega2", s.omega2),
        ]
        .into_py_dict(py)?,
    )?;
    let q = spec.quantity();
    out.set_item("quantity", q.name)?;
    out.set_item("unit", q.unit)?;
    out.set_item("command", command)?;
    out.set_item("place", place)?;
    out.set_item(
        "notices",
        notices.iter().map(|n| spelt(n)).collect::<Vec<_>>(),
    )?;
    out.set_item("png_text", provenance)?;
    out.set_item("rule", rule)?;
    let any =
        serde_json::to_string(&spec.any()).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    out.set_item("spec", any)?;
    Ok(out)
}

use pyo3::types::IntoPyDict;

/// A map job run in memory (`samples`, `resolved` from the keywords): checked as the command
/// line checks it, computed as it computes it; `command_of` writes its command line.
fn run_map<'py, S: MapKernels + chaoscope::render::MapPicture + Copy + Send + Sync + 'static>(
    py: Python<'py>,
    k: &Keywords<'py>,
    spec: S,
    backend: Backend,
    command_of: fn(&MapJob<S>) -> String,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let samples: u32 = k.whole("samples")?.unwrap_or(1);
    let resolved: bool = k.or("resolved", false)?;
    let job = MapJob {
        spec,
        backend,
        picture: PictureSpec::default(),
        files: no_files(),
        tile: None,
        colour_range: None,
        samples,
    };
    if let Some(settings) = k.get::<Bound<'py, PyDict>>("zoom")? {
        // The map is a zoom's first frame: its picture's settings count, its files do not.
        for (given, key) in [
            (resolved, "resolved"),
            (k.get::<std::path::PathBuf>("store")?.is_some(), "store"),
        ] {
            if given {
                return Err(PyValueError::new_err(format!(
                    "{key}: is a map's own; a zoom judges its frames with verdict=True and writes them to output"
                )));
            }
        }
        let colour_range = k
            .pair("colour_range")?
            .map(|(lo, hi)| (lo as f32, hi as f32));
        let job = MapJob {
            colour_range,
            files: MapOutputs {
                show_unresolved: k.or("show_unresolved", false)?,
                ..no_files()
            },
            ..job
        };
        let out = PyDict::new(py);
        out.set_item("zoom", zoom::run(py, settings, job, command_of, progress)?)?;
        return Ok(out);
    }
    let command = command_of(&job);
    if let Some(path) = k.get::<std::path::PathBuf>("store")? {
        return fill_store(py, k, &job, path, resolved, command, progress);
    }
    if k.get::<(i64, i64)>("tile")?.is_some() {
        return Err(PyValueError::new_err(
            "tile: is a share of a map in a store: give store= too (a map in memory is made whole)",
        ));
    }
    chaoscope::app::map::check_in_memory(&spec, resolved, samples).map_err(py_err)?;
    let s = spec;
    let engine = engine(backend)?;
    let made = watched(py, progress, move |monitor| {
        chaoscope::app::map::compute(&s, &engine, resolved, samples, monitor)
    })?;
    let (field, mask) = made.made;
    map_answer(
        py,
        &spec,
        field,
        mask,
        command,
        (&made.info, made.notices, made.rule_in_full),
    )
}

/// A map into a Zarr store, as `--data MAP.zarr` fills it: band by band (memory holds one),
/// resumable, only part `tile` = (index, count) of it when given (tasks of one map on many
/// workers). Returns what was filled; the store is opened lazily by the wrapper.
fn fill_store<'py, S: MapKernels + Copy + Send + Sync + 'static>(
    py: Python<'py>,
    k: &Keywords<'py>,
    job: &MapJob<S>,
    path: std::path::PathBuf,
    resolved: bool,
    command: String,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (spec, backend) = (job.spec, job.backend);
    if job.samples != 1 {
        return Err(PyValueError::new_err(
            "samples: is for maps made in memory; a store is filled band by band at one start a pixel",
        ));
    }
    let tile = k.tile()?;
    let files = MapOutputs {
        output: std::path::PathBuf::from("out.png"),
        data: Some(path.clone()),
        resolved: resolved.then(|| path.clone()),
        show_unresolved: false,
    };
    chaoscope::app::map::validate(&spec, &files, tile).map_err(py_err)?;
    let engine = engine(backend)?;
    let made = watched(py, progress, move |monitor| {
        chaoscope::app::map::make_store(&spec, &engine, &path, command, tile, resolved, monitor)
    })?;
    let f = made.made;
    let out = PyDict::new(py);
    for (key, v) in [
        ("pixels", f.pixels),
        ("counted", f.counted),
        ("nan", f.nan),
        ("resolved", f.resolved),
        ("missing", f.missing),
    ] {
        out.set_item(key, v)?;
    }
    out.set_item("place", made.info.place().to_string())?;
    out.set_item(
        "notices",
        made.notices.iter().map(|n| spelt(n)).collect::<Vec<_>>(),
    )?;
    Ok(out)
}

#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
fn flip_map<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let k = Keywords { dict: keywords };
    let backend = k.backend()?;
    let precision = k.precision()?;
    let accurate: bool = k.or("accurate", false)?;
    let measures: Vec<&str> = FlipMeasure::ALL.iter().map(|m| m.name()).collect();
    let measure = match k.choice("measure", &measures)? {
        None => FlipMeasure::Time,
        Some(n) => *FlipMeasure::ALL
            .iter()
            .find(|m| m.name() == n)
            .expect("listed"),
    };
    let integrator = k.or("integrator", "rk4".to_string())?;
    let gpu_f32 = engine(backend)?.computes_in_f32(precision);
    let asked = k.stepping_asked(&integrator, precision, accurate, gpu_f32)?;
    let grid = k.grid()?;
    let params = chaoscope::spec::resolve_on(&k.sources()?, &grid).map_err(py_err)?;
    let spec = asked
        .flip(FlipSpec {
            measure,
            early_exit: k.or("early_exit", true)?,
            use_symmetry: k.or("use_symmetry", true)?,
            ..FlipSpec::new(params, grid, k.stepping(30.0)?)
        })
        .map_err(py_err)?;
    run_map(py, &k, spec, backend, command_line::flip, progress)
}

#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
fn lyapunov_map<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let k = Keywords { dict: keywords };
    let backend = k.backend()?;
    let precision = k.precision()?;
    let accurate: bool = k.or("accurate", false)?;
    let gpu_f32 = engine(backend)?.computes_in_f32(precision);
    let options = k.indicator_options()?;
    let indicator = IndicatorAsked {
        name: &k.or("indicator", "ftle".to_string())?,
        options: &options,
        accurate,
        gpu_f32,
    }
    .indicator()
    .map_err(py_err)?;
    // eps is the twin's distance; a value no twin could take is refused with either method,
    // not ignored.
    let eps: f64 = k.or("eps", 1e-8)?;
    if !(eps.is_finite() && eps > 0.0) {
        return Err(PyValueError::new_err(format!(
            "eps: {eps} must be a finite distance > 0"
        )));
    }
    let method = match k.choice("method", &["tangent", "twin"])?.as_deref() {
        Some("twin") => Method::Twin { eps },
        _ => Method::Tangent,
    };
    let integrator = k.or("integrator", "rk4".to_string())?;
    let asked = k.stepping_asked(&integrator, precision, accurate, gpu_f32)?;
    let grid = k.grid()?;
    let spec = asked.lyapunov(LyapunovSpec {
        params: chaoscope::spec::resolve_on(&k.sources()?, &grid).map_err(py_err)?,
        grid,
        stepping: k.stepping(20.0)?,
        method,
        renorm: k.or("renorm", 0.1)?,
        use_symmetry: k.or("use_symmetry", true)?,
        precision,
        band: None,
        integrator: Integrator::Rk4,
        indicator,
    });
    let spec = spec.map_err(py_err)?;
    run_map(py, &k, spec, backend, command_line::lyapunov_map, progress)
}

/// A job made in memory writes no file: the command names none.
fn no_files() -> MapOutputs {
    MapOutputs {
        output: std::path::PathBuf::from("out.png"),
        data: None,
        resolved: None,
        show_unresolved: false,
    }
}

/// One start's trajectory as `chaoscope trajectory` writes it: the CSV's text (its first line
/// the reproducing command).
#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
fn trajectory<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<String> {
    let k = Keywords { dict: keywords };
    let stepping = k.stepping(20.0)?;
    // `at`: a parameter plane's pixel, {axis name: value}, as `trajectory --at` takes it.
    let at = k
        .get::<std::collections::BTreeMap<String, f64>>("at")?
        .unwrap_or_default()
        .into_iter()
        .map(|(name, v)| {
            chaoscope::spec::Var::parse(&name)
                .map(|var| (var, v))
                .ok_or_else(|| PyValueError::new_err(format!("at: {name:?} is no map axis")))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let job = TrajectoryJob {
        params: chaoscope::spec::resolve_at(&k.sources()?, &at).map_err(py_err)?,
        start: State {
            theta1: k.or("theta1", 0.0)?,
            omega1: k.or("omega1", 0.0)?,
            theta2: k.or("theta2", 0.0)?,
            omega2: k.or("omega2", 0.0)?,
        },
        stepping,
        every: k.get("every")?,
        backend: k.backend()?,
        precision: k.precision()?,
        output: None,
    };
    let command = command_line::trajectory(&job);
    let engine = engine_in(job.backend, job.precision)?;
    let csv = watched(py, progress, move |monitor| {
        let mut csv = Vec::new();
        chaoscope::app::trajectory::run(
            &job,
            &chaoscope::app::Running::new(&engine, command, monitor),
            &mut csv,
        )?;
        Ok(csv)
    })?;
    String::from_utf8(csv).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// Light trails of releases from "the same" start (`chaoscope traces`'s job): the picture
/// written to `output`, the runs' positions as float32 .npy to `data`; the summary as JSON.
#[pyfunction]
#[pyo3(signature = (keywords, progress=None))]
fn traces<'py>(
    py: Python<'py>,
    keywords: Bound<'py, PyDict>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<String> {
    let k = Keywords { dict: keywords };
    // A spread in radians (a number) or with a unit ("5mm"), as --spread takes it.
    let spread = match k.get::<String>("spread") {
        Ok(Some(text)) => chaoscope::cli::parse::parse_spread(&text)
            .map_err(|e| PyValueError::new_err(format!("spread: {e}")))?,
        _ => chaoscope::spec::Spread::Radians(k.or("spread", 0.01)?),
    };
    let job = chaoscope::app::traces::TracesJob {
        params: k.sources()?.resolve().map_err(py_err)?,
        start: State {
            theta1: k.or("theta1", 0.0)?,
            omega1: k.or("omega1", 0.0)?,
            theta2: k.or("theta2", 0.0)?,
            omega2: k.or("omega2", 0.0)?,
        },
        runs: k.whole("runs")?.unwrap_or(3),
        spread,
        stepping: chaoscope::spec::Stepping {
            dt: k.or("dt", 0.001)?,
            t_max: k.or("exposure", 3.2)?,
        },
        size: k.whole("size")?.unwrap_or(1024),
        backend: k.backend()?,
        precision: k.precision()?,
        output: k.or("output", std::path::PathBuf::from("out/traces.png"))?,
        film: None,
        data: k.get("data")?,
    };
    let command = command_line::traces(&job);
    let engine = engine_in(job.backend, job.precision)?;
    let summary = watched(py, progress, move |monitor| {
        chaoscope::app::traces::run(
            &job,
            &chaoscope::app::Running::new(&engine, command.clone(), monitor),
        )
        .map(|s| (s, command))
        .map_err(|e| e.renamed("t_max", "exposure"))
    })?;
    let mut value =
        serde_json::to_value(&summary.0).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    value["command"] = summary.1.into();
    Ok(value.to_string())
}

/// The physics the keywords give (a preset or file, then the values given), resolved and
/// checked: every value by the name the map functions take it under.
#[pyfunction]
fn params<'py>(py: Python<'py>, keywords: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let k = Keywords { dict: keywords };
    let p = k.sources()?.resolve().map_err(py_err)?;
    chaoscope::spec::validate_params(&p).map_err(py_err)?;
    let l = p.losses;
    let out = PyDict::new(py);
    for (key, v) in [
        ("m1", p.m1),
        ("m2", p.m2),
        ("l1", p.l1),
        ("l2", p.l2),
        ("g", p.g),
    ] {
        out.set_item(key, v)?;
    }
    out.set_item("rod_mass", (p.rod1, p.rod2))?;
    out.set_item("joint_damping", (l.joint1, l.joint2))?;
    out.set_item("air_drag", l.has_drag())?;
    if l.has_drag() {
        out.set_item("rho", l.rho)?;
        out.set_item("cw", l.cw)?;
        out.set_item("drag_area", (l.bob_area1, l.bob_area2))?;
        out.set_item("rod_drag_area", (l.rod_area1, l.rod_area2))?;
    }
    if l.has_bearings() {
        out.set_item("bearing_friction", l.bearing)?;
        out.set_item("bearing_radius", l.bearing_radius)?;
    }
    Ok(out)
}

/// The command line, as the `chaoscope` program runs it (the wheel's console script): its
/// exit status.
#[pyfunction]
fn main(py: Python<'_>, args: Vec<String>) -> u8 {
    py.detach(|| chaoscope::cli::main(args))
}

#[pymodule]
fn _chaoscope(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("INDICATORS", chaoscope::measure::names())?;
    m.add(
        "INDICATOR_OPTIONS",
        chaoscope::measure::options()
            .iter()
            .map(|o| o.field)
            .collect::<Vec<_>>(),
    )?;
    m.add_function(wrap_pyfunction!(flip_map, m)?)?;
    m.add_function(wrap_pyfunction!(lyapunov_map, m)?)?;
    m.add_function(wrap_pyfunction!(trajectory, m)?)?;
    m.add_function(wrap_pyfunction!(picture::picture, m)?)?;
    m.add_function(wrap_pyfunction!(params, m)?)?;
    m.add_function(wrap_pyfunction!(tracked::fit, m)?)?;
    m.add_function(wrap_pyfunction!(tracked::forecast, m)?)?;
    m.add_function(wrap_pyfunction!(traces, m)?)?;
    m.add_function(wrap_pyfunction!(track::track, m)?)?;
    m.add_function(wrap_pyfunction!(zoom::png_rgb, m)?)?;
    m.add_function(wrap_pyfunction!(main, m)?)?;
    Ok(())
}
