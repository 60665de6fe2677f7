//! The divergence family's measures, a unit each: what a map of the family measures of each
//! start (the largest exponent, the spectrum, alignment indices, MEGNO and the FLI, Lagrangian
//! descriptors), the names every door asks for it by, its options and their rules, its
//! picture, its GPU entry and its CPU accumulator. [`MEASURES`] is the one list the doors
//! iterate (`--indicator`, Python's `indicator=`, sweeps' and the explorer's maps, the bench);
//! [`Indicator::measure`] is the one place an indicator is matched to its family. A new
//! measure is a file here (and its WGSL, if it has a kernel of its own) and its lines below.

mod alignment;
mod descriptor;
mod ftle;
mod growth;
pub(crate) mod indicator;
mod ofli;
mod range;
mod rli;
mod spectrum;

use crate::error::{Error, Result};
use crate::field::Field;
use crate::field::Precision;
use crate::model::{Params, State};
use crate::quantity::Quantity;
use crate::spec::{Integrator, Stepping};

pub use descriptor::DESCRIPTOR_POWERS;
pub use indicator::{ALIGNED, ALIGNED_F32_FLOOR, Alignment, Indicator};
pub use range::{End, FTLE_RANGE, RangeRule};

/// A map's line in the kinds' table.
pub struct MapKindEntry {
    pub quantity: &'static Quantity,
    /// Its name in `sweep --map`.
    pub name: &'static str,
    /// Its name in the explorer's queries (`kind=`).
    pub short: &'static str,
    /// The explorer's menu entry.
    pub label: &'static str,
    /// What its colours mean, under the explorer's colour bar; `{ends}` stands where the
    /// picture's dark and bright ends are named, with the meanings `low` and `high` of its
    /// low and high values in the order the picture draws them (`render::legend`).
    pub legend: &'static str,
    /// What its low values mean ("" where its colours have no order).
    pub low: &'static str,
    /// What its high values mean.
    pub high: &'static str,
    /// Whether its colours span a range the user may set (`--colour-range`).
    pub ranged: bool,
    /// Whether it has accurate settings (`--accurate`: f64, adaptive steps).
    pub accurate: bool,
    /// The divergence family's measure a front door asks for by this name (None: a flip map).
    pub indicator: Option<Indicator>,
}

/// Every family, in the order the doors list them.
pub static MEASURES: [&dyn Measure; 7] = [
    &ftle::Ftle,
    &spectrum::Spectrum,
    &alignment::AlignmentIndex,
    &growth::Growth,
    &descriptor::Descriptor,
    &ofli::Ofli,
    &rli::Rli,
];

impl Indicator {
    /// Its family.
    pub fn measure(self) -> &'static dyn Measure {
        match self {
            Indicator::Ftle => &ftle::Ftle,
            Indicator::Exponent(_) | Indicator::ExponentSum => &spectrum::Spectrum,
            Indicator::Alignment { .. } | Indicator::AlignmentTime { .. } => {
                &alignment::AlignmentIndex
            }
            Indicator::Megno | Indicator::Fli => &growth::Growth,
            Indicator::Descriptor { .. } => &descriptor::Descriptor,
            Indicator::Ofli => &ofli::Ofli,
            Indicator::Rli { .. } => &rli::Rli,
        }
    }

    /// The quantity it measures.
    pub fn quantity(self) -> &'static Quantity {
        self.measure().quantity(self)
    }

    /// Tangent vectors it follows (0: none).
    pub fn vectors(self) -> u32 {
        self.measure().vectors(self)
    }

    /// Its name in words, for the picture and the summary ("log10 SALI").
    pub fn title(self) -> String {
        self.measure().title(self)
    }

    /// Its settings in range for `precision`.
    pub fn validate(self, precision: Precision) -> Result<()> {
        self.measure().validate(self, precision)
    }

    /// The name a door asks for it by and its options, as (field, value): the inverse of
    /// [`IndicatorAsked::indicator`].
    pub fn spelled(self) -> (&'static str, Vec<(Opt, String)>) {
        self.measure().spelled(self)
    }
}

/// An option some measures take: the job's field a door spells it from (`--ld-p`,
/// `ld_p=`), what it sets (`{field}` where another field is named: the door spells it),
/// and its values. Each measure declares its own; the doors iterate [`options`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Opt {
    pub field: &'static str,
    pub help: &'static str,
    /// Whole numbers within this range (inclusive); None: any number, the measure's
    /// [`Measure::validate`] checks it.
    pub whole: Option<(u8, u8)>,
    /// The values the explorer offers besides the whole ones (its f32 runs' choices).
    pub offered: &'static [f64],
}

/// Every option the measures take, each once, in the list's order.
pub fn options() -> Vec<Opt> {
    let mut out: Vec<Opt> = Vec::new();
    for m in MEASURES {
        for name in m.names() {
            for opt in m.options(name) {
                if !out.iter().any(|o| o.field == opt.field) {
                    out.push(*opt);
                }
            }
        }
    }
    out
}

/// `text` with every `{field}` of an option, and `{indicator}`, spelt by `spell`.
pub fn spelt(text: &str, spell: &impl Fn(&str) -> String) -> String {
    let mut text = text.replace("{indicator}", &spell("indicator"));
    for opt in options() {
        text = text.replace(&format!("{{{}}}", opt.field), &spell(opt.field));
    }
    text
}

/// Where a measure's map is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Runs {
    /// The divergence kernel (`gpu::lyapunov`, `cpu::ftle_map`): tangent or twin, RK4 or DP54.
    Divergence,
    /// The indicators' kernel (`shaders/indicators.wgsl` and the measures' own WGSL) at
    /// `entry`, and `cpu::indicator_map`.
    Indicators(GpuEntry),
}

/// A measure's entry in the indicators' kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuEntry {
    /// Its advance entry point (after the shared `indicator_init`).
    pub entry: &'static str,
    /// The entry that steps with DP54 (its dispatches count renormalisation windows), if any.
    pub adaptive: Option<&'static str>,
    /// `params.measure`: which value the entry writes.
    pub measure: u32,
    /// `params.setting`: the alignment threshold, the descriptor's power.
    pub setting: f64,
    /// What one step costs, in plain RK4 steps (the progress bar's units of work).
    pub cost: u64,
}

/// A tangent step costs about this many plain steps, per vector.
pub const TANGENT_COST: u64 = 3;

pub use crate::render::Look;

/// One start's run on the CPU: the spec, the start, where the columns go at every
/// renormalisation (`sample(t, columns)`) and the progress tick (`tick(steps done)`).
pub struct CpuRun<'a> {
    pub params: Params,
    pub stepping: Stepping,
    pub integrator: Integrator,
    /// Steps in a renormalisation window.
    pub renorm_steps: u32,
    pub start: State,
    pub sample: &'a mut dyn FnMut(f64, &[f64]),
    pub tick: &'a dyn Fn(u32) -> Result<()>,
}

impl CpuRun<'_> {
    /// Whether the `k`-th step ends a renormalisation window.
    pub fn renormalise(&self, k: u32) -> bool {
        k.is_multiple_of(self.renorm_steps) || k == self.stepping.steps()
    }
}

/// A divergence-family measure: everything that decides on its indicators.
pub trait Measure: Sync {
    /// The names a door asks for its indicators by, in the order the doors list them.
    fn names(&self) -> &'static [&'static str];
    /// What its names map, for a door's help: (names, what, with `{field}` where an option is
    /// named, the door spelling it as its flag or keyword); an empty `what` says nothing.
    fn about(&self) -> &'static [(&'static str, &'static str)];
    /// The options it takes when asked by `name`.
    fn options(&self, name: &str) -> &'static [Opt];
    /// The indicator asked by `name` (one of [`Measure::names`]), its options as `asked`
    /// gives them or their defaults.
    fn asked(&self, name: &str, asked: &IndicatorAsked) -> Indicator;
    /// The name `i` is asked by, and its options with their values.
    fn spelled(&self, i: Indicator) -> (&'static str, Vec<(Opt, String)>);
    fn quantity(&self, i: Indicator) -> &'static Quantity;
    /// Tangent vectors it follows (0: none, a plain trajectory each way).
    fn vectors(&self, i: Indicator) -> u32;
    fn title(&self, i: Indicator) -> String;
    /// Its name where a picture's colour range is written down.
    fn short_title(&self, i: Indicator) -> String {
        self.title(i)
    }
    /// Its settings in range for `precision` (the error names the option's field).
    fn validate(&self, _i: Indicator, _precision: Precision) -> Result<()> {
        Ok(())
    }
    /// Whether it has accurate settings (f64, adaptive steps).
    fn accurate(&self) -> bool {
        false
    }
    /// Whether it steps with DP54 too (else RK4 only).
    fn adaptive(&self) -> bool {
        false
    }
    /// Whether it needs the tangent method (the FTLE has twins too).
    fn tangent_only(&self) -> bool {
        true
    }
    /// Whether its tangent vectors are renormalised every `renorm`.
    fn renormalised(&self) -> bool {
        true
    }
    fn runs(&self, i: Indicator) -> Runs;
    /// The map's value from the GPU entry's raw value at t-max `t_end` (not NaN).
    fn finish(&self, _i: Indicator, raw: f64, _t_end: f64) -> f32 {
        raw as f32
    }
    /// The columns a single start's run writes after `t`.
    fn columns(&self, i: Indicator) -> &'static [&'static str];
    /// One start's run on the CPU (f64), its columns sampled at every renormalisation: the
    /// map's value.
    fn cpu(&self, i: Indicator, run: &mut CpuRun) -> Result<f64>;
    /// All four exponents' layers make its map (the spectrum).
    fn of_spectrum(&self, _i: Indicator, _layers: &[Field; 4]) -> Option<Field> {
        None
    }
    fn look(&self, i: Indicator, t_max: f64) -> Look;
    /// The rule of its map's colour range by default (data: the browser page applies it too).
    fn range_rule(&self, i: Indicator, t_max: f64) -> RangeRule;
    /// The colour range of its map by default.
    fn default_range(&self, i: Indicator, t_max: f64, field: &Field) -> (f32, f32) {
        self.range_rule(i, t_max).apply(field)
    }
    /// Whether the summary counts a pixel (chaotic).
    fn counted(&self, i: Indicator, x: f32) -> bool {
        (self.quantity(i).counted)(x)
    }
    /// Which pixels those are, in words.
    fn counted_rule(&self, i: Indicator) -> String {
        self.quantity(i).counted_rule.to_string()
    }
    /// What a map of it should tell its user about these physics.
    fn notices(&self, _i: Indicator, _params: &Params) -> Vec<String> {
        Vec::new()
    }
    /// Its maps a door lists by name (sweeps, the explorer's menu).
    fn kinds(&self) -> &'static [MapKindEntry];
    /// The indicators the bench times, by name.
    fn bench(&self) -> Vec<(&'static str, Indicator)>;
    /// Its own WGSL, appended to the indicators' kernel.
    fn wgsl(&self) -> &'static str {
        ""
    }
}

/// Every name an indicator is asked by, as `--indicator` and `indicator=` take it.
pub fn names() -> Vec<&'static str> {
    MEASURES.iter().flat_map(|m| m.names()).copied().collect()
}

/// The names whose indicator (its options at their defaults) calls each start chaotic or
/// not, each with its rule ("megno", "<Y> > 4"): what may draw a boundary's chaotic class.
pub fn classifying() -> Vec<(&'static str, String)> {
    names()
        .into_iter()
        .filter_map(|name| {
            let i = IndicatorAsked::named(name).indicator().ok()?;
            (i.quantity().counted_as == "chaotic").then(|| (name, i.measure().counted_rule(i)))
        })
        .collect()
}

/// What each name maps, in the list's order ("ftle (the largest exponent), ..."), every
/// `{field}` spelt by `spell` (a door's flag or keyword).
pub fn about(spell: impl Fn(&str) -> String) -> String {
    let mut items = Vec::new();
    for (names, what) in MEASURES.iter().flat_map(|m| m.about()) {
        let what = spelt(what, &spell);
        items.push(match what.is_empty() {
            true => names.to_string(),
            false => format!("{names} ({what})"),
        });
    }
    items.join(", ")
}

/// The measures' own WGSL, in the list's order.
pub fn wgsl() -> String {
    MEASURES
        .iter()
        .map(|m| m.wgsl())
        .collect::<Vec<_>>()
        .join("\n")
}

/// An indicator as a user asks for it: its name and the options given, by field.
#[derive(Clone, Copy, Debug)]
pub struct IndicatorAsked<'a> {
    pub name: &'a str,
    /// The options given ([`options`]), as (field, value).
    pub options: &'a [(&'static str, f64)],
    /// The accurate settings asked.
    pub accurate: bool,
    /// Whether it runs in f32 on a GPU (some options' defaults).
    pub gpu_f32: bool,
}

impl<'a> IndicatorAsked<'a> {
    /// `name` with every option at its default (an f64 run's).
    pub fn named(name: &'a str) -> Self {
        IndicatorAsked {
            name,
            options: &[],
            accurate: false,
            gpu_f32: false,
        }
    }

    /// The value given for `opt`, if any.
    pub fn get(&self, opt: Opt) -> Option<f64> {
        self.options
            .iter()
            .find(|(field, _)| *field == opt.field)
            .map(|&(_, v)| v)
    }

    /// The indicator asked for; an option of another indicator is refused naming it.
    pub fn indicator(&self) -> Result<Indicator> {
        let name = self.name;
        let Some(measure) = MEASURES.iter().find(|m| m.names().contains(&name)) else {
            return Err(Error::invalid(
                "indicator",
                format!("{name:?}: one of {}", names().join(", ")),
            ));
        };
        let takes = measure.options(name);
        for opt in options() {
            if self.get(opt).is_some() && !takes.contains(&opt) {
                let of: Vec<&str> = names()
                    .into_iter()
                    .filter(|n| {
                        let m = MEASURES.iter().find(|m| m.names().contains(n));
                        m.is_some_and(|m| m.options(n).contains(&opt))
                    })
                    .collect();
                return Err(Error::invalid(
                    opt.field,
                    format!("is for the indicator {}", or_list(&of)),
                ));
            }
        }
        if self.accurate && !measure.accurate() {
            let accurate: Vec<&str> = MEASURES
                .iter()
                .filter(|m| m.accurate())
                .flat_map(|m| m.names())
                .copied()
                .collect();
            return Err(Error::invalid(
                "accurate",
                format!(
                    "is for {}; {name} steps with rk4 (set dt and precision)",
                    or_list(&accurate)
                ),
            ));
        }
        Ok(measure.asked(name, self))
    }
}

/// "a, b or c".
fn or_list(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => one.to_string(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_is_one_measures_and_spelled_back() {
        let all = names();
        for (k, name) in all.iter().enumerate() {
            assert!(!all[k + 1..].contains(name), "{name} twice");
            let i = IndicatorAsked::named(name).indicator().unwrap();
            assert_eq!(i.spelled().0, *name);
            assert!(i.measure().names().contains(name));
        }
    }

    #[test]
    fn an_option_of_another_indicator_names_the_ones_it_is_for() {
        let asked = IndicatorAsked {
            options: &[("threshold", 1e-8)],
            ..IndicatorAsked::named("megno")
        };
        match asked.indicator() {
            Err(Error::InvalidSpec { field, reason }) => {
                assert_eq!(field, "threshold");
                assert!(
                    reason.contains("sali, sali-time, gali or gali-time"),
                    "{reason}"
                );
            }
            other => panic!("{other:?}"),
        }
    }
}
