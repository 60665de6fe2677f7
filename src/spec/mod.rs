//! What a run is: the grid of starts, the physics, the time stepping. Validated before any
//! work starts, so a bad value fails fast; errors name the field (`t_max`, `size`...), which
//! the command line turns into its flag.

use crate::error::{Error, Result, finite_positive};
use crate::model::{Params, State};

mod ensemble;
mod grid;
mod kind;
mod map;
mod memory;
mod method;
mod plane;
mod stability;
mod var;
mod zoom;

pub use crate::measure::indicator::{ALIGNED, ALIGNED_F32_FLOOR, Alignment, Indicator};
pub use ensemble::{Chunk, EnsembleSpec, Keep};
pub use grid::{Axis, Grid, Sampling, Var, pcg};
pub use kind::{MapKind, MapKindEntry};
pub(crate) use map::on_any;
pub use map::{AnyMap, FlipMeasure, FlipSpec, LyapunovSpec, MAX_STEPS, MapSpec, Method, RowSpan};
pub use memory::{available_memory, check_memory};
pub use method::{
    ACCURATE, ACCURATE_FTLE, Integrator, MIN_TOLERANCE_F32, MIN_TOLERANCE_F64, Precision,
    SteppingAsked, integrator_of,
};
pub use plane::{Angles, AxisAsked, PlaneAsked, check_along, resolve_at, resolve_on};
pub use stability::{largest_stable_dt, speed_bound, validate_speeds, validate_stability};
pub use zoom::{ZOOM, ZoomDefaults};

/// A closed interval `min:max` of angles (rad).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Range {
    pub min: f64,
    pub max: f64,
}

impl Range {
    pub fn mid(&self) -> f64 {
        0.5 * (self.min + self.max)
    }

    pub const FULL_TURN: Range = Range {
        min: -std::f64::consts::PI,
        max: std::f64::consts::PI,
    };
}

/// Smallest angle step between pixels that f32 still resolves near |theta| = pi: 16 ulp of
/// pi (ulp = 2.4e-7), so neighbouring pixels start from distinct f32 angles with room for
/// the arithmetic that forms them.
pub const F32_MIN_PIXEL_STEP: f64 = 16.0 * 2.384185791015625e-7;

/// The same for f64: 16 ulp of pi (ulp = 4.4e-16).
pub const F64_MIN_PIXEL_STEP: f64 = 16.0 * 4.440892098500626e-16;

/// Fixed-step time integration from t = 0 to `t_max`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stepping {
    /// Time step (s).
    pub dt: f64,
    /// End time (s).
    pub t_max: f64,
}

impl Stepping {
    /// A flip-family map's simulated time by default (s): most starts that flip at all do
    /// within it.
    pub const FLIP_T_MAX: f64 = 30.0;
    /// A divergence map's (s): long enough for the exponents to part regular from chaotic.
    pub const DIVERGENCE_T_MAX: f64 = 20.0;
    /// The RK4 step by default (s): well inside RK4's stable step for the presets.
    pub const DT: f64 = 0.01;

    /// Number of steps to cover `t_max`; a final partial step is taken whole, and events
    /// after `t_max` are not reported.
    pub fn steps(&self) -> u32 {
        let n = self.t_max / self.dt;
        // t_max = 20, dt = 0.01 gives 2000.0000000000002: round when within round-off.
        let rounded = n.round();
        if (n - rounded).abs() < 1e-9 * n.max(1.0) {
            rounded as u32
        } else {
            n.ceil() as u32
        }
    }
}

/// How far apart the releases of an ensemble start: an angle (rad) or a position error of
/// the bobs (m), as the lab report quotes its release accuracy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Spread {
    Radians(f64),
    Metres(f64),
}

impl Spread {
    /// Between 0 and 1 (rad or m), else an error naming `spread`.
    pub fn validate(&self) -> Result<()> {
        let (Spread::Radians(r) | Spread::Metres(r)) = *self;
        if r.is_finite() && (0.0..=1.0).contains(&r) {
            Ok(())
        } else {
            Err(Error::invalid(
                "spread",
                "must be between 0 and 1 (rad, or m with a unit)",
            ))
        }
    }
}

/// The releases: `runs` starts around `start`, evenly on a circle of radius `spread` in the
/// (theta1, theta2) plane (a position error e moves arm i by e / l_i). Deterministic, so a
/// picture can be made again; with spread 0 all starts are identical.
pub fn releases(p: &Params, start: State, runs: u32, spread: Spread) -> Vec<State> {
    let (d1, d2) = match spread {
        Spread::Radians(r) => (r, r),
        Spread::Metres(e) => (e / p.l1, e / p.l2),
    };
    (0..runs)
        .map(|k| {
            let phi = std::f64::consts::TAU * k as f64 / runs as f64;
            State {
                theta1: start.theta1 + d1 * phi.cos(),
                theta2: start.theta2 + d2 * phi.sin(),
                ..start
            }
        })
        .collect()
}

pub fn validate_params(p: &Params) -> Result<()> {
    crate::params::validate(p)
}

pub fn validate_stepping(s: &Stepping) -> Result<()> {
    finite_positive("dt", s.dt)?;
    finite_positive("t_max", s.t_max)?;
    let n = s.t_max / s.dt;
    if n > MAX_STEPS as f64 {
        return Err(Error::invalid(
            "dt",
            format!(
                "t-max / dt = {n:.0} steps; at most {MAX_STEPS} are allowed (raise the step or shorten the run)"
            ),
        ));
    }
    Ok(())
}

/// A single start (trajectory, convergence run): every component finite.
pub fn validate_start(s: &State) -> Result<()> {
    for (field, v) in [
        ("theta1", s.theta1),
        ("theta2", s.theta2),
        ("omega1", s.omega1),
        ("omega2", s.omega2),
    ] {
        if !v.is_finite() {
            return Err(Error::invalid(field, "must be a finite number"));
        }
    }
    Ok(())
}

/// The grid in range, its whole map within the memory this process may take.
pub fn validate_grid(g: &Grid) -> Result<()> {
    validate_grid_holding(g, g.height)
}

/// The grid in range, `rows` of its map (all, or a store's band) within the memory this
/// process may take.
pub fn validate_grid_holding(g: &Grid, rows: u32) -> Result<()> {
    const MAX_SIDE: u32 = 1 << 16;
    if g.width == 0 || g.height == 0 || g.width > MAX_SIDE || g.height > MAX_SIDE {
        return Err(Error::invalid(
            "size",
            format!(
                "{}x{} must be between 1 and {MAX_SIDE} on each side",
                g.width, g.height
            ),
        ));
    }
    // The map (4 B), its colours (3 B) and the PNG encoder's copy (3 B) live in memory at
    // once; a store's run holds one band of them.
    let held = match rows == g.height {
        true => format!("a {}x{} map", g.width, g.height),
        false => format!("a band of {rows} rows of a {}x{} map", g.width, g.height),
    };
    check_memory("size", g.width as u64 * rows as u64 * 10, &held)?;
    g.validate_axes()
}

/// The map's physics over its whole plane: the parameters in range, the step stable and
/// the speeds the starts can reach within RK4's reach, at the plane's corners and a lattice
/// between them ([`Grid::lattice`]; exact for the speeds, which grow with |omega|, and for
/// monotone parameters). A parameter the axes take out of range is named by its axis.
pub fn validate_plane(p: &Params, g: &Grid, s: &Stepping) -> Result<()> {
    let axis_of = |e: Error| -> Error {
        let var = match (g.x.var.is_state(), g.y.var.is_state()) {
            (false, _) => g.x.var,
            (_, false) => g.y.var,
            _ => return e,
        };
        let field = if var == g.x.var { "x" } else { "y" };
        Error::invalid(field, format!("{} over this plane: {e}", var.name()))
    };
    // A plane of the start alone has one set of parameters: its stability is checked once.
    let mut checked: Option<Params> = None;
    for (q, start) in g.lattice(p) {
        let at = |e: Error| match g.varies_params() || !g.is_angle_plane() {
            true => with_context(e, &format!("at {}", point_words(g, &q, &start))),
            false => e,
        };
        if checked != Some(q) {
            validate_params(&q).map_err(axis_of)?;
            validate_stability(&q, s).map_err(at)?;
            checked = Some(q);
        }
        validate_speeds(&q, s, start.omega1, start.omega2).map_err(at)?;
    }
    Ok(())
}

/// `x = .., y = ..` of a point of the plane, in words.
fn point_words(g: &Grid, p: &Params, s: &State) -> String {
    format!(
        "{} = {}, {} = {}",
        g.x.var.name(),
        g.x.var.get(p, s),
        g.y.var.name(),
        g.y.var.get(p, s)
    )
}

/// The same error with `context` after its message.
fn with_context(e: Error, context: &str) -> Error {
    match e {
        Error::InvalidSpec { field, reason } => {
            Error::invalid(field, format!("{reason} ({context})"))
        }
        e => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_round_off() {
        let s = Stepping {
            dt: 0.01,
            t_max: 20.0,
        };
        assert_eq!(s.steps(), 2000);
        let s = Stepping {
            dt: 0.3,
            t_max: 1.0,
        };
        assert_eq!(s.steps(), 4);
    }

    #[test]
    fn pixel_centres() {
        let g = Grid::square(4);
        let h = std::f64::consts::PI / 4.0;
        assert!((g.x_at(0) - (-3.0 * h)).abs() < 1e-15);
        assert!((g.y_at(0) - 3.0 * h).abs() < 1e-15);
        assert!((g.y_at(3) + 3.0 * h).abs() < 1e-15);
    }
}
