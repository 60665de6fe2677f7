//! A plane as a user asks for it (the command line's `--x`, `--y` and angle flags, Python's
//! keywords): what each axis varies, perhaps with its range, and the start's values; checked
//! and completed into a [`Grid`].

use super::{Axis, Grid, Range, Var};
use crate::error::{Error, Result};
use crate::model::{Params, State};
use crate::params::ParamSources;

/// An angle as asked: a range (along an axis) or one value (the start's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Angles {
    Range(Range),
    Point(f64),
}

/// What an axis varies, perhaps with its range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisAsked {
    pub var: Var,
    pub range: Option<Range>,
}

/// A plane as asked; an error names the field (`x`, `theta1`...) it is about.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlaneAsked {
    /// theta1 when None.
    pub x: Option<AxisAsked>,
    /// theta2 when None.
    pub y: Option<AxisAsked>,
    pub theta1: Option<Angles>,
    pub theta2: Option<Angles>,
    pub omega1: Option<f64>,
    pub omega2: Option<f64>,
}

impl PlaneAsked {
    /// The grid of `size` pixels asked for: an angle gives its range when it lies along an
    /// axis (unless the axis gives it) and its start otherwise; a parameter or angular
    /// velocity along an axis takes its range from the axis.
    pub fn grid(&self, (width, height): (u32, u32)) -> Result<Grid> {
        let x = self.x.unwrap_or(AxisAsked {
            var: Var::Theta1,
            range: None,
        });
        let y = self.y.unwrap_or(AxisAsked {
            var: Var::Theta2,
            range: None,
        });
        let given = |var: Var| -> Option<Angles> {
            match var {
                Var::Theta1 => self.theta1,
                Var::Theta2 => self.theta2,
                Var::Omega1 => self.omega1.map(Angles::Point),
                Var::Omega2 => self.omega2.map(Angles::Point),
                _ => None,
            }
        };
        let axis = |field: &'static str, a: AxisAsked| -> Result<Axis> {
            let range = match (a.range, given(a.var)) {
                (Some(_), Some(_)) => {
                    return Err(Error::invalid(
                        a.var.name(),
                        format!("{} lies along {field}, which gives its range", a.var.name()),
                    ));
                }
                (Some(r), None) | (None, Some(Angles::Range(r))) => r,
                (None, None) if a.var.is_angle() => Range::FULL_TURN,
                (None, Some(Angles::Point(_))) if a.var.is_angle() => {
                    return Err(Error::invalid(
                        a.var.name(),
                        format!(
                            "{} lies along {field}: give its range MIN:MAX",
                            a.var.name()
                        ),
                    ));
                }
                _ => {
                    return Err(Error::invalid(
                        field,
                        format!("{} along {field} needs a range MIN:MAX", a.var.name()),
                    ));
                }
            };
            Ok(Axis { var: a.var, range })
        };
        let (x, y) = (axis("x", x)?, axis("y", y)?);
        let mut fixed = State::default();
        let mut params = Params::default();
        for var in [Var::Theta1, Var::Omega1, Var::Theta2, Var::Omega2] {
            if var == x.var || var == y.var {
                continue;
            }
            match given(var) {
                Some(Angles::Point(v)) => var.set(v, &mut params, &mut fixed),
                Some(Angles::Range(_)) => {
                    return Err(Error::invalid(
                        var.name(),
                        format!(
                            "{} lies along no axis (x is {}, y is {}): give its start, one angle",
                            var.name(),
                            x.var.name(),
                            y.var.name()
                        ),
                    ));
                }
                None => {}
            }
        }
        Ok(Grid {
            width,
            height,
            x,
            y,
            fixed,
            sampling: Default::default(),
        })
    }
}

/// That no value given here is one that varies along a map's axis or a sweep (`along`:
/// the field that names the axis, and what it varies): the axis would override it
/// silently. A pair (rod masses, joint damping) may give the part an axis sets as 0,
/// so that its other part can be given.
pub fn check_along(sources: &ParamSources, along: &[(&'static str, Var)]) -> Result<()> {
    let one = |field, v: Option<f64>| v.map(|v| (field, vec![(field, v)]));
    let pair = |field, parts: [&'static str; 2], v: Option<(f64, f64)>| {
        v.map(|(a, b)| (field, vec![(parts[0], a), (parts[1], b)]))
    };
    let given = [
        one("m1", sources.m1),
        one("m2", sources.m2),
        one("l1", sources.l1),
        one("l2", sources.l2),
        one("g", sources.g),
        pair("rod_mass", ["rod1", "rod2"], sources.rod_mass),
        pair("joint_damping", ["joint1", "joint2"], sources.joint_damping),
    ];
    for (field, parts) in given.into_iter().flatten() {
        for &(axis, var) in along {
            let single = parts.len() == 1;
            if let Some((part, _)) = parts
                .iter()
                .find(|(part, v)| var.writes().contains(part) && (single || *v != 0.0))
            {
                let hint = match single {
                    true => "leave one of them out".to_string(),
                    false => format!("give its {part} part as 0, or leave it out"),
                };
                return Err(Error::invalid(
                    field,
                    format!(
                        "{} along {axis} sets {part}, which this value would give too: {hint}",
                        var.name()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The parameters of one pixel of a parameter plane: the sources' with each of `at` (a
/// parameter axis's variable and its value there) set as the map sets it, ratios after the
/// values they multiply. Each must be a parameter (a start's component has its own value),
/// within its range, set by no other of `at` nor by a value the sources give.
pub fn resolve_at(sources: &ParamSources, at: &[(Var, f64)]) -> Result<Params> {
    for (k, &(var, v)) in at.iter().enumerate() {
        if var.is_state() {
            return Err(Error::invalid(
                "at",
                format!(
                    "{} is a component of the start, given by its own value",
                    var.name()
                ),
            ));
        }
        let r = var.limits();
        if !(v.is_finite() && r.min <= v && v <= r.max) {
            return Err(Error::invalid(
                "at",
                format!("{}={v} must be from {} to {}", var.name(), r.min, r.max),
            ));
        }
        if let Some((other, _)) = at[..k].iter().find(|(o, _)| o.overlaps(var)) {
            return Err(Error::invalid(
                "at",
                format!("{} and {} set the same value", other.name(), var.name()),
            ));
        }
    }
    let along: Vec<(&'static str, Var)> = at.iter().map(|&(v, _)| ("[[at]]", v)).collect();
    check_along(sources, &along)?;
    let mut p = sources.resolve()?;
    let mut start = State::default();
    let (ratios, values): (Vec<_>, Vec<_>) = at.iter().partition(|(v, _)| v.is_ratio());
    for (var, v) in values.into_iter().chain(ratios) {
        var.set(v, &mut p, &mut start);
    }
    crate::params::validate(&p)?;
    Ok(p)
}

/// The parameters of a map on `grid`, none given that an axis sets ([`check_along`]).
pub fn resolve_on(sources: &ParamSources, grid: &Grid) -> Result<Params> {
    check_along(sources, &[("x", grid.x.var), ("y", grid.y.var)])?;
    sources.resolve()
}
