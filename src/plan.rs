//! A map planned once on the engine a door lends: the path it takes, the checks that depend
//! on that path, the notices to give, and the verdict's finer maps, derived here and nowhere
//! else. Every door plans, then computes ([`Engine::planned_map`]) or fills a store band by
//! band ([`MapPlan::with_band`]).

use crate::engine::{Engine, MapKernels, RunInfo};
use crate::error::{Error, Result};
use crate::field::Field;
use crate::monitor::Monitor;
use crate::spec::{Grid, Integrator, MapSpec, Precision};
use crate::verdict;

/// One map the verdict checks, with the maps it is checked against.
#[derive(Clone, Debug)]
pub struct Checked<S> {
    pub map: S,
    /// Half the step or a tenth of the tolerances, in f64 where the engine has it.
    pub finer: S,
    /// Fixed steps: one finer still, which the finer map must agree with too (a chaotic
    /// pixel's runs at dt and dt/2 agree by chance often enough to break the verdict's
    /// promise at coarse steps: 0.83 % of the resolved pixels wrong at dt 0.05; a chance
    /// agreement of three is rare, 0.46 %, and <= 0.05 % at dt <= 0.01).
    pub finest: Option<S>,
}

/// A map as planned on an engine.
#[derive(Clone, Debug)]
pub struct MapPlan<S> {
    pub spec: S,
    /// The path it takes.
    pub info: RunInfo,
    /// What to tell the user about the engine, the precision and the map on this path.
    pub notices: Vec<String>,
    /// The maps the verdict compares, when it was asked for: the map's own, then the map its
    /// quantity is read off ([`MapSpec::underlying`]), where it has one.
    pub verdict: Option<Vec<Checked<S>>>,
    /// The verdict's rule in a few words and in full (said whether or not it was asked for).
    pub rule: String,
    pub rule_in_full: String,
}

impl<S: MapSpec> MapPlan<S> {
    /// The same plan over rows `first..first + count` only (a store's band).
    pub fn with_band(&self, band: (u32, u32)) -> Self {
        let checked = |c: &Checked<S>| Checked {
            map: c.map.with_band(band),
            finer: c.finer.with_band(band),
            finest: c.finest.as_ref().map(|f| f.with_band(band)),
        };
        MapPlan {
            spec: self.spec.with_band(band),
            verdict: self
                .verdict
                .as_ref()
                .map(|v| v.iter().map(checked).collect()),
            info: self.info.clone(),
            notices: self.notices.clone(),
            rule: self.rule.clone(),
            rule_in_full: self.rule_in_full.clone(),
        }
    }
}

/// The verdict's finer map of `spec` checked as the map is, before any engine is made (f64
/// assumed there: the finer map only moves up to it): its errors say so.
pub fn check_verdict(spec: &impl MapSpec, verdict: bool) -> Result<()> {
    verdict::check_step(spec, verdict)?;
    if verdict {
        check_finer(verdict::finer(spec, true).validate())?;
    }
    Ok(())
}

/// An error of the verdict's finer map, said to be that map's.
fn check_finer(finer: Result<()>) -> Result<()> {
    finer.map_err(|e| match e {
        Error::InvalidSpec { field, reason } => {
            Error::invalid(field, format!("the verdict's finer map: {reason}"))
        }
        e => e,
    })
}

impl Engine {
    /// `spec`'s map planned on this engine, with the verdict's maps when `verdict`: the path
    /// and its notices ([`precision_notices`]), the tolerances within what that path's
    /// precision can follow (an f32 kernel's error estimate is round-off below
    /// [`crate::spec::MIN_TOLERANCE_F32`]), the finer maps' too.
    pub fn plan<S: MapKernels>(&self, spec: &S, verdict: bool) -> Result<MapPlan<S>> {
        let (precision, grid) = (spec.precision(), spec.grid());
        let info = self.map_info(grid, precision);
        let mut notices = self.notices();
        notices.extend(precision_notices(self, precision, grid, &info)?);
        notices.extend(spec.notices(info.path));
        spec.validate_in(info.path.precision())?;
        let checked = |map: S| {
            let finer = verdict::finer(&map, self.has_f64());
            let finest = (map.integrator() == Integrator::Rk4)
                .then(|| verdict::finer(&finer, self.has_f64()));
            Checked { map, finer, finest }
        };
        let own = checked(*spec);
        let (rule, rule_in_full) = (
            verdict::rule_short(spec, &own.finer),
            verdict::rule(spec, &own.finer),
        );
        let verdict = match verdict {
            false => None,
            true => {
                let all: Vec<Checked<S>> = std::iter::once(own)
                    .chain(spec.underlying().map(checked))
                    .collect();
                for c in &all {
                    let path = self.map_info(c.finer.grid(), c.finer.precision()).path;
                    check_finer(c.finer.validate_in(path.precision()))?;
                }
                Some(all)
            }
        };
        Ok(MapPlan {
            spec: *spec,
            info,
            notices,
            verdict,
            rule,
            rule_in_full,
        })
    }

    /// The planned map and, when the plan holds the verdict, its mask: 1 where every map the
    /// verdict compares agrees with its finer ones within the quantity's tolerance.
    pub fn planned_map<S: MapKernels>(
        &self,
        plan: &MapPlan<S>,
        monitor: &Monitor,
    ) -> Result<(Field, Option<Vec<u8>>)> {
        let field = self.map(&plan.spec, monitor)?;
        let Some(checked) = &plan.verdict else {
            return Ok((field, None));
        };
        let agree = |spec: &S, a: &Field, b: &Field| {
            let vouch = spec.quantity().vouch;
            verdict::grid_mask(spec.grid(), a, b, |x, y| vouch.agrees(x, y))
        };
        let mut mask = vec![1u8; field.data.len()];
        for (k, c) in checked.iter().enumerate() {
            let own;
            let map = match k {
                0 => &field,
                _ => {
                    own = self.map(&c.map, monitor)?;
                    &own
                }
            };
            let finer = self.map(&c.finer, monitor)?;
            let mut agreed = agree(&c.map, map, &finer);
            if let Some(finest) = &c.finest {
                let settled = agree(&c.map, &finer, &self.map(finest, monitor)?);
                agreed.iter_mut().zip(settled).for_each(|(m, s)| *m &= s);
            }
            mask.iter_mut().zip(agreed).for_each(|(m, a)| *m &= a);
        }
        Ok((field, Some(mask)))
    }
}

/// What a map's precision means on this engine: f64 asked of a GPU without it is an error
/// naming `precision` when the GPU was asked for, else a note that the CPU runs it; a grid
/// finer than f32 resolves gets a note saying where it runs in f64 (`info`).
fn precision_notices(
    engine: &Engine,
    precision: Precision,
    grid: &Grid,
    info: &RunInfo,
) -> Result<Vec<String>> {
    let mut notices: Vec<String> = engine
        .check_f64(precision, engine.asked())?
        .into_iter()
        .collect();
    if engine.computes_in_f32(precision) && grid.needs_f64() {
        notices.push(f64_notice(grid, info.path.on_gpu(), None));
    }
    if grid.beyond_f64() {
        notices.push(format!(
            "note: the pixel step is {}: neighbouring pixels start from the same numbers, and the verdict ([[resolved]]) marks every pixel unresolved",
            below(grid, crate::spec::F64_MIN_PIXEL_STEP, "even f64")
        ));
    }
    Ok(notices)
}

/// How fine a grid's pixel step is, against the finest `float` resolves (`step`, near pi):
/// the angle plane says it in radians; any other names its axes.
fn below(grid: &Grid, step: f64, float: &str) -> String {
    match grid.is_angle_plane() {
        true => format!("below {step:.1e} rad, finer than {float} resolves near pi"),
        false => format!(
            "finer along {} or {} than {float} resolves",
            grid.x.var.name(),
            grid.y.var.name()
        ),
    }
}

/// The one note that maps run in f64 because their pixel step is finer than f32 resolves:
/// a map's, or a film's from the frame (and its width) where its maps turn to f64.
pub fn f64_notice(grid: &Grid, on_gpu: bool, from: Option<(u32, f64)>) -> String {
    let (when, what) = match from {
        None => (String::new(), "the map runs"),
        Some((frame, width)) => (
            format!("from frame {frame} on (width {width:.3e}) "),
            "those frames run",
        ),
    };
    format!(
        "note: {when}the pixel step is {}; {what} on the {} in f64",
        below(grid, crate::spec::F32_MIN_PIXEL_STEP, "f32"),
        if on_gpu { "GPU" } else { "CPU" }
    )
}
