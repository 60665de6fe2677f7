//! What a request asks for, from its query string: the map kind, the physics, the time
//! stepping and the picture, each value checked; an error names the query key, which the
//! page shows as it is (400).

use std::collections::HashMap;
use std::f64::consts::PI;

use crate::app::sweep::FrameMap;
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::params::ParamSources;
use crate::render::Colormap;
use crate::spec::{
    FlipMeasure, FlipSpec, Grid, LyapunovSpec, MapSpec, Method, Precision, Range, Stepping,
};

pub use super::kind::Kind;

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
    pub colormap: Option<Colormap>,
    /// Paint the pixels the verdict cannot resolve grey.
    pub unresolved: bool,
    /// FTLE colours from .0 to .1 (1/s).
    pub range: (f32, f32),
    /// A store's map, whose command fixed the physics, stepping and integrator.
    pub stored: Option<FrameMap>,
}

/// A query string's values by key, each key read at most once; keys nobody read are
/// refused ([`Query::finish`]), so a misspelt key is an error, not a silent default.
pub struct Query {
    values: HashMap<String, String>,
}

impl Query {
    /// The query's pairs, each key once: a repeated key (`size=16&size=512`) is refused
    /// naming it, rather than one of its values being taken silently.
    pub fn new(pairs: Vec<(String, String)>) -> Result<Self> {
        let mut values = HashMap::with_capacity(pairs.len());
        for (key, value) in pairs {
            if values.contains_key(&key) {
                let key = KNOWN_KEYS
                    .iter()
                    .copied()
                    .find(|k| *k == key)
                    .unwrap_or("query");
                return Err(Error::invalid(key, "is given more than once"));
            }
            values.insert(key, value);
        }
        Ok(Query { values })
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

    /// The view's settings; `base` gives the physics not in the query (the server's flags),
    /// or `stored`, a store's map, fixes them (and the query may not name them).
    pub fn view(&mut self, base: &ParamSources, stored: Option<FrameMap>) -> Result<View> {
        let kind = self.take("kind");
        let kind = match (kind.as_deref(), stored) {
            (Some(k), _) => Kind::parse(k)?,
            (None, Some(map)) => Kind::of(&map),
            (None, None) => Kind::FLIP,
        };
        if let Some(map) = stored {
            for key in PHYSICS_KEYS {
                if self.values.contains_key(key) {
                    return Err(Error::invalid(
                        key,
                        "is fixed by the store's command (serve --store)",
                    ));
                }
            }
            let (params, stepping) = (map.params(), map.stepping());
            return Ok(View {
                kind,
                params,
                stepping,
                accurate: false,
                colormap: self.colormap()?,
                unresolved: self.flag("unresolved")?,
                range: self.range()?,
                stored,
            });
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
        let t_max = self.within("t_max", 0.0, MAX_T_MAX)?.unwrap_or(20.0);
        let dt = self.within("dt", MIN_DT, 0.1)?.unwrap_or(0.01);
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
            colormap: self.colormap()?,
            unresolved: self.flag("unresolved")?,
            range: self.range()?,
            stored: None,
        })
    }

    fn colormap(&mut self) -> Result<Option<Colormap>> {
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
    fn range(&mut self) -> Result<(f32, f32)> {
        let lo = self.within("lo", -1e6, 1e6)?.unwrap_or(0.0) as f32;
        let hi = self.within("hi", -1e6, 1e6)?.unwrap_or(2.0) as f32;
        if lo >= hi {
            return Err(Error::invalid("hi", format!("{hi} must exceed lo = {lo}")));
        }
        Ok((lo, hi))
    }
}

/// The query's keys for the physics and the stepping, which a store's command fixes.
/// Every key a query may hold (a repeated one is named from here).
const KNOWN_KEYS: [&str; 25] = [
    "kind",
    "t_max",
    "dt",
    "cmap",
    "m1",
    "m2",
    "l1",
    "l2",
    "g",
    "damping",
    "accurate",
    "unresolved",
    "lo",
    "hi",
    "size",
    "pixel",
    "theta1",
    "theta2",
    "width",
    "annotate",
    "theta1_min",
    "theta1_max",
    "theta2_min",
    "theta2_max",
    "omega1",
];

pub const PHYSICS_KEYS: [&str; 9] = [
    "m1", "m2", "l1", "l2", "g", "damping", "t_max", "dt", "accurate",
];

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
        if let Some(FrameMap::Flip(stored)) = self.stored {
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
        if self.accurate { spec.accurate() } else { spec }
    }

    /// The divergence map of this view over `grid`, as `chaoscope lyapunov` makes it by
    /// default (tangent method, renormalised every 0.1 s), or with `--accurate`.
    pub fn lyapunov_spec(&self, grid: Grid) -> LyapunovSpec {
        if let Some(FrameMap::Lyapunov(stored)) = self.stored {
            return LyapunovSpec {
                grid,
                band: None,
                ..stored
            };
        }
        let spec = LyapunovSpec {
            params: self.params,
            grid,
            stepping: self.stepping,
            method: Method::Tangent,
            renorm: renorm_of(self.stepping.dt),
            use_symmetry: true,
            precision: Precision::F32,
            band: None,
            integrator: crate::spec::Integrator::Rk4,
            indicator: match self.kind {
                Kind::Map(k) => k.entry().indicator.unwrap_or_default(),
                Kind::Resolved => crate::spec::Indicator::Ftle,
            },
        };
        if self.accurate { spec.accurate() } else { spec }
    }
}

/// The divergence map's renormalisation interval at step `dt`: the whole number of steps
/// nearest 0.1 s (`chaoscope lyapunov`'s default), at least one.
fn renorm_of(dt: f64) -> f64 {
    (0.1 / dt).round().max(1.0) * dt
}

/// What the map's tiles cover: a region of starts that is `width` x `height` pixels at zoom
/// level `native` (tile pixels there are the region's pixels). Level 0's pixel units are
/// Leaflet's coordinates: the region spans `width / 2^native` of them across.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct World {
    pub theta1: Range,
    pub theta2: Range,
    pub width: u32,
    pub height: u32,
    pub native: u32,
}

impl World {
    /// The whole turn [-pi, pi]^2 as tile (0, 0, 0), computed at every level.
    pub const TURN: World = World {
        theta1: Range::FULL_TURN,
        theta2: Range::FULL_TURN,
        width: 256,
        height: 256,
        native: 0,
    };

    /// A stored map's grid: its own pixels at the first level where 256-pixel tiles hold
    /// them one to one.
    pub fn of_grid(grid: &Grid) -> World {
        let side = grid.width.max(grid.height).max(1) as f64;
        World {
            theta1: grid.x.range,
            theta2: grid.y.range,
            width: grid.width,
            height: grid.height,
            native: (side / 256.0).log2().ceil().max(0.0) as u32,
        }
    }

    /// The region's size in level-0 pixel units (across, down).
    pub fn units(&self) -> (f64, f64) {
        let scale = (1u64 << self.native) as f64;
        (self.width as f64 / scale, self.height as f64 / scale)
    }

    /// Radians per level-0 unit (theta1, theta2).
    pub fn rad_per_unit(&self) -> (f64, f64) {
        let (w, h) = self.units();
        (
            (self.theta1.max - self.theta1.min) / w,
            (self.theta2.max - self.theta2.min) / h,
        )
    }

    /// Checks tile (z, x, y) lies on the region.
    pub fn check_tile(&self, z: u32, x: u64, y: u64) -> Result<()> {
        if z > MAX_ZOOM {
            return Err(Error::invalid(
                "z",
                format!("{z} must be at most {MAX_ZOOM}"),
            ));
        }
        let (w, h) = self.units();
        let tiles = |units: f64| (units * (1u64 << z) as f64 / 256.0).ceil() as u64;
        for (key, v, n) in [("x", x, tiles(w)), ("y", y, tiles(h))] {
            if v >= n {
                return Err(Error::invalid(
                    key,
                    format!("{v} lies outside level {z}'s tiles 0..{n}"),
                ));
            }
        }
        Ok(())
    }

    /// The grid of tile (z, x, y) with `size` pixels a side; y counts down from the top
    /// (theta2's maximum).
    pub fn tile_grid(&self, z: u32, x: u64, y: u64, size: u32) -> Result<Grid> {
        self.check_tile(z, x, y)?;
        let span = 256.0 / (1u64 << z) as f64;
        let (k1, k2) = self.rad_per_unit();
        // span * k is exact (a power of two times k), so the whole turn's tiles get
        // -pi + x * 2 pi / 2^z, the same numbers at every level.
        let (step1, step2) = (span * k1, span * k2);
        Ok(Grid::angles(
            size,
            size,
            Range {
                min: self.theta1.min + x as f64 * step1,
                max: self.theta1.min + (x + 1) as f64 * step1,
            },
            Range {
                min: self.theta2.max - (y + 1) as f64 * step2,
                max: self.theta2.max - y as f64 * step2,
            },
            0.0,
            0.0,
        ))
    }

    /// The region's pixel under pixel `k` of `size` along tile `t` of level `z` (<= native),
    /// sampled at the tile pixel's centre: column (or row) of the stored map.
    pub fn stored_pixel(&self, z: u32, t: u64, k: u32, size: u32) -> u64 {
        let scale = (1u64 << (self.native - z)) as f64;
        let unit = (t * 256) as f64 + (k as f64 + 0.5) * 256.0 / size as f64;
        (unit * scale).floor() as u64
    }
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
    Ok(Grid::angles(width, height, theta1, theta2, 0.0, 0.0))
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
        let turn = World::TURN;
        let a = turn.tile_grid(3, 2, 5, 256).unwrap();
        let b = turn.tile_grid(3, 3, 5, 256).unwrap();
        assert_eq!(a.x.range.max, b.x.range.min);
        assert_eq!(a.x.range.min, -PI + 2.0 * (2.0 * PI / 8.0));
        let top = turn.tile_grid(0, 0, 0, 256).unwrap();
        assert_eq!(
            (top.x.range, top.y.range),
            (Range::FULL_TURN, Range::FULL_TURN)
        );
        assert!(turn.tile_grid(3, 8, 0, 256).is_err());
        assert!(turn.tile_grid(MAX_ZOOM + 1, 0, 0, 256).is_err());
    }

    #[test]
    fn a_stored_maps_tiles_hold_its_pixels_at_the_native_level() {
        let grid = Grid {
            width: 1000,
            height: 600,
            ..Grid::square(1)
        };
        let world = World::of_grid(&grid);
        assert_eq!(world.native, 2);
        // Level 2: tile pixel k of tile t is stored pixel 256 t + k; level 0 every 4th.
        assert_eq!(world.stored_pixel(2, 3, 7, 256), 3 * 256 + 7);
        assert_eq!(world.stored_pixel(0, 0, 10, 256), 42);
        assert!(world.check_tile(2, 3, 2).is_ok());
        assert!(
            world.check_tile(2, 3, 3).is_err(),
            "600 rows are 3 tiles down"
        );
        // The native level's tile grid has the stored map's pixel centres.
        let g = world.tile_grid(2, 1, 0, 256).unwrap();
        assert!((g.x_at(0) - grid.x_at(256)).abs() < 1e-12);
        assert!((g.y_at(5) - grid.y_at(5)).abs() < 1e-12);
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
            match q(pairs).view(&base, None) {
                Err(Error::InvalidSpec { field: f, .. }) => assert_eq!(f, field, "{pairs:?}"),
                other => panic!("{pairs:?}: {other:?}"),
            }
        }
        let mut extra = q(&[("tmax", "3")]);
        extra.view(&base, None).unwrap();
        assert!(extra.finish().is_err());
    }
}
