//! The keywords of a call from the Python wrappers: typed, each error naming its keyword
//! (TypeError for a wrong type, ValueError for a bad value), and the specs' parts built from
//! them by the library's own askers.

use chaoscope::engine::Backend;
use chaoscope::params::{ParamSources, Preset};
use chaoscope::spec::{
    Angles, AxisAsked, Grid, PlaneAsked, Precision, Range, Stepping, SteppingAsked, Var,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};

use crate::py_err;

/// The keywords of one call.
pub struct Keywords<'py> {
    pub dict: Bound<'py, PyDict>,
}

impl<'py> Keywords<'py> {
    /// `key`'s value, None when absent or None; a value of the wrong type is a TypeError
    /// naming the keyword.
    pub fn get<T: for<'a> FromPyObject<'a, 'py>>(&self, key: &str) -> PyResult<Option<T>> {
        match self.dict.get_item(key)? {
            None => Ok(None),
            Some(v) if v.is_none() => Ok(None),
            // Python's bool is an int: size=True would be read as 1.
            Some(v) if v.is_instance_of::<PyBool>() && std::any::type_name::<T>() != "bool" => Err(
                PyTypeError::new_err(format!("{key}: True or False where a value is wanted")),
            ),
            Some(v) => v.extract::<T>().map(Some).map_err(|e| {
                let e: PyErr = e.into();
                PyTypeError::new_err(format!("{key}: {}", e.value(self.dict.py())))
            }),
        }
    }

    /// A tracked file's units: `pixels_per_metre` (a number, or "motion"), `frame_rate`,
    /// `before_release` and `y_up`.
    pub fn units(&self) -> PyResult<chaoscope::fit::data::Units> {
        use chaoscope::fit::data::PixelScale;
        let pixels_per_metre = match self.get::<String>("pixels_per_metre") {
            Ok(Some(text)) if text.trim() == "motion" => Some(PixelScale::FromMotion),
            Ok(Some(text)) => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "pixels_per_metre: {text:?} is neither a number nor \"motion\" (the scale from the swing)"
                )));
            }
            _ => self
                .get::<f64>("pixels_per_metre")?
                .map(PixelScale::PerMetre),
        };
        Ok(chaoscope::fit::data::Units {
            pixels_per_metre,
            frame_rate: self.get("frame_rate")?,
            before_release: self.or("before_release", false)?,
            y_up: self.or("y_up", false)?,
        })
    }

    pub fn or<T: for<'a> FromPyObject<'a, 'py>>(&self, key: &str, default: T) -> PyResult<T> {
        Ok(self.get(key)?.unwrap_or(default))
    }

    /// One of `names` (a string), None when absent.
    pub fn choice(&self, key: &'static str, names: &[&str]) -> PyResult<Option<String>> {
        let Some(v) = self.get::<String>(key)? else {
            return Ok(None);
        };
        if !names.contains(&v.as_str()) {
            return Err(PyValueError::new_err(format!(
                "{key}: {v:?} is not one of {}",
                names.join(", ")
            )));
        }
        Ok(Some(v))
    }

    /// A (low, high) pair as a range.
    /// A range (low, high), checked here so that its error names this keyword (the
    /// library's checks name the quantity along the axis).
    pub fn range(&self, key: &str) -> PyResult<Option<Range>> {
        match self.get::<(f64, f64)>(key)? {
            Some((min, max)) if !(min.is_finite() && max.is_finite() && min < max) => {
                Err(PyValueError::new_err(format!(
                    "{key}: ({min}, {max}) must be (low, high) with low < high, both finite"
                )))
            }
            r => Ok(r.map(|(min, max)| Range { min, max })),
        }
    }

    /// An angle: one number (a start) or a (low, high) pair (a range along an axis).
    pub fn angles(&self, key: &str) -> PyResult<Option<Angles>> {
        match self.dict.get_item(key)? {
            None => Ok(None),
            Some(v) if v.is_none() => Ok(None),
            Some(v) => match (v.extract::<f64>(), v.extract::<(f64, f64)>()) {
                (Ok(x), _) => Ok(Some(Angles::Point(x))),
                (_, Ok((min, max))) => Ok(Some(Angles::Range(Range { min, max }))),
                _ => Err(PyTypeError::new_err(format!(
                    "{key}: a number (the start's, rad) or a pair (low, high) (a range along an axis), not {}",
                    v.get_type().name()?
                ))),
            },
        }
    }

    /// A value for two things at once: one number for both, or a pair.
    pub fn pair(&self, key: &str) -> PyResult<Option<(f64, f64)>> {
        match self.dict.get_item(key)? {
            None => Ok(None),
            Some(v) if v.is_none() => Ok(None),
            Some(v) => match v.extract::<f64>() {
                Ok(x) => Ok(Some((x, x))),
                Err(_) => self.get::<(f64, f64)>(key),
            },
        }
    }

    /// A whole number that fits `T`; a negative or huge one is a ValueError naming the
    /// keyword (the library checks the allowed range after).
    /// `tile=(index, count)`: whole numbers >= 0 (their range is the job's to check).
    pub fn tile(&self) -> PyResult<Option<(u32, u32)>> {
        match self.get::<(i64, i64)>("tile")? {
            None => Ok(None),
            Some((i, n)) => match (u32::try_from(i), u32::try_from(n)) {
                (Ok(i), Ok(n)) => Ok(Some((i, n))),
                _ => Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "tile: ({i}, {n}) must be (index, count), whole numbers >= 0"
                ))),
            },
        }
    }

    /// The indicators' options given, each as the measures declare it
    /// (`chaoscope::measure::options`): a whole number in its range, or any number.
    pub fn indicator_options(&self) -> PyResult<Vec<(&'static str, f64)>> {
        let mut given = Vec::new();
        for o in chaoscope::measure::options() {
            let value = match o.whole {
                Some((low, high)) => match self.get::<i64>(o.field)? {
                    Some(n) if (i64::from(low)..=i64::from(high)).contains(&n) => Some(n as f64),
                    Some(n) => {
                        return Err(PyValueError::new_err(format!(
                            "{}: {n} must be a whole number from {low} to {high}",
                            o.field
                        )));
                    }
                    None => None,
                },
                None => self.get::<f64>(o.field)?,
            };
            given.extend(value.map(|v| (o.field, v)));
        }
        Ok(given)
    }

    pub fn whole<T: TryFrom<i64>>(&self, key: &str) -> PyResult<Option<T>> {
        let Some(n) = self.get::<i64>(key)? else {
            return Ok(None);
        };
        T::try_from(n).map(Some).map_err(|_| {
            PyValueError::new_err(format!("{key}: {n} is out of range (a whole number >= 0)"))
        })
    }

    /// N (square) or (width, height) pixels.
    pub fn size(&self) -> PyResult<(u32, u32)> {
        let whole = |n: i64| {
            u32::try_from(n).map_err(|_| {
                PyValueError::new_err(format!("size: {n} is out of range (pixels, >= 1)"))
            })
        };
        match self.dict.get_item("size")? {
            Some(v) if v.is_instance_of::<PyBool>() => Err(PyTypeError::new_err(
                "size: True or False where N or (width, height) is wanted",
            )),
            Some(v) if !v.is_none() => match (v.extract::<i64>(), v.extract::<(i64, i64)>()) {
                (Ok(n), _) => Ok((whole(n)?, whole(n)?)),
                (_, Ok((w, h))) => Ok((whole(w)?, whole(h)?)),
                _ => Err(PyTypeError::new_err(format!(
                    "size: N or (width, height), not {}",
                    v.get_type().name()?
                ))),
            },
            _ => Ok((512, 512)),
        }
    }

    pub fn backend(&self) -> PyResult<Backend> {
        let names: Vec<&str> = Backend::ALL.iter().map(|b| b.name()).collect();
        Ok(match self.choice("backend", &names)? {
            None => Backend::Auto,
            Some(n) => *Backend::ALL.iter().find(|b| b.name() == n).expect("listed"),
        })
    }

    pub fn precision(&self) -> PyResult<Precision> {
        let names: Vec<&str> = Precision::ALL.iter().map(|p| p.name()).collect();
        Ok(match self.choice("precision", &names)? {
            None => Precision::default(),
            Some(n) => *Precision::ALL
                .iter()
                .find(|p| p.name() == n)
                .expect("listed"),
        })
    }

    /// The physics: a preset or file and the values given (the command line's sources).
    pub fn sources(&self) -> PyResult<ParamSources> {
        let names: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
        let preset = self
            .choice("preset", &names)?
            .map(|n| *Preset::ALL.iter().find(|p| p.name() == n).expect("listed"));
        Ok(ParamSources {
            m1: self.get("m1")?,
            m2: self.get("m2")?,
            l1: self.get("l1")?,
            l2: self.get("l2")?,
            g: self.get("g")?,
            rod_mass: self.pair("rod_mass")?,
            joint_damping: self.pair("joint_damping")?,
            air_drag: self.or("air_drag", false)?,
            rho: self.get("rho")?,
            cw: self.get("cw")?,
            drag_area: self.pair("drag_area")?,
            rod_drag_area: self.pair("rod_drag_area")?,
            bearing_friction: self.get("bearing_friction")?,
            bearing_radius: self.get("bearing_radius")?,
            preset,
            params: self.get::<std::path::PathBuf>("params_file")?,
        })
    }

    /// The plane: `x`, `y` (names as `--x`/`--y` take them) with `x_range`, `y_range`, and
    /// the start's angles (a range along an axis, else a value) and angular velocities.
    pub fn grid(&self) -> PyResult<Grid> {
        let names: Vec<&str> = Var::ALL.iter().map(|v| v.name()).collect();
        let axis = |key: &'static str, range: &str| -> PyResult<Option<AxisAsked>> {
            let var = self.choice(key, &names)?;
            let range = self.range(range)?;
            Ok(match (var, range) {
                (None, None) => None,
                (var, range) => Some(AxisAsked {
                    var: Var::parse(var.as_deref().unwrap_or(if key == "x" {
                        "theta1"
                    } else {
                        "theta2"
                    }))
                    .expect("listed"),
                    range,
                }),
            })
        };
        PlaneAsked {
            x: axis("x", "x_range")?,
            y: axis("y", "y_range")?,
            theta1: self.angles("theta1")?,
            theta2: self.angles("theta2")?,
            omega1: self.get("omega1")?,
            omega2: self.get("omega2")?,
        }
        .grid(self.size()?)
        .map_err(py_err)
    }

    /// How the keywords ask for a map to be stepped: `integrator` (the keyword's value) with
    /// `rtol` and `atol`, in `precision`, or `accurate`'s settings.
    pub fn stepping_asked<'a>(
        &self,
        integrator: &'a str,
        precision: Precision,
        accurate: bool,
        gpu_f32: bool,
    ) -> PyResult<SteppingAsked<'a>> {
        Ok(SteppingAsked {
            precision,
            integrator,
            rtol: self.get("rtol")?,
            atol: self.get("atol")?,
            accurate,
            gpu_f32,
        })
    }

    pub fn stepping(&self, t_max: f64) -> PyResult<Stepping> {
        Ok(Stepping {
            dt: self.or("dt", 0.01)?,
            t_max: self.or("t_max", t_max)?,
        })
    }
}
