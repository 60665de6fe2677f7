//! What a run is: the grid of starts, the physics, the time stepping. Validated before any
//! work starts, so a bad value fails fast; errors name the field (`t_max`, `size`...), which
//! the command line turns into its flag.

use crate::error::{Error, Result, finite_positive};
use crate::model::{Params, State};

mod indicator;
mod kind;
mod map;
mod memory;
mod method;
mod stability;

pub use indicator::{ALIGNED, ALIGNED_F32_FLOOR, Alignment, Indicator};
pub use kind::{MapKind, MapKindEntry};
pub(crate) use map::on_any;
pub use map::{AnyMap, FlipMeasure, FlipSpec, LyapunovSpec, MAX_STEPS, MapSpec, Method, RowSpan};
pub use memory::{available_memory, check_memory};
pub use method::{
    ACCURATE, ACCURATE_FTLE, Integrator, MIN_TOLERANCE_F32, MIN_TOLERANCE_F64, Precision,
};
pub use stability::{largest_stable_dt, speed_bound, validate_speeds, validate_stability};

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

/// The initial-condition grid: theta1 along x (left to right), theta2 along y (top = max),
/// every start with the same angular velocities. Pixel centres, not edges.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Grid {
    pub width: u32,
    pub height: u32,
    pub theta1: Range,
    pub theta2: Range,
    /// Initial angular velocities (rad/s), the same for every pixel.
    pub omega1: f64,
    pub omega2: f64,
}

impl Grid {
    pub fn square(n: u32) -> Self {
        Grid {
            width: n,
            height: n,
            theta1: Range::FULL_TURN,
            theta2: Range::FULL_TURN,
            omega1: 0.0,
            omega2: 0.0,
        }
    }

    pub fn theta1_step(&self) -> f64 {
        (self.theta1.max - self.theta1.min) / self.width as f64
    }

    pub fn theta2_step(&self) -> f64 {
        (self.theta2.max - self.theta2.min) / self.height as f64
    }

    /// theta1 at the centre of column `col`: the range's middle plus an odd whole number of
    /// half steps, so columns mirrored about the middle get exactly opposite angles (the map's
    /// symmetry, see `point_symmetric`, then holds bit for bit).
    pub fn theta1_at(&self, col: u32) -> f64 {
        let half_steps = 2.0 * col as f64 + 1.0 - self.width as f64;
        self.theta1.mid() + half_steps * (0.5 * self.theta1_step())
    }

    /// theta2 at the centre of row `row` (row 0 is the top, theta2 near its maximum).
    pub fn theta2_at(&self, row: u32) -> f64 {
        let half_steps = 2.0 * row as f64 + 1.0 - self.height as f64;
        self.theta2.mid() - half_steps * (0.5 * self.theta2_step())
    }

    /// Whether the starts come in opposite pairs (theta1, theta2) <-> (-theta1, -theta2), i.e.
    /// pixel (col, row) <-> (width-1-col, height-1-row): both ranges centred on 0 and released
    /// from rest. The equations of motion are odd under y -> -y (losses included), so mirrored
    /// starts follow mirrored trajectories and flip at the same time: half the map is enough.
    pub fn point_symmetric(&self) -> bool {
        self.theta1.mid() == 0.0
            && self.theta2.mid() == 0.0
            && self.omega1 == 0.0
            && self.omega2 == 0.0
    }

    pub fn start(&self, col: u32, row: u32) -> State {
        State {
            theta1: self.theta1_at(col),
            omega1: self.omega1,
            theta2: self.theta2_at(row),
            omega2: self.omega2,
        }
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Whether neighbouring pixels are closer than f32 resolves near |theta| = pi
    /// ([`F32_MIN_PIXEL_STEP`]): such a grid must be integrated in f64.
    pub fn needs_f64(&self) -> bool {
        self.theta1_step().min(self.theta2_step()) < F32_MIN_PIXEL_STEP
    }

    /// Whether neighbouring pixels are closer than even f64 resolves near |theta| = pi
    /// ([`F64_MIN_PIXEL_STEP`]): the map is computed, but no pixel of it is resolved.
    pub fn beyond_f64(&self) -> bool {
        self.theta1_step().min(self.theta2_step()) < F64_MIN_PIXEL_STEP
    }
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

/// Angles must stay strictly inside (-pi, pi): a start outside has already flipped.
fn validate_range(field: &'static str, r: &Range) -> Result<()> {
    use std::f64::consts::PI;
    // Allow the user's "-pi:pi" written with a rounded pi.
    let limit = PI + 1e-9;
    if !(r.min.is_finite() && r.max.is_finite()) || r.min >= r.max {
        return Err(Error::invalid(
            field,
            format!("{}:{} must be MIN:MAX with MIN < MAX", r.min, r.max),
        ));
    }
    if r.min < -limit || r.max > limit {
        return Err(Error::invalid(
            field,
            format!("{}:{} must lie within -pi:pi", r.min, r.max),
        ));
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
    validate_range("theta1", &g.theta1)?;
    validate_range("theta2", &g.theta2)?;
    if !g.omega1.is_finite() {
        return Err(Error::invalid("omega1", "must be a finite number"));
    }
    if !g.omega2.is_finite() {
        return Err(Error::invalid("omega2", "must be a finite number"));
    }
    Ok(())
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
        assert!((g.theta1_at(0) - (-3.0 * h)).abs() < 1e-15);
        assert!((g.theta2_at(0) - 3.0 * h).abs() < 1e-15);
        assert!((g.theta2_at(3) + 3.0 * h).abs() < 1e-15);
    }
}
