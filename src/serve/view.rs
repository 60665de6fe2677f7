//! What a request asks for, from its query string: the map kind, the physics, the time
//! stepping and the picture, each value checked; an error names the query key, which the
//! page shows as it is (400).

use std::f64::consts::PI;

use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::params::ParamSources;
use crate::render::Colormap;
use crate::spec::AnyMap;
use crate::spec::{
    Axis, FlipMeasure, FlipSpec, Grid, Integrator, LyapunovSpec, MapSpec, Precision, Range,
    Sampling, Stepping, Var,
};

pub use super::kind::Kind;
pub use super::query::{PHYSICS_KEYS, PLANE_KEYS, Query};

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

/// Everything about a view but its region.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub kind: Kind,
    pub params: Params,
    pub stepping: Stepping,
    /// `--accurate`'s settings (f64, DP54): `flip`'s for flip maps, `lyapunov`'s for FTLE.
    pub accurate: bool,
    /// The precision and integrator asked for (`precision`, `integrator`, `rtol`, `atol`),
    /// when not `accurate`'s: checked against the path where a map is planned, as the
    /// commands' are (an f32 kernel refuses tolerances below its floor).
    pub method: Option<(Precision, Integrator)>,
    pub colormap: Option<Colormap>,
    /// Paint the pixels the verdict cannot resolve grey.
    pub unresolved: bool,
    /// FTLE colours from .0 to .1 (1/s).
    pub range: (f32, f32),
    /// A store's map, whose command fixed the physics, stepping and integrator.
    pub stored: Option<AnyMap>,
    /// The plane and its region (256 x 256 pixels; tiles, points and saved views take their
    /// own sizes).
    pub plane: Grid,
    /// Whether the query gave the region (`x_min`...).
    pub region_given: bool,
}

impl Query {
    /// The view's settings; `base` gives the physics not in the query (the server's flags),
    /// or `stored`, a store's map, fixes them (and the query may not name them).
    /// `on_gpu`: whether the explorer's engine has a GPU ([`Query::method`]'s default).
    pub fn view(
        &mut self,
        base: &ParamSources,
        stored: Option<AnyMap>,
        on_gpu: bool,
    ) -> Result<View> {
        let kind = self.take("kind");
        let kind = match (kind.as_deref(), stored) {
            (Some(k), _) => Kind::parse(k)?,
            (None, Some(map)) => Kind::of(&map),
            (None, None) => Kind::FLIP,
        };
        let (plane, region_given) = self.plane(stored.map(|m| *m.grid()))?;
        if let Some(map) = stored {
            for key in PHYSICS_KEYS {
                if self.values.contains_key(key) {
                    return Err(Error::invalid(
                        key,
                        "is fixed by the command of the store this explorer serves",
                    ));
                }
            }
            let (params, stepping) = (map.params(), map.stepping());
            return Ok(View {
                kind,
                params,
                stepping,
                accurate: false,
                method: None,
                colormap: self.colormap()?,
                unresolved: self.flag("unresolved")?,
                range: self.range()?,
                stored,
                plane,
                region_given,
            });
        }
        for key in ["m1", "m2", "l1", "l2", "g", "damping"] {
            let along =
                [("x", plane.x.var), ("y", plane.y.var)]
                    .into_iter()
                    .find(|(_, v)| match key {
                        "damping" => v.overlaps(Var::Damping),
                        _ => v.writes().contains(&key),
                    });
            if let Some((axis, var)) = along
                && self.values.contains_key(key)
            {
                return Err(Error::invalid(
                    key,
                    format!("{key} varies along {axis} ({}); leave it out", var.name()),
                ));
            }
        }
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
        if let Kind::Map(k) = kind
            && accurate
            && !k.entry().accurate
        {
            return Err(Error::invalid(
                "accurate",
                format!(
                    "the map \"{}\" has no accurate settings; leave accurate off",
                    k.entry().label
                ),
            ));
        }
        let method = self.method(accurate, on_gpu)?;
        // The divergence map's default time for every kind: a view computes fast.
        let t_max = self
            .within("t_max", 0.0, MAX_T_MAX)?
            .unwrap_or(crate::spec::Stepping::DIVERGENCE_T_MAX);
        let dt = self
            .within("dt", MIN_DT, 0.1)?
            .unwrap_or(crate::spec::Stepping::DT);
        if let Kind::Map(k) = kind
            && k.entry().indicator.is_some()
            && t_max < renorm_of(dt)
        {
            return Err(Error::invalid(
                "t_max",
                format!(
                    "{t_max:e} s is shorter than the divergence map's renormalisation interval, {} s",
                    renorm_of(dt)
                ),
            ));
        }
        Ok(View {
            kind,
            params,
            stepping: Stepping { dt, t_max },
            accurate,
            method,
            colormap: self.colormap()?,
            unresolved: self.flag("unresolved")?,
            range: self.range()?,
            stored: None,
            plane,
            region_given,
        })
    }

    /// The plane a view spans: its axes (`x`, `y`, named as `--x`/`--y` name them; theta1
    /// and theta2 by default), their region (`x_min`:`x_max`, `y_min`:`y_max`; each axis'
    /// default range otherwise), and the start's components along neither axis (`theta1`,
    /// `omega1`, `theta2`, `omega2`; 0 otherwise). A store's map fixes all but the region.
    /// Also whether the region was given.
    fn plane(&mut self, stored: Option<Grid>) -> Result<(Grid, bool)> {
        let mut plane = match stored {
            Some(grid) => {
                if let Some(key) = PLANE_KEYS.iter().find(|k| self.values.contains_key(**k)) {
                    return Err(Error::invalid(
                        key,
                        "is fixed by the command of the store this explorer serves",
                    ));
                }
                grid
            }
            None => self.axes()?,
        };
        let mut given = false;
        for (axis, lo, hi) in [
            (&mut plane.x, "x_min", "x_max"),
            (&mut plane.y, "y_min", "y_max"),
        ] {
            // Angles within a turn (a start outside has already flipped).
            let limit = if axis.var.is_angle() { PI + 1e-9 } else { 1e6 };
            match (
                self.within(lo, -limit, limit)?,
                self.within(hi, -limit, limit)?,
            ) {
                (None, None) => {}
                (Some(min), Some(max)) if min < max => {
                    axis.range = Range { min, max };
                    // Level 0's tile must have distinct pixels in f64.
                    let finest = 256.0 * axis.finest_step(f64::EPSILON);
                    if max - min < finest {
                        return Err(Error::invalid(
                            hi,
                            format!("must exceed {lo} by {finest:e} at least"),
                        ));
                    }
                    given = true;
                }
                (Some(_), Some(_)) => return Err(Error::invalid(hi, format!("must exceed {lo}"))),
                (Some(_), None) => return Err(Error::invalid(lo, format!("needs {hi}"))),
                (None, Some(_)) => return Err(Error::invalid(hi, format!("needs {lo}"))),
            }
        }
        Ok((plane, given))
    }

    /// The axes and the fixed start of a view that is not a store's.
    fn axes(&mut self) -> Result<Grid> {
        let mut var = |key: &'static str, default: Var| match self.take(key) {
            None => Ok(default),
            Some(name) => Var::parse(&name).ok_or_else(|| {
                let names: Vec<&str> = Var::ALL.iter().map(|v| v.name()).collect();
                Error::invalid(key, format!("{name:?}: one of {}", names.join(" ")))
            }),
        };
        let (x, y) = (var("x", Var::Theta1)?, var("y", Var::Theta2)?);
        let mut fixed = State::default();
        for v in [Var::Theta1, Var::Omega1, Var::Theta2, Var::Omega2] {
            let key = v.name();
            let axis = [("x", x), ("y", y)].into_iter().find(|(_, a)| *a == v);
            match axis {
                Some((axis, _)) if self.values.contains_key(key) => {
                    return Err(Error::invalid(
                        key,
                        format!("{key} lies along {axis}: its range is {axis}_min:{axis}_max"),
                    ));
                }
                Some(_) => {}
                None => {
                    let limit = if v.is_angle() { PI } else { 1e3 };
                    if let Some(value) = self.within(key, -limit, limit)? {
                        v.set(value, &mut Params::default(), &mut fixed);
                    }
                }
            }
        }
        let plane = Grid {
            width: 256,
            height: 256,
            x: Axis {
                var: x,
                range: x.default_range(),
            },
            y: Axis {
                var: y,
                range: y.default_range(),
            },
            fixed,
            sampling: Sampling::Centres,
        };
        plane.validate_axes()?;
        Ok(plane)
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
        if let Some(AnyMap::Flip(stored)) = self.stored {
            return FlipSpec {
                grid,
                band: None,
                ..stored
            };
        }
        let spec = FlipSpec {
            measure: match self.kind {
                Kind::FLIP_KIND => FlipMeasure::Kind,
                _ => FlipMeasure::Time,
            },
            ..FlipSpec::new(self.params, grid, self.stepping)
        };
        match (self.accurate, self.method) {
            (true, _) => spec.accurate(),
            (false, Some((precision, integrator))) => {
                spec.restepped(self.stepping, integrator, precision)
            }
            (false, None) => spec,
        }
    }

    /// The divergence map of this view over `grid`, as `chaoscope lyapunov` makes it by
    /// default (tangent method, renormalised every 0.1 s), or with `--accurate`.
    pub fn lyapunov_spec(&self, grid: Grid) -> LyapunovSpec {
        if let Some(AnyMap::Lyapunov(stored)) = self.stored {
            return LyapunovSpec {
                grid,
                band: None,
                ..stored
            };
        }
        let spec = LyapunovSpec {
            renorm: renorm_of(self.stepping.dt),
            indicator: match self.kind {
                Kind::Map(k) => k.entry().indicator.unwrap_or_default(),
                Kind::Resolved => crate::spec::Indicator::default(),
            },
            ..LyapunovSpec::new(self.params, grid, self.stepping)
        };
        match (self.accurate, self.method) {
            (true, _) => spec.accurate(),
            (false, Some((precision, integrator))) => {
                spec.restepped(self.stepping, integrator, precision)
            }
            (false, None) => spec,
        }
    }
}

/// The divergence map's renormalisation interval at step `dt`: the whole number of steps
/// nearest 0.1 s (`chaoscope lyapunov`'s default), at least one.
fn renorm_of(dt: f64) -> f64 {
    (0.1 / dt).round().max(1.0) * dt
}

/// A region of the view's plane: its `width` x `height` pixels (a saved view).
pub fn region_grid(q: &mut Query, view: &View) -> Result<Grid> {
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
        ..view.plane
    })
}

/// A point of the view's plane, `px` along x and `py` along y: the one-pixel grid around it,
/// `pixel` wide along x and `pixel_y` (default `pixel`) along y, so it runs in the precision
/// of the tile it was clicked on; and its pendulum (parameters and start).
pub fn point(q: &mut Query, view: &View) -> Result<(Grid, (Params, State))> {
    let mut value = |key| {
        q.within(key, -1e6, 1e6)?
            .ok_or_else(|| Error::invalid(key, "is needed (a value along the axis)"))
    };
    let (px, py) = (value("px")?, value("py")?);
    let dx = q.within("pixel", 1e-300, 1e6)?.unwrap_or(1e-3);
    let dy_given = q.within("pixel_y", 1e-300, 1e6)?;
    let dy = dy_given.unwrap_or(dx);
    let around = |a: Axis, v: f64, d: f64| Axis::new(a.var, v - 0.5 * d, v + 0.5 * d);
    let grid = Grid {
        width: 1,
        height: 1,
        x: around(view.plane.x, px, dx),
        y: around(view.plane.y, py, dy),
        ..view.plane
    };
    for (key, a, d) in [("pixel", grid.x, dx), ("pixel_y", grid.y, dy)] {
        // A narrower pixel has no distinct edges in f64.
        let finest = a.finest_step(f64::EPSILON);
        if d < finest {
            return Err(Error::invalid(
                key,
                format!(
                    "{d:e} is finer than f64 resolves along {} ({finest:e})",
                    a.var.name()
                ),
            ));
        }
    }
    // Errors name the point's keys, not the axes' (`x`, or `theta1` on the angle plane): the
    // point where it lies outside the axis' limits, else the pixel's size that reaches past.
    let inside =
        |var: crate::spec::Var, v: f64| !var.is_angle() || v.abs() <= std::f64::consts::PI + 1e-9;
    let y_size = if dy_given.is_some() {
        "pixel_y"
    } else {
        "pixel"
    };
    let name = |e| match e {
        Error::InvalidSpec { field, reason } => {
            let key = match field {
                f if f == "x" || f == grid.x.var.name() => match inside(grid.x.var, px) {
                    true => "pixel",
                    false => "px",
                },
                f if f == "y" || f == grid.y.var.name() => match inside(grid.y.var, py) {
                    true => y_size,
                    false => "py",
                },
                _ => return Error::InvalidSpec { field, reason },
            };
            Error::invalid(key, reason)
        }
        e => e,
    };
    grid.validate_axes().map_err(name)?;
    let (p, s) = view.plane.at(&view.params, px, py);
    // The point's own parameters (an axis may set them): an error names the axis' key.
    crate::spec::validate_params(&p).map_err(|e| {
        let key = if grid.x.var.is_state() { "py" } else { "px" };
        Error::invalid(key, e.to_string())
    })?;
    Ok((grid, (p, s)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_and_bad_keys_name_themselves() {
        let q = |pairs: &[(&str, &str)]| {
            Query::new(
                pairs
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
            )
            .unwrap()
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
            match q(pairs).view(&base, None, true) {
                Err(Error::InvalidSpec { field: f, .. }) => assert_eq!(f, field, "{pairs:?}"),
                other => panic!("{pairs:?}: {other:?}"),
            }
        }
        let mut extra = q(&[("tmax", "3")]);
        extra.view(&base, None, true).unwrap();
        assert!(extra.finish().is_err());
    }
}
