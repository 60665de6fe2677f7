//! What a request asks for, from its query string: the map kind, the physics, the time
//! stepping and the picture, each value checked; an error names the query key, which the
//! page shows as it is (400).

use std::collections::HashMap;
use std::f64::consts::PI;

use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::params::ParamSources;
use crate::render::Colormap;
use crate::spec::{
    ACCURATE, FlipSpec, Grid, Integrator, LyapunovSpec, Method, Precision, Range, Stepping,
};

/// The deepest zoom level: 256 * 2^42 pixels across a turn, a pixel step of 5.6e-15 rad,
/// below what f64 resolves (the verdict then says so); Leaflet's pixel coordinates stay
/// exact integers in a double there.
pub const MAX_ZOOM: u32 = 42;

/// Largest simulated time a request may ask for (s): a 256^2 tile at dt 0.01 then takes
/// about a second on lavapipe.
pub const MAX_T_MAX: f64 = 100.0;

/// Smallest time step a request may ask for (s): with MAX_T_MAX, 10^5 steps a pendulum.
pub const MIN_DT: f64 = 1e-3;

/// A tile's sides (pixels): Leaflet's 256 by default, at most 512.
pub const TILE_SIZES: (u32, u32) = (16, 512);

/// Largest side of a saved view (pixels), and its most pixels.
pub const MAX_SAVE_SIDE: u32 = 4096;
pub const MAX_SAVE_PIXELS: u64 = 1 << 24;

/// The map a tile shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Flip times.
    Flip,
    /// Largest finite-time Lyapunov exponents.
    Ftle,
    /// The verdict on the flip map: white resolved, black not.
    Resolved,
}

impl Kind {
    pub const NAMES: [&'static str; 3] = ["flip", "ftle", "resolved"];

    fn parse(s: &str) -> Result<Kind> {
        match s {
            "flip" => Ok(Kind::Flip),
            "ftle" => Ok(Kind::Ftle),
            "resolved" => Ok(Kind::Resolved),
            _ => Err(Error::invalid(
                "kind",
                format!("{s:?}: one of {}", Kind::NAMES.join(", ")),
            )),
        }
    }
}

/// Everything about a view but its region.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub kind: Kind,
    pub params: Params,
    pub stepping: Stepping,
    /// `--accurate`'s settings for flip maps (f64, DP54).
    pub accurate: bool,
    pub colormap: Option<Colormap>,
    /// Paint the pixels the verdict cannot resolve grey.
    pub unresolved: bool,
    /// FTLE colours from .0 to .1 (1/s).
    pub range: (f32, f32),
}

/// A query string's values by key, each key read at most once; keys nobody read are
/// refused ([`Query::finish`]), so a misspelt key is an error, not a silent default.
pub struct Query {
    values: HashMap<String, String>,
}

impl Query {
    pub fn new(values: HashMap<String, String>) -> Self {
        Query { values }
    }

    fn take(&mut self, key: &'static str) -> Option<String> {
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

    /// An error naming the first key nobody asked for.
    pub fn finish(self) -> Result<()> {
        let mut left: Vec<String> = self.values.into_keys().collect();
        left.sort();
        match left.first() {
            None => Ok(()),
            Some(k) => Err(Error::invalid("query", format!("unknown key {k:?}"))),
        }
    }

    /// The view's settings; `base` gives the physics not in the query (the server's flags).
    pub fn view(&mut self, base: &ParamSources) -> Result<View> {
        let kind = Kind::parse(self.take("kind").as_deref().unwrap_or("flip"))?;
        let sources = ParamSources {
            m1: self.number("m1")?.or(base.m1),
            m2: self.number("m2")?.or(base.m2),
            l1: self.number("l1")?.or(base.l1),
            l2: self.number("l2")?.or(base.l2),
            g: self.number("g")?.or(base.g),
            joint_damping: self
                .number("damping")?
                .map(|c| (c, c))
                .or(base.joint_damping),
            ..base.clone()
        };
        let params = sources
            .resolve()
            .and_then(|p| crate::spec::validate_params(&p).map(|_| p))
            .map_err(|e| rename(e, "joint_damping", "damping"))?;
        let accurate = self.flag("accurate")?;
        let t_max = self.within("t_max", 0.0, MAX_T_MAX)?.unwrap_or(20.0);
        let dt = self.within("dt", MIN_DT, 0.1)?.unwrap_or(0.01);
        let colormap = match self.take("cmap") {
            None => None,
            Some(name) => Some(
                Colormap::ALL
                    .into_iter()
                    .find(|c| c.name() == name)
                    .ok_or_else(|| {
                        let names: Vec<&str> = Colormap::ALL.iter().map(|c| c.name()).collect();
                        Error::invalid("cmap", format!("{name:?}: one of {}", names.join(", ")))
                    })?,
            ),
        };
        let lo = self.within("lo", -100.0, 100.0)?.unwrap_or(0.0) as f32;
        let hi = self.within("hi", -100.0, 100.0)?.unwrap_or(2.0) as f32;
        if lo >= hi {
            return Err(Error::invalid("hi", format!("{hi} must exceed lo = {lo}")));
        }
        Ok(View {
            kind,
            params,
            stepping: Stepping { dt, t_max },
            accurate,
            colormap,
            unresolved: self.flag("unresolved")?,
            range: (lo, hi),
        })
    }
}

/// The same error, naming `to` where it named `from` (the query's key for a spec's field).
fn rename(e: Error, from: &str, to: &'static str) -> Error {
    match e {
        Error::InvalidSpec { field, reason } if field == from => Error::invalid(to, reason),
        e => e,
    }
}

impl View {
    /// The flip map of this view over `grid`, as `chaoscope flip` makes it.
    pub fn flip_spec(&self, grid: Grid) -> FlipSpec {
        let mut spec = FlipSpec::new(self.params, grid, self.stepping);
        if self.accurate {
            let (precision, integrator, dt) = ACCURATE;
            spec.precision = precision;
            spec.integrator = integrator;
            spec.stepping.dt = dt;
        }
        spec
    }

    /// The divergence map of this view over `grid`, as `chaoscope lyapunov` makes it by
    /// default (tangent method, renormalised every 0.1 s).
    pub fn lyapunov_spec(&self, grid: Grid) -> LyapunovSpec {
        LyapunovSpec {
            params: self.params,
            grid,
            stepping: self.stepping,
            method: Method::Tangent,
            renorm: 0.1,
            use_symmetry: true,
            precision: Precision::F32,
            band: None,
        }
    }

    /// The integrator the flip map uses.
    pub fn integrator(&self) -> Integrator {
        self.flip_spec(Grid::square(1)).integrator
    }
}

/// The grid of tile (z, x, y) with `size` pixels a side: the full turn [-pi, pi]^2 is tile
/// (0, 0, 0); each level halves the tiles' sides; y counts down from theta2 = pi.
pub fn tile_grid(z: u32, x: u64, y: u64, size: u32) -> Result<Grid> {
    if z > MAX_ZOOM {
        return Err(Error::invalid(
            "z",
            format!("{z} must be at most {MAX_ZOOM}"),
        ));
    }
    let n = 1u64 << z;
    for (key, v) in [("x", x), ("y", y)] {
        if v >= n {
            return Err(Error::invalid(
                key,
                format!("{v} lies outside level {z}'s tiles 0..{n}"),
            ));
        }
    }
    let step = 2.0 * PI / n as f64;
    Ok(Grid {
        width: size,
        height: size,
        theta1: Range {
            min: -PI + x as f64 * step,
            max: -PI + (x + 1) as f64 * step,
        },
        theta2: Range {
            min: PI - (y + 1) as f64 * step,
            max: PI - y as f64 * step,
        },
        omega1: 0.0,
        omega2: 0.0,
    })
}

/// A region `theta1`, `theta2` (MIN:MAX, rad) of `width` x `height` pixels: a saved view.
pub fn region_grid(q: &mut Query) -> Result<Grid> {
    let range = |q: &mut Query, lo: &'static str, hi: &'static str| -> Result<Range> {
        let min = q.within(lo, -4.0 * PI, 4.0 * PI)?;
        let max = q.within(hi, -4.0 * PI, 4.0 * PI)?;
        match (min, max) {
            (Some(min), Some(max)) if min < max => Ok(Range { min, max }),
            (Some(_), Some(_)) => Err(Error::invalid(hi, "must exceed its minimum")),
            _ => Err(Error::invalid(lo, format!("{lo} and {hi} are both needed"))),
        }
    };
    let theta1 = range(q, "theta1_min", "theta1_max")?;
    let theta2 = range(q, "theta2_min", "theta2_max")?;
    let width = q.count("width", 16, MAX_SAVE_SIDE)?.unwrap_or(1024);
    let height = q.count("height", 16, MAX_SAVE_SIDE)?.unwrap_or(width);
    if width as u64 * height as u64 > MAX_SAVE_PIXELS {
        return Err(Error::invalid(
            "height",
            format!("{width} x {height} exceeds {MAX_SAVE_PIXELS} pixels"),
        ));
    }
    Ok(Grid {
        width,
        height,
        theta1,
        theta2,
        omega1: 0.0,
        omega2: 0.0,
    })
}

/// One start, `theta1`, `theta2` (rad), from rest.
pub fn start(q: &mut Query) -> Result<State> {
    let mut angle = |key| {
        q.within(key, -4.0 * PI, 4.0 * PI)?
            .ok_or_else(|| Error::invalid(key, "is needed (rad)"))
    };
    Ok(State {
        theta1: angle("theta1")?,
        omega1: 0.0,
        theta2: angle("theta2")?,
        omega2: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_turn_without_gaps() {
        let a = tile_grid(3, 2, 5, 256).unwrap();
        let b = tile_grid(3, 3, 5, 256).unwrap();
        assert_eq!(a.theta1.max, b.theta1.min);
        let top = tile_grid(0, 0, 0, 256).unwrap();
        assert_eq!(
            (top.theta1, top.theta2),
            (Range::FULL_TURN, Range::FULL_TURN)
        );
        assert!(tile_grid(3, 8, 0, 256).is_err());
        assert!(tile_grid(MAX_ZOOM + 1, 0, 0, 256).is_err());
    }

    #[test]
    fn unknown_and_bad_keys_name_themselves() {
        let q = |pairs: &[(&str, &str)]| {
            Query::new(
                pairs
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
            )
        };
        let base = ParamSources::default();
        for (pairs, field) in [
            (&[("t_max", "NaN")][..], "t_max"),
            (&[("t_max", "1e9")][..], "t_max"),
            (&[("kind", "mandelbrot")][..], "kind"),
            (&[("m1", "-1")][..], "m1"),
            (&[("damping", "-1")][..], "damping"),
            (&[("cmap", "nope")][..], "cmap"),
        ] {
            match q(pairs).view(&base) {
                Err(Error::InvalidSpec { field: f, .. }) => assert_eq!(f, field, "{pairs:?}"),
                other => panic!("{pairs:?}: {other:?}"),
            }
        }
        let mut extra = q(&[("tmax", "3")]);
        extra.view(&base).unwrap();
        assert!(extra.finish().is_err());
    }
}
