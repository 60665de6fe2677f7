//! The two map families' specs: flip-time maps and divergence maps, and the rows a run covers.

use super::Indicator;
use super::stability::{validate_speeds, validate_stability};
use super::{
    ACCURATE, ACCURATE_FTLE, Grid, Integrator, Precision, Stepping, validate_grid_holding,
    validate_params, validate_plane, validate_stepping,
};
use crate::error::{Error, Result};
use crate::model::Params;

/// What a flip map shows of each start's first flip.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FlipMeasure {
    /// The time until either arm first flips over ([`crate::quantity::FLIP_TIME`]).
    #[default]
    Time,
    /// Which arm flips first and which way ([`crate::quantity::FLIP_KIND`]).
    Kind,
}

impl FlipMeasure {
    pub const ALL: [FlipMeasure; 2] = [FlipMeasure::Time, FlipMeasure::Kind];

    pub fn name(self) -> &'static str {
        match self {
            FlipMeasure::Time => "time",
            FlipMeasure::Kind => "kind",
        }
    }
}

/// A flip map: for every start, its first flip over the top (when, or which arm which way).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlipSpec {
    /// What the map shows of the first flip.
    pub measure: FlipMeasure,
    pub params: Params,
    pub grid: Grid,
    pub stepping: Stepping,
    /// Stop integrating a pixel once it has flipped, and skip the starts that cannot flip.
    /// Off only for benchmarks (every pixel runs every step).
    pub early_exit: bool,
    /// Integrate only the top half of a point-symmetric grid and mirror it (same map, half
    /// the work). Off for benchmarks of raw throughput and for checking the symmetry.
    pub use_symmetry: bool,
    /// The GPU's precision (the CPU is always f64); grids finer than f32 resolves run in
    /// f64 whatever is asked.
    pub precision: Precision,
    pub integrator: Integrator,
    /// Only these rows of the grid (first, count): a unit of a store's work. The map then
    /// holds just them (nothing mirrored).
    pub band: Option<(u32, u32)>,
}

/// The rows a map run integrates and the field it gives: rows `first..first + count` of
/// the grid; `whole`: the field is the whole grid, the rows below `count` mirrored from them
/// (`first` is 0), else the field is just those rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowSpan {
    pub first: u32,
    pub count: u32,
    pub whole: bool,
}

impl RowSpan {
    /// The whole grid, `count` top rows integrated.
    pub fn top(count: u32) -> Self {
        RowSpan {
            first: 0,
            count,
            whole: true,
        }
    }

    /// The rows a map over `grid` integrates: the `band`'s, or the top half when the map
    /// `mirrors` a point-symmetric grid, or all.
    pub fn of(grid: &Grid, band: Option<(u32, u32)>, mirrors: bool) -> Self {
        match band {
            Some((first, count)) => RowSpan {
                first,
                count,
                whole: false,
            },
            None if mirrors && grid.point_symmetric() => RowSpan::top(grid.height.div_ceil(2)),
            None => RowSpan::top(grid.height),
        }
    }

    /// Rows of the field this span gives on `grid`.
    pub fn field_rows(&self, grid: &Grid) -> u32 {
        if self.whole { grid.height } else { self.count }
    }
}

/// Largest number of steps one run may take (the step counter is a u32 on the GPU, and f32
/// counts steps exactly only up to 2^24).
pub const MAX_STEPS: u32 = 1 << 24;

impl FlipSpec {
    pub fn new(params: Params, grid: Grid, stepping: Stepping) -> Self {
        FlipSpec {
            measure: FlipMeasure::Time,
            params,
            grid,
            stepping,
            early_exit: true,
            use_symmetry: true,
            precision: Precision::F32,
            integrator: Integrator::Rk4,
            band: None,
        }
    }

    /// The same map with `--accurate`'s settings ([`ACCURATE`]): the one place they are
    /// spelt out for flip maps.
    pub fn accurate(self) -> Self {
        let (precision, integrator, dt) = ACCURATE;
        let stepping = Stepping {
            dt,
            ..self.stepping
        };
        self.restepped(stepping, integrator, precision)
    }

    /// Rows to integrate: the band's, or all from the top, or the top half when the other
    /// half mirrors it.
    pub fn rows_to_integrate(&self) -> u32 {
        self.row_span().count
    }

    pub fn row_span(&self) -> RowSpan {
        RowSpan::of(&self.grid, self.band, self.mirrors())
    }

    /// Whether a point-symmetric grid's bottom half is the top half mirrored: flip times
    /// are (the mirrored start flips at the same time), flip kinds are not (the same arm
    /// flips the other way), so those are integrated whole.
    pub fn mirrors(&self) -> bool {
        self.use_symmetry && self.measure == FlipMeasure::Time
    }

    pub fn validate(&self) -> Result<()> {
        validate_params(&self.params)?;
        validate_grid_holding(&self.grid, self.band.map_or(self.grid.height, |b| b.1))?;
        validate_stepping(&self.stepping)?;
        if self.measure == FlipMeasure::Kind && self.integrator != Integrator::Rk4 {
            return Err(Error::invalid(
                "integrator",
                "the flip kind is located with rk4 only (take [[integrator=rk4]])",
            ));
        }
        // The f64 range here; the f32 GPU's own is checked where the engine has picked it.
        self.integrator.validate(Precision::F64)?;
        if let Some((first, count)) = self.band
            && (count == 0 || first as u64 + count as u64 > self.grid.height as u64)
        {
            return Err(Error::invalid(
                "tile",
                format!(
                    "rows {first}..{} lie outside the grid's {} rows",
                    first as u64 + count as u64,
                    self.grid.height
                ),
            ));
        }
        validate_plane(&self.params, &self.grid, &self.stepping)
    }
}

/// How the divergence of nearby starts is measured.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Method {
    /// Tangent (variational) equations alongside the state (Benettin et al.).
    Tangent,
    /// A second trajectory started `eps` away (Euclidean in (theta1, omega1, theta2, omega2)),
    /// pulled back to `eps` at every renormalisation.
    Twin { eps: f64 },
}

/// A divergence map: the largest finite-time Lyapunov exponent (1/s) of every start.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LyapunovSpec {
    pub params: Params,
    pub grid: Grid,
    pub stepping: Stepping,
    pub method: Method,
    /// Renormalisation interval (s), a whole number of steps.
    pub renorm: f64,
    /// With the tangent method, integrate only the top half of a point-symmetric grid and
    /// mirror it: the tangent equations are even under y -> -y (the Jacobian of an odd field
    /// is even), so mirrored starts get the same exponent bit for bit. Twins are not mirrored
    /// (the twin of -y sits at -y + eps, the mirror of y - eps, not of y + eps).
    pub use_symmetry: bool,
    /// The GPU's precision (the CPU is always f64); grids finer than f32 resolves run in f64.
    pub precision: Precision,
    /// Only these rows of the grid (first, count), as for [`FlipSpec::band`].
    pub band: Option<(u32, u32)>,
    /// How the state and the tangent vector are stepped: RK4 at `dt`, or DP54 with every
    /// pendulum's own steps (of at most `dt`) between renormalisations, which it lands on
    /// exactly; the error is controlled over the state and the tangent vector. Tangent method
    /// only.
    pub integrator: Integrator,
    /// What the map measures of each start (stores written before it hold the FTLE).
    #[serde(default)]
    pub indicator: Indicator,
}

impl LyapunovSpec {
    /// The FTLE map of `chaoscope lyapunov` by default: the tangent method renormalised every
    /// 0.1 s, mirrored, f32 on the GPU, RK4.
    pub fn new(params: Params, grid: Grid, stepping: Stepping) -> Self {
        LyapunovSpec {
            params,
            grid,
            stepping,
            method: Method::Tangent,
            renorm: 0.1,
            use_symmetry: true,
            precision: Precision::F32,
            band: None,
            integrator: Integrator::Rk4,
            indicator: Indicator::default(),
        }
    }

    /// Rows to integrate: the band's, or all from the top, or the top half when the other
    /// half mirrors it.
    pub fn rows_to_integrate(&self) -> u32 {
        self.row_span().count
    }

    /// The same map with `lyapunov --accurate`'s settings ([`ACCURATE_FTLE`], steps of the
    /// longest whole fraction of `renorm` within its largest step): the one place they are
    /// spelt out for divergence maps.
    pub fn accurate(self) -> Self {
        let (precision, integrator, largest) = ACCURATE_FTLE;
        let dt = self.renorm / (self.renorm / largest).ceil().max(1.0);
        let stepping = Stepping {
            dt,
            ..self.stepping
        };
        self.restepped(stepping, integrator, precision)
    }

    /// Whether the tangent map's point symmetry applies (see `use_symmetry`).
    pub fn mirrors(&self) -> bool {
        self.use_symmetry && self.method == Method::Tangent
    }

    pub fn row_span(&self) -> RowSpan {
        RowSpan::of(&self.grid, self.band, self.mirrors())
    }

    /// Steps between renormalisations (the last interval may be shorter).
    pub fn renorm_steps(&self) -> u32 {
        ((self.renorm / self.stepping.dt).round() as u32).max(1)
    }

    pub fn validate(&self) -> Result<()> {
        validate_params(&self.params)?;
        validate_grid_holding(&self.grid, self.band.map_or(self.grid.height, |b| b.1))?;
        validate_plane(&self.params, &self.grid, &self.stepping)?;
        self.validate_run()
    }

    /// Everything but the grid (a single-point run has none).
    pub fn validate_run(&self) -> Result<()> {
        validate_params(&self.params)?;
        validate_stepping(&self.stepping)?;
        validate_stability(&self.params, &self.stepping)?;
        let g = &self.grid;
        validate_speeds(&self.params, &self.stepping, g.fixed.omega1, g.fixed.omega2)?;
        let k = self.renorm / self.stepping.dt;
        if !(self.renorm.is_finite() && self.renorm > 0.0)
            || k.round() < 1.0
            || (k - k.round()).abs() > 1e-9 * k
            || self.renorm > self.stepping.t_max
        {
            return Err(Error::invalid(
                "renorm",
                format!(
                    "{} s must be a whole multiple of the time step {} s and at most the run's {} s",
                    self.renorm, self.stepping.dt, self.stepping.t_max
                ),
            ));
        }
        self.integrator.validate(Precision::F64)?;
        self.indicator.validate(Precision::F64)?;
        let measure = self.indicator.measure();
        if measure.tangent_only() && self.method != Method::Tangent {
            return Err(Error::invalid(
                "method",
                format!(
                    "the {} follows tangent vectors: take [[method=tangent]]",
                    self.indicator.title()
                ),
            ));
        }
        if !(self.integrator == Integrator::Rk4 || measure.adaptive()) {
            let adaptive: Vec<String> = crate::measure::MEASURES
                .iter()
                .filter(|m| m.adaptive())
                .map(|m| m.names().join(", "))
                .collect();
            return Err(Error::invalid(
                "integrator",
                format!(
                    "the {} steps with rk4 only (dp54 steps {})",
                    self.indicator.title(),
                    adaptive.join(", ")
                ),
            ));
        }
        match (self.method, self.integrator) {
            (_, Integrator::Rk4) | (Method::Tangent, Integrator::Dp54 { .. }) => {}
            (Method::Twin { .. }, _) | (_, Integrator::Dop853 { .. }) => {
                return Err(Error::invalid(
                    "integrator",
                    "divergence maps step adaptively with dp54 and the tangent method only",
                ));
            }
        }
        if let Method::Twin { eps } = self.method
            && !(eps.is_finite() && eps > 0.0 && eps <= 0.1)
        {
            return Err(Error::invalid(
                "eps",
                format!("{eps} must be in (0, 0.1]: the twin must stay in the linear regime"),
            ));
        }
        Ok(())
    }
}

/// A map of either family, as data: a sweep's frame, and what a store records it holds.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum AnyMap {
    Flip(FlipSpec),
    Lyapunov(LyapunovSpec),
}

/// `$body` with `$s` bound to the spec of either family inside `$map` (an [`AnyMap`]).
macro_rules! on_any {
    ($map:expr, $s:ident => $body:expr) => {
        match $map {
            $crate::spec::AnyMap::Flip($s) => $body,
            $crate::spec::AnyMap::Lyapunov($s) => $body,
        }
    };
}
pub(crate) use on_any;

impl MapSpec for AnyMap {
    fn quantity(&self) -> &'static crate::quantity::Quantity {
        on_any!(self, s => s.quantity())
    }
    fn params(&self) -> Params {
        on_any!(self, s => s.params())
    }
    fn grid(&self) -> &Grid {
        on_any!(self, s => s.grid())
    }
    fn stepping(&self) -> Stepping {
        on_any!(self, s => s.stepping())
    }
    fn precision(&self) -> Precision {
        on_any!(self, s => s.precision())
    }
    fn integrator(&self) -> Integrator {
        on_any!(self, s => s.integrator())
    }
    fn mirrors(&self) -> bool {
        on_any!(self, s => s.mirrors())
    }
    fn row_span(&self) -> RowSpan {
        on_any!(self, s => s.row_span())
    }
    fn validate(&self) -> Result<()> {
        on_any!(self, s => MapSpec::validate(s))
    }
    fn validate_in(&self, precision: Precision) -> Result<()> {
        on_any!(self, s => s.validate_in(precision))
    }
    fn counted(&self, x: f32) -> bool {
        on_any!(self, s => s.counted(x))
    }
    fn counted_rule(&self) -> String {
        on_any!(self, s => s.counted_rule())
    }
    fn with_band(&self, band: (u32, u32)) -> Self {
        on_any!(self, s => s.with_band(band).any())
    }
    fn on_grid(&self, grid: Grid) -> Self {
        on_any!(self, s => s.on_grid(grid).any())
    }
    fn restepped(&self, stepping: Stepping, integrator: Integrator, precision: Precision) -> Self {
        on_any!(self, s => s.restepped(stepping, integrator, precision).any())
    }
    fn underlying(&self) -> Option<Self> {
        on_any!(self, s => s.underlying().map(|u| u.any()))
    }
    fn any(&self) -> AnyMap {
        *self
    }
}

/// What the one map path (the engine's entry, the verdict, the store) needs of a map's spec,
/// whichever quantity it measures: a map is its quantity's settings over a grid, stepped in a
/// precision by an integrator, optionally over a band of rows.
pub trait MapSpec: Copy + std::fmt::Debug + PartialEq + Send + Sync {
    /// The quantity's entry in [`crate::quantity::QUANTITIES`].
    fn quantity(&self) -> &'static crate::quantity::Quantity;
    fn params(&self) -> Params;
    fn grid(&self) -> &Grid;
    fn stepping(&self) -> Stepping;
    fn precision(&self) -> Precision;
    fn integrator(&self) -> Integrator;
    /// Whether a point-symmetric grid's bottom half is the top half mirrored.
    fn mirrors(&self) -> bool;
    /// The rows a run integrates and the field it gives.
    fn row_span(&self) -> RowSpan;
    /// Every field in range (the f64 tolerances; the f32 GPU's are checked once the engine
    /// has picked the path).
    fn validate(&self) -> Result<()>;
    /// Whether the summary counts a pixel of value `x` (its quantity's rule).
    fn counted(&self, x: f32) -> bool {
        (self.quantity().counted)(x)
    }
    /// Which pixels those are, in words.
    fn counted_rule(&self) -> String {
        self.quantity().counted_rule.to_string()
    }
    /// What the path's `precision` must hold beyond [`MapSpec::validate`] (the f32 GPU's
    /// tolerance floor), once the engine has picked it.
    fn validate_in(&self, precision: Precision) -> Result<()> {
        self.integrator().validate(precision)
    }
    /// The same map over rows `first..first + count` only.
    fn with_band(&self, band: (u32, u32)) -> Self;
    /// The same map over another grid.
    fn on_grid(&self, grid: Grid) -> Self;
    /// The same map stepped otherwise.
    fn restepped(&self, stepping: Stepping, integrator: Integrator, precision: Precision) -> Self;
    /// The map of the event this quantity is read off, when it has one (the flip kind: the
    /// flip time): the verdict vouches for a pixel only where that map is resolved too (two
    /// chaotic runs can name the same class by chance, not the same flip).
    fn underlying(&self) -> Option<Self> {
        None
    }
    /// The map as data of either family.
    fn any(&self) -> AnyMap;
}

/// The accessors every spec type shares (its fields of the same names, and its own mirrors
/// and validate).
macro_rules! map_spec_fields {
    ($t:ident) => {
        fn params(&self) -> Params {
            self.params
        }
        fn grid(&self) -> &Grid {
            &self.grid
        }
        fn stepping(&self) -> Stepping {
            self.stepping
        }
        fn precision(&self) -> Precision {
            self.precision
        }
        fn integrator(&self) -> Integrator {
            self.integrator
        }
        fn mirrors(&self) -> bool {
            $t::mirrors(self)
        }
        fn row_span(&self) -> RowSpan {
            $t::row_span(self)
        }
        fn validate(&self) -> Result<()> {
            $t::validate(self)
        }
        fn with_band(&self, band: (u32, u32)) -> Self {
            $t {
                band: Some(band),
                ..*self
            }
        }
        fn on_grid(&self, grid: Grid) -> Self {
            $t { grid, ..*self }
        }
        fn restepped(
            &self,
            stepping: Stepping,
            integrator: Integrator,
            precision: Precision,
        ) -> Self {
            $t {
                stepping,
                integrator,
                precision,
                ..*self
            }
        }
    };
}

impl MapSpec for FlipSpec {
    fn quantity(&self) -> &'static crate::quantity::Quantity {
        match self.measure {
            FlipMeasure::Time => &crate::quantity::FLIP_TIME,
            FlipMeasure::Kind => &crate::quantity::FLIP_KIND,
        }
    }
    map_spec_fields!(FlipSpec);
    fn any(&self) -> AnyMap {
        AnyMap::Flip(*self)
    }
    fn underlying(&self) -> Option<Self> {
        (self.measure == FlipMeasure::Kind).then_some(FlipSpec {
            measure: FlipMeasure::Time,
            ..*self
        })
    }
}

impl MapSpec for LyapunovSpec {
    fn quantity(&self) -> &'static crate::quantity::Quantity {
        self.indicator.quantity()
    }
    map_spec_fields!(LyapunovSpec);
    fn any(&self) -> AnyMap {
        AnyMap::Lyapunov(*self)
    }
    fn validate_in(&self, precision: Precision) -> Result<()> {
        self.integrator.validate(precision)?;
        self.indicator.validate(precision)
    }
    /// The pixels its measure counts (an alignment index: the starts it stopped).
    fn counted(&self, x: f32) -> bool {
        self.indicator.measure().counted(self.indicator, x)
    }
    fn counted_rule(&self) -> String {
        self.indicator.measure().counted_rule(self.indicator)
    }
}
