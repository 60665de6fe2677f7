//! The plane a map spans: any two of the start's angles and angular velocities and the
//! physical parameters along x and y ([`Var`]), everything else fixed. Pixel centres, row 0
//! at the top (y at its maximum).

use super::Range;
pub use super::var::Var;
use crate::error::{Error, Result};
use crate::model::{Params, State};

/// One axis: what it varies, over which range (pixel edges at the range's ends).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Axis {
    pub var: Var,
    pub range: Range,
}

impl Axis {
    pub fn new(var: Var, min: f64, max: f64) -> Self {
        Axis {
            var,
            range: Range { min, max },
        }
    }

    /// Width of one of `n` pixels.
    pub fn step(&self, n: u32) -> f64 {
        (self.range.max - self.range.min) / n as f64
    }

    /// The centre of pixel `k` of `n`, counted from the range's minimum: the middle plus an
    /// odd whole number of half steps, so pixels mirrored about the middle get exactly
    /// opposite values (the map's point symmetry then holds bit for bit).
    pub fn at(&self, k: u32, n: u32) -> f64 {
        self.range.mid() + Axis::half_steps(k, n) * (0.5 * self.step(n))
    }

    /// The centre of pixel `k` of `n`, counted from the range's maximum.
    pub fn at_from_max(&self, k: u32, n: u32) -> f64 {
        self.range.mid() - Axis::half_steps(k, n) * (0.5 * self.step(n))
    }

    fn half_steps(k: u32, n: u32) -> f64 {
        2.0 * k as f64 + 1.0 - n as f64
    }

    /// The smallest step between pixels that a float of relative precision `epsilon` still
    /// resolves over this axis: 16 ulp of its largest value (angles: of pi at least, where
    /// they flip).
    pub fn finest_step(&self, epsilon: f64) -> f64 {
        let floor = if self.var.is_angle() {
            std::f64::consts::PI
        } else {
            f64::MIN_POSITIVE
        };
        let largest = self.range.min.abs().max(self.range.max.abs()).max(floor);
        // ulp(x) = epsilon 2^floor(log2 x): pi's is 2 epsilon.
        16.0 * epsilon * largest.log2().floor().exp2()
    }
}

/// How a grid's pixels sample its plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Sampling {
    /// The centres of a regular grid of pixels: every map.
    #[default]
    Centres,
    /// Pairs of starts, side by side (pair `row * width / 2 + col / 2`): the even column's
    /// drawn uniformly over the plane, the odd column's the same start moved by `eps` of the plane's width (along x) or height
    /// (along y), either way, drawn too (back inside when it would leave). The draws are a
    /// hash of (`seed`, pair) that the shaders compute alike: the uncertainty exponent's
    /// samples (`chaoscope boundary`).
    Pairs { seed: u32, eps: f64 },
}

/// PCG's output hash of `v` (O'Neill; the "pcg_hash" of Jarzynski and Olano 2020): the
/// same u32 arithmetic as shaders/common.wgsl `pcg`.
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// A number in [0, 1) of 48 random bits from two hashes (exact in f64; shaders/common.wgsl
/// `unit` forms it alike).
fn unit(a: u32, b: u32) -> f64 {
    (a >> 8) as f64 * (1.0 / 16777216.0) + (b >> 8) as f64 * (1.0 / 281474976710656.0)
}

/// The initial-condition grid: `x` left to right, `y` bottom to top (row 0 at the top), the
/// start's other components from `fixed`, the parameters from the map's. Pixel centres.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(from = "GridRecord")]
pub struct Grid {
    pub width: u32,
    pub height: u32,
    pub x: Axis,
    pub y: Axis,
    /// The start's angles (rad) and angular velocities (rad/s) where no axis sets them.
    pub fixed: State,
    /// Pixel centres, or seeded pairs of starts (see [`Sampling`]).
    pub sampling: Sampling,
}

/// A grid as stores record it: as now, or as written before axes were data (theta1 along x,
/// theta2 along y).
#[derive(serde::Deserialize)]
#[serde(untagged)]
enum GridRecord {
    Plane {
        width: u32,
        height: u32,
        x: Axis,
        y: Axis,
        fixed: State,
        #[serde(default)]
        sampling: Sampling,
    },
    Angles {
        width: u32,
        height: u32,
        theta1: Range,
        theta2: Range,
        omega1: f64,
        omega2: f64,
    },
}

impl From<GridRecord> for Grid {
    fn from(r: GridRecord) -> Grid {
        match r {
            GridRecord::Plane {
                width,
                height,
                x,
                y,
                fixed,
                sampling,
            } => Grid {
                width,
                height,
                x,
                y,
                fixed,
                sampling,
            },
            GridRecord::Angles {
                width,
                height,
                theta1,
                theta2,
                omega1,
                omega2,
            } => Grid::angles(width, height, theta1, theta2, omega1, omega2),
        }
    }
}

impl Grid {
    /// The (theta1, theta2) plane released with angular velocities (`omega1`, `omega2`).
    pub fn angles(
        width: u32,
        height: u32,
        theta1: Range,
        theta2: Range,
        omega1: f64,
        omega2: f64,
    ) -> Self {
        Grid {
            width,
            height,
            x: Axis {
                var: Var::Theta1,
                range: theta1,
            },
            y: Axis {
                var: Var::Theta2,
                range: theta2,
            },
            fixed: State {
                omega1,
                omega2,
                ..State::default()
            },
            sampling: Sampling::Centres,
        }
    }

    /// The whole (theta1, theta2) plane released from rest.
    pub fn square(n: u32) -> Self {
        Grid::angles(n, n, Range::FULL_TURN, Range::FULL_TURN, 0.0, 0.0)
    }

    /// Whether it is the (theta1, theta2) plane, the map of today's flags.
    pub fn is_angle_plane(&self) -> bool {
        self.x.var == Var::Theta1 && self.y.var == Var::Theta2
    }

    /// The distance between neighbouring starts along x: a pixel's width, or a pair's
    /// perturbation along x.
    pub fn x_step(&self) -> f64 {
        match self.sampling {
            Sampling::Centres => self.x.step(self.width),
            Sampling::Pairs { eps, .. } => eps * (self.x.range.max - self.x.range.min),
        }
    }

    pub fn y_step(&self) -> f64 {
        match self.sampling {
            Sampling::Centres => self.y.step(self.height),
            Sampling::Pairs { eps, .. } => eps * (self.y.range.max - self.y.range.min),
        }
    }

    /// (x, y) of pixel (`col`, `row`): its centre, or its member of a pair.
    pub fn xy(&self, col: u32, row: u32) -> (f64, f64) {
        let Sampling::Pairs { seed, eps } = self.sampling else {
            return (self.x_at(col), self.y_at(row));
        };
        let h = pcg(seed ^ pcg(row * (self.width / 2) + col / 2));
        let (xr, yr) = (self.x.range, self.y.range);
        let (wx, wy) = (xr.max - xr.min, yr.max - yr.min);
        let mut xy = [
            xr.min + unit(pcg(h ^ 1), pcg(h ^ 2)) * wx,
            yr.min + unit(pcg(h ^ 3), pcg(h ^ 4)) * wy,
        ];
        if col % 2 == 1 {
            let d = pcg(h ^ 5) & 3;
            let (k, lo, width) = match d >= 2 {
                false => (0, xr.min, wx),
                true => (1, yr.min, wy),
            };
            let step = eps * width;
            let (v, down) = (xy[k], d & 1 == 1);
            let mut moved = if down { v - step } else { v + step };
            if moved < lo || moved > lo + width {
                moved = if down { v + step } else { v - step };
            }
            xy[k] = moved;
        }
        (xy[0], xy[1])
    }

    /// x at the centre of column `col`.
    pub fn x_at(&self, col: u32) -> f64 {
        self.x.at(col, self.width)
    }

    /// y at the centre of row `row` (row 0 is the top, y near its maximum).
    pub fn y_at(&self, row: u32) -> f64 {
        self.y.at_from_max(row, self.height)
    }

    /// Whether a parameter lies on an axis (each pixel then has its own).
    pub fn varies_params(&self) -> bool {
        !(self.x.var.is_state() && self.y.var.is_state())
    }

    /// The parameters and the start of pixel (`col`, `row`) of a map with parameters `p`.
    /// Ratios are set after the values they multiply.
    pub fn pixel(&self, p: &Params, col: u32, row: u32) -> (Params, State) {
        let (x, y) = self.xy(col, row);
        self.at(p, x, y)
    }

    /// The parameters and start at (`x`, `y`) of the plane.
    pub fn at(&self, p: &Params, x: f64, y: f64) -> (Params, State) {
        let (mut p, mut s) = (*p, self.fixed);
        let mut axes = [(self.x.var, x), (self.y.var, y)];
        axes.sort_by_key(|(v, _)| v.is_ratio());
        for (var, value) in axes {
            var.set(value, &mut p, &mut s);
        }
        (p, s)
    }

    /// The start of pixel (`col`, `row`) (its parameters: [`Grid::pixel`]).
    pub fn start(&self, col: u32, row: u32) -> State {
        self.pixel(&Params::default(), col, row).1
    }

    /// Whether the starts come in opposite pairs, pixel (col, row) <-> (width-1-col,
    /// height-1-row) starting from s and -s: both axes components of the start with ranges
    /// centred on 0 and every other component 0. The equations of motion are odd under
    /// y -> -y (losses included), so mirrored starts follow mirrored trajectories and flip at
    /// the same time: half the map is enough. A parameter axis breaks it.
    pub fn point_symmetric(&self) -> bool {
        if self.varies_params()
            || self.sampling != Sampling::Centres
            || self.x.range.mid() != 0.0
            || self.y.range.mid() != 0.0
        {
            return false;
        }
        let s = self.fixed;
        [
            (Var::Theta1, s.theta1),
            (Var::Omega1, s.omega1),
            (Var::Theta2, s.theta2),
            (Var::Omega2, s.omega2),
        ]
        .iter()
        .all(|&(v, value)| value == 0.0 || v == self.x.var || v == self.y.var)
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Whether neighbouring pixels are closer than f32 resolves (16 ulp of the axis's
    /// largest value, of pi for angles): such a grid must be integrated in f64.
    pub fn needs_f64(&self) -> bool {
        self.x_step() < self.x.finest_step(f32::EPSILON as f64)
            || self.y_step() < self.y.finest_step(f32::EPSILON as f64)
    }

    /// Whether neighbouring pixels are closer than even f64 resolves: the map is computed,
    /// but no pixel of it is resolved.
    pub fn beyond_f64(&self) -> bool {
        self.x_step() < self.x.finest_step(f64::EPSILON)
            || self.y_step() < self.y.finest_step(f64::EPSILON)
    }

    /// The plane's corners and a lattice between them (9 x 9 points): where the parameters
    /// and speeds are checked against their ranges and the step's stability.
    pub fn lattice(&self, p: &Params) -> Vec<(Params, State)> {
        let at = |a: &Axis, k: u32| a.range.min + (a.range.max - a.range.min) * k as f64 / 8.0;
        (0..9)
            .flat_map(|i| (0..9).map(move |j| (i, j)))
            .map(|(i, j)| self.at(p, at(&self.x, i), at(&self.y, j)))
            .collect()
    }

    /// The two axes vary different things, each range MIN < MAX, angles within -pi:pi,
    /// every value finite.
    pub fn validate_axes(&self) -> Result<()> {
        use std::f64::consts::PI;
        for (field, a) in [("x", &self.x), ("y", &self.y)] {
            let r = a.range;
            // The angle flags keep their names in errors (`--theta1 -4:4`).
            let field = match a.var {
                Var::Theta1 | Var::Theta2 if self.is_angle_plane() => a.var.name(),
                _ => field,
            };
            if !(r.min.is_finite() && r.max.is_finite()) || r.min >= r.max {
                return Err(Error::invalid(
                    field,
                    format!("{}:{} must be MIN:MAX with MIN < MAX", r.min, r.max),
                ));
            }
            // Allow the user's "-pi:pi" written with a rounded pi.
            let limit = PI + 1e-9;
            if a.var.is_angle() && (r.min < -limit || r.max > limit) {
                return Err(Error::invalid(
                    field,
                    format!(
                        "{}:{} must lie within -pi:pi (a start outside has already flipped)",
                        r.min, r.max
                    ),
                ));
            }
        }
        if self.x.var.overlaps(self.y.var) {
            return Err(Error::invalid(
                "y",
                format!(
                    "{} and {} set the same value: take two different axes",
                    self.x.var.name(),
                    self.y.var.name()
                ),
            ));
        }
        let s = self.fixed;
        super::validate_start(&s)?;
        for (field, v) in [("theta1", s.theta1), ("theta2", s.theta2)] {
            if v.abs() > PI + 1e-9 {
                return Err(Error::invalid(
                    field,
                    format!("{v} must lie within -pi..pi (a start outside has already flipped)"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_limits_are_what_the_engine_accepts() {
        for v in Var::ALL {
            let (r, l) = (v.default_range(), v.limits());
            assert!(l.min <= r.min && r.max <= l.max, "{}", v.name());
            let (mut p, mut s) = (Params::default(), State::default());
            // A parameter at its lower limit passes the parameters' check; half of a positive
            // one's fails. (Below a zero limit, a negative rod may still pass as an
            // equivalent pendulum, which the explorer does not offer.)
            if !v.is_state() {
                v.set(l.min, &mut p, &mut s);
                assert!(crate::params::validate(&p).is_ok(), "{}", v.name());
                if l.min > 0.0 {
                    v.set(l.min / 2.0, &mut p, &mut s);
                    assert!(crate::params::validate(&p).is_err(), "{}", v.name());
                }
            }
        }
        // An angle axis at the turn's ends passes, beyond them fails.
        let plane = |min: f64, max: f64| Grid {
            x: Axis::new(Var::Theta1, min, max),
            ..Grid::square(8)
        };
        let l = Var::Theta1.limits();
        assert!(plane(l.min, l.max).validate_axes().is_ok());
        assert!(plane(l.min - 1e-3, l.max).validate_axes().is_err());
    }

    #[test]
    fn codes_put_the_state_first() {
        let state: Vec<_> = Var::ALL.iter().filter(|v| v.is_state()).collect();
        assert_eq!(
            state,
            [&Var::Theta1, &Var::Omega1, &Var::Theta2, &Var::Omega2]
        );
        for v in Var::ALL {
            assert_eq!(Var::parse(v.name()), Some(v));
            assert_eq!(Var::parse(v.key()), Some(v));
        }
    }

    #[test]
    fn old_records_read_as_the_angle_plane() {
        let old = r#"{"width":4,"height":2,"theta1":{"min":-1.0,"max":1.0},
            "theta2":{"min":-2.0,"max":2.0},"omega1":0.5,"omega2":0.0}"#;
        let g: Grid = serde_json::from_str(old).unwrap();
        let r = |min, max| Range { min, max };
        assert_eq!(g, Grid::angles(4, 2, r(-1.0, 1.0), r(-2.0, 2.0), 0.5, 0.0));
        let again: Grid = serde_json::from_str(&serde_json::to_string(&g).unwrap()).unwrap();
        assert_eq!(again, g);
    }

    #[test]
    fn ratios_compose_with_the_values_they_multiply() {
        let g = Grid {
            x: Axis::new(Var::MassRatio, 1.0, 3.0),
            y: Axis::new(Var::M1, 1.0, 3.0),
            ..Grid::square(2)
        };
        // Pixel (1, 0): m2/m1 = 2.5, m1 = 2.5 (top row): m2 = 6.25 whichever axis comes first.
        let (p, _) = g.pixel(&Params::default(), 1, 0);
        assert_eq!((p.m1, p.m2), (2.5, 6.25));
    }
}
