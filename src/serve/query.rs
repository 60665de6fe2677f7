//! A view's query string: its values by key, each read at most once and checked as it is
//! read, and the keys there are.

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::render::Colormap;
use crate::spec::{Integrator, Precision, integrator_of};

/// A query string's values by key, each key read at most once; keys nobody read are
/// refused ([`Query::finish`]), so a misspelt key is an error, not a silent default.
pub struct Query {
    pub(super) values: HashMap<String, String>,
}

impl Query {
    /// The query's pairs, each key once: a repeated key (`size=16&size=512`) is refused
    /// naming it, rather than one of its values being taken silently.
    pub fn new(pairs: Vec<(String, String)>) -> Result<Self> {
        let mut values = HashMap::with_capacity(pairs.len());
        for (key, value) in pairs {
            if values.contains_key(&key) {
                let key = known(&key).unwrap_or("query");
                return Err(Error::invalid(key, "is given more than once"));
            }
            values.insert(key, value);
        }
        Ok(Query { values })
    }

    pub(super) fn take(&mut self, key: &'static str) -> Option<String> {
        self.values.remove(key)
    }

    /// A finite number, if given.
    pub fn number(&mut self, key: &'static str) -> Result<Option<f64>> {
        self.take(key)
            .map(|s| match s.trim().parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(Error::invalid(key, format!("{s:?} is not a finite number"))),
            })
            .transpose()
    }

    /// A number within [lo, hi], if given.
    pub fn within(&mut self, key: &'static str, lo: f64, hi: f64) -> Result<Option<f64>> {
        let v = self.number(key)?;
        if let Some(v) = v
            && !(lo..=hi).contains(&v)
        {
            return Err(Error::invalid(key, format!("{v} must be in [{lo}, {hi}]")));
        }
        Ok(v)
    }

    /// A whole number within [lo, hi], if given.
    pub fn count(&mut self, key: &'static str, lo: u32, hi: u32) -> Result<Option<u32>> {
        self.take(key)
            .map(|s| match s.trim().parse::<u32>() {
                Ok(v) if (lo..=hi).contains(&v) => Ok(v),
                _ => Err(Error::invalid(
                    key,
                    format!("{s:?} must be a whole number in [{lo}, {hi}]"),
                )),
            })
            .transpose()
    }

    /// `1`/`true` or `0`/`false`, false when absent.
    pub fn flag(&mut self, key: &'static str) -> Result<bool> {
        match self.take(key).as_deref() {
            None | Some("0" | "false") => Ok(false),
            Some("1" | "true") => Ok(true),
            Some(s) => Err(Error::invalid(key, format!("{s:?}: 1 or 0"))),
        }
    }

    /// `precision` (f32, f64) and `integrator` (rk4, dp54, dop853; `rtol`, `atol` as the
    /// commands take them), when any is given; not with `accurate`, which sets its own.
    /// `on_gpu`: whether the explorer's engine has a GPU (f32's tolerance floor by default
    /// there).
    pub(super) fn method(
        &mut self,
        accurate: bool,
        on_gpu: bool,
    ) -> Result<Option<(Precision, Integrator)>> {
        let keys = ["precision", "integrator", "rtol", "atol"];
        let Some(given) = keys.into_iter().find(|k| self.values.contains_key(*k)) else {
            return Ok(None);
        };
        if accurate {
            return Err(Error::invalid(given, "is set by accurate: leave one out"));
        }
        let precision = match self.take("precision").as_deref() {
            None | Some("f32") => Precision::F32,
            Some("f64") => Precision::F64,
            Some(s) => return Err(Error::invalid("precision", format!("{s:?}: f32 or f64"))),
        };
        let name = self.take("integrator").unwrap_or_else(|| "rk4".into());
        let (rtol, atol) = (self.number("rtol")?, self.number("atol")?);
        let integrator = integrator_of(&name, rtol, atol, on_gpu && precision == Precision::F32)?;
        Ok(Some((precision, integrator)))
    }

    /// An error naming the first key nobody asked for.
    pub fn finish(self) -> Result<()> {
        let mut left: Vec<String> = self.values.into_keys().collect();
        left.sort();
        match left.first() {
            None => Ok(()),
            Some(k) => Err(Error::invalid("query", format!("unknown key {k:?}"))),
        }
    }

    pub(super) fn colormap(&mut self) -> Result<Option<Colormap>> {
        let Some(name) = self.take("cmap") else {
            return Ok(None);
        };
        Colormap::ALL
            .into_iter()
            .find(|c| c.name() == name)
            .map(Some)
            .ok_or_else(|| {
                let names: Vec<&str> = Colormap::ALL.iter().map(|c| c.name()).collect();
                Error::invalid("cmap", format!("{name:?}: one of {}", names.join(", ")))
            })
    }

    /// The colour range `lo`..`hi` of a divergence-family map (its quantity's unit).
    pub(super) fn range(&mut self) -> Result<(f32, f32)> {
        let lo = self.within("lo", -1e6, 1e6)?.unwrap_or(0.0) as f32;
        let hi = self.within("hi", -1e6, 1e6)?.unwrap_or(2.0) as f32;
        if lo >= hi {
            return Err(Error::invalid("hi", format!("{hi} must exceed lo = {lo}")));
        }
        Ok((lo, hi))
    }
}

/// The keys a query may hold besides the physics' and the plane's.
const VIEW_KEYS: [&str; 17] = [
    "kind",
    "cmap",
    "unresolved",
    "lo",
    "hi",
    "size",
    "width",
    "height",
    "annotate",
    "x_min",
    "x_max",
    "y_min",
    "y_max",
    "px",
    "py",
    "pixel",
    "pixel_y",
];

/// Every key a query may hold, as the static name an error carries.
fn known(key: &str) -> Option<&'static str> {
    VIEW_KEYS
        .iter()
        .chain(&PHYSICS_KEYS)
        .chain(&PLANE_KEYS)
        .copied()
        .find(|k| *k == key)
}

/// The keys of the plane's axes and fixed start, which a store's map fixes.
pub const PLANE_KEYS: [&str; 6] = ["x", "y", "theta1", "omega1", "theta2", "omega2"];

/// The query's keys for the physics and the stepping, which a store's command fixes.
pub const PHYSICS_KEYS: [&str; 13] = [
    "m1",
    "m2",
    "l1",
    "l2",
    "g",
    "damping",
    "t_max",
    "dt",
    "accurate",
    "precision",
    "integrator",
    "rtol",
    "atol",
];
