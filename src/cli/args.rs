//! Flag groups shared by the commands, flattened into each; a command changes a group's
//! defaults with `mut_arg` (e.g. `trajectory`'s `--t-max 10`).

use std::path::PathBuf;

use clap::Args;

use super::parse::{
    Angles, AxisArg, one_of, parse_angles, parse_axis, parse_number, parse_pair, parse_size,
};
use crate::engine::{Backend, Engine};
use crate::model::State;
use crate::params::{ParamSources, Preset};
use crate::render::{Colormap, PictureSpec};
use crate::spec::{Grid, PlaneAsked, Stepping};

/// `--backend auto|gpu|cpu`.
/// `--precision f32` given for a run on the CPU, which computes in f64 only: said once, not
/// run in f64 silently (issue 25's audit).
pub fn f32_on_the_cpu(precision: Option<crate::spec::Precision>, backend: Backend) {
    if precision == Some(crate::spec::Precision::F32) && backend == Backend::Cpu {
        eprintln!("note: --precision f32 is the GPU's; the CPU backend computes in f64");
    }
}

/// The engine a map's command computes on, and its job as `job` builds it knowing whether
/// that engine computes in f32 (some settings' defaults are f32's); [`f32_on_the_cpu`]'s
/// note first.
pub fn engine_then<J>(
    precision: Option<crate::spec::Precision>,
    backend: Backend,
    job: impl FnOnce(bool) -> crate::Result<J>,
) -> crate::Result<(Engine, J)> {
    let engine = lent_engine(precision, backend)?;
    let job = job(engine.computes_in_f32(precision.unwrap_or_default()))?;
    Ok((engine, job))
}

/// Where a command that runs trajectories or ensembles runs them, and in what precision.
#[derive(Args, Debug, Clone)]
pub struct LentEngineArgs {
    /// auto, gpu or cpu (f64).
    #[arg(long, default_value = "auto", value_parser = backend_parser())]
    pub backend: Backend,
    /// The GPU's precision, f32 or f64 (an adapter with f64); the CPU is always f64.
    /// [default: f32]
    #[arg(long, value_parser = one_of(&crate::spec::Precision::ALL, crate::spec::Precision::name))]
    pub precision: Option<crate::spec::Precision>,
}

impl LentEngineArgs {
    pub fn lent(&self) -> crate::Result<Engine> {
        lent_engine(self.precision, self.backend)
    }

    /// A command's `run` of `job` on the engine lent, with the command line that `command`
    /// makes of the job (written into its files).
    pub fn run<J, S>(
        &self,
        job: &J,
        command: impl FnOnce(&J) -> String,
        monitor: &crate::monitor::Monitor,
        run: impl FnOnce(&J, &crate::app::Running) -> crate::Result<S>,
    ) -> crate::Result<S> {
        let engine = self.lent()?;
        run(
            job,
            &crate::app::Running::new(&engine, command(job), monitor),
        )
    }
}

/// The one way the command line makes an engine, once a command: its trajectories and
/// ensembles in the precision asked (f32 unless given; [`f32_on_the_cpu`]'s note first). A
/// map's plan picks each map's precision on it ([`crate::plan::MapPlan`]), f64 on a GPU
/// without it falling back alike.
pub fn lent_engine(
    asked: Option<crate::spec::Precision>,
    backend: Backend,
) -> crate::Result<Engine> {
    f32_on_the_cpu(asked, backend);
    Engine::in_precision(backend, asked.unwrap_or_default())
}

pub fn backend_parser() -> impl clap::builder::TypedValueParser<Value = Backend> {
    one_of(&Backend::ALL, Backend::name)
}

pub fn colormap_parser() -> impl clap::builder::TypedValueParser<Value = Colormap> {
    one_of(&Colormap::ALL, Colormap::name)
}

pub(super) fn preset_parser() -> impl clap::builder::TypedValueParser<Value = Preset> {
    one_of(&Preset::ALL, Preset::name)
}

/// The physical parameters, SI units; every command takes them.
#[derive(Args, Debug, Clone, Default)]
pub struct PhysicalArgs {
    /// Upper bob mass (kg, 1e-30 to 1e30) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub m1: Option<f64>,
    /// Lower bob mass (kg, 1e-30 to 1e30) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub m2: Option<f64>,
    /// Upper arm length (m, 1e-4 to 1e4) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub l1: Option<f64>,
    /// Lower arm length (m, 1e-4 to 1e4) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub l2: Option<f64>,
    /// Gravitational acceleration (m/s^2, 1e-6 to 1e6) [default 9.81].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub g: Option<f64>,
    /// Masses of uniform rods along the arms, R or R1,R2 (kg, 0 to 1e30) [default 0:
    /// massless arms].
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub rod_mass: Option<(f64, f64)>,
    /// Viscous joint damping, C or C1,C2 (N m s, 0 to 1e30): torque -C1 w1 at the pivot,
    /// -C2 (w2 - w1) at the middle joint.
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub joint_damping: Option<(f64, f64)>,
    /// Quadratic air drag on bobs and rods (F = 1/2 rho c_w A v^2).
    #[arg(long)]
    pub air_drag: bool,
    /// Air density (kg/m^3, 0 to 1e4) for --air-drag [default 1.2].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub rho: Option<f64>,
    /// Drag coefficient for --air-drag (0 to 100) [default 2, the report's plates].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub cw: Option<f64>,
    /// Projected areas of the bobs, A or A1,A2 (m^2, 0 to 1e4) [default 1.45e-3].
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub drag_area: Option<(f64, f64)>,
    /// Projected areas of the rods, A or A1,A2 (m^2, 0 to 1e4) [default 0].
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub rod_drag_area: Option<(f64, f64)>,
    /// Rolling-friction coefficient c_R of the pivot and middle bearings (F = c_R F_N; 0 to
    /// 1; the report: 0.5e-3 to 1e-3).
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub bearing_friction: Option<f64>,
    /// Radius (m, above 0 to 1) at which bearing friction acts [default 0.004].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub bearing_radius: Option<f64>,
    /// A named set of parameters: lab, the report's apparatus (flags given as well override
    /// it).
    #[arg(long, value_parser = preset_parser())]
    pub preset: Option<Preset>,
    /// Parameters from a TOML file (keys: m1 m2 l1 l2 g rod_mass joint_damping
    /// bearing_friction bearing_radius, table [air_drag] with rho cw bob_area rod_area);
    /// flags given as well override it.
    #[arg(long)]
    pub params: Option<PathBuf>,
}

impl PhysicalArgs {
    pub fn sources(&self) -> ParamSources {
        ParamSources {
            m1: self.m1,
            m2: self.m2,
            l1: self.l1,
            l2: self.l2,
            g: self.g,
            rod_mass: self.rod_mass,
            joint_damping: self.joint_damping,
            air_drag: self.air_drag,
            rho: self.rho,
            cw: self.cw,
            drag_area: self.drag_area,
            rod_drag_area: self.rod_drag_area,
            bearing_friction: self.bearing_friction,
            bearing_radius: self.bearing_radius,
            preset: self.preset,
            params: self.params.clone(),
        }
    }
}

/// The grid of starts of a map.
#[derive(Args, Debug, Clone)]
pub struct GridArgs {
    /// Grid size: N (square) or WxH, one pendulum per pixel.
    #[arg(long, default_value = "512", value_parser = parse_size, allow_hyphen_values = true)]
    pub size: (u32, u32),
    #[command(flatten)]
    pub plane: PlaneArgs,
}

impl GridArgs {
    pub fn grid(&self) -> crate::Result<Grid> {
        self.plane.grid(self.size)
    }
}

/// What the axes of a map vary, and the start's other values.
#[derive(Args, Debug, Clone, Default)]
pub struct PlaneArgs {
    /// What varies along x: NAME or NAME=MIN:MAX, NAME one of theta1 omega1 theta2 omega2 (rad,
    /// rad/s), m1 m2 (kg), m2/m1 (m1 held), l1 l2 (m), l2/l1 (l1 held), g (m/s^2), damping
    /// (both joints), joint1 joint2 (N m s), rod1 rod2 (kg). Two axes may not set one value
    /// (m2 and m2/m1, l2 and l2/l1, damping and joint1, damping and joint2), nor an axis and
    /// a flag (--m2 beside m2/m1; a pair's part along an axis is given as 0). The other
    /// parameters come from their flags [default theta1].
    #[arg(long, value_parser = parse_axis, allow_hyphen_values = true)]
    pub x: Option<AxisArg>,
    /// What varies along y (top = MAX), as --x [default theta2].
    #[arg(long, value_parser = parse_axis, allow_hyphen_values = true)]
    pub y: Option<AxisArg>,
    /// theta1: its range MIN:MAX (rad, `pi` is understood) when it lies along an axis
    /// [default -pi:pi], else its start (rad) [default 0].
    #[arg(long, value_parser = parse_angles, allow_hyphen_values = true)]
    pub theta1: Option<Angles>,
    /// theta2, as --theta1.
    #[arg(long, value_parser = parse_angles, allow_hyphen_values = true)]
    pub theta2: Option<Angles>,
    /// Initial angular velocity of the upper arm (rad/s), the same for every pixel unless
    /// it lies along an axis [default 0].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: Option<f64>,
    /// Initial angular velocity of the lower arm (rad/s) [default 0].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: Option<f64>,
}

impl PlaneArgs {
    /// The grid of `size` pixels these flags describe ([`PlaneAsked::grid`]).
    pub fn grid(&self, size: (u32, u32)) -> crate::Result<Grid> {
        PlaneAsked {
            x: self.x,
            y: self.y,
            theta1: self.theta1,
            theta2: self.theta2,
            omega1: self.omega1,
            omega2: self.omega2,
        }
        .grid(size)
    }
}

/// Time stepping: fixed-step RK4 from 0 to --t-max.
#[derive(Args, Debug, Clone)]
pub struct StepArgs {
    /// Simulated time (s).
    #[arg(long, default_value_t = Stepping::FLIP_T_MAX, value_parser = parse_number, allow_hyphen_values = true)]
    pub t_max: f64,
    /// RK4 time step (s).
    #[arg(long, default_value_t = Stepping::DT, value_parser = parse_number, allow_hyphen_values = true)]
    pub dt: f64,
}

impl StepArgs {
    pub fn stepping(&self) -> Stepping {
        Stepping {
            dt: self.dt,
            t_max: self.t_max,
        }
    }
}

/// One start: both angles, angular velocities 0 unless given.
#[derive(Args, Debug, Clone)]
pub struct StartArgs {
    /// Initial upper-arm angle (rad).
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub theta1: f64,
    /// Initial lower-arm angle (rad).
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub theta2: f64,
    /// Initial angular velocity of the upper arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega1: f64,
    /// Initial angular velocity of the lower arm (rad/s).
    #[arg(long, default_value = "0", value_parser = parse_number, allow_hyphen_values = true)]
    pub omega2: f64,
}

impl StartArgs {
    pub fn state(&self) -> State {
        State {
            theta1: self.theta1,
            omega1: self.omega1,
            theta2: self.theta2,
            omega2: self.omega2,
        }
    }
}

/// How a map becomes a picture.
#[derive(Args, Debug, Clone, Default)]
pub struct PictureArgs {
    /// Frame the map with theta axes (ticks at multiples of pi), a colour bar with units and
    /// a title. Without it the PNG is the bare map, one pixel a pendulum.
    #[arg(long)]
    pub annotate: bool,
    /// Colour map (default: inferno for flip times, magma for exponents; sinebow and rainbow
    /// are cyclic).
    #[arg(long, value_parser = colormap_parser())]
    pub colormap: Option<Colormap>,
}

impl PictureArgs {
    pub fn spec(&self) -> PictureSpec {
        PictureSpec {
            annotate: self.annotate,
            colormap: self.colormap,
        }
    }
}

/// Which pixels are resolved: the map again at half the step, compared pixel by pixel
/// (flip times within 1 % or 0.02 s, exponents within 5 % or 0.02 /s). Costs the map twice
/// more.
#[derive(Args, Debug, Clone, Default)]
pub struct VerdictArgs {
    /// Write the verdict as uint8 .npy, the layout of --data: 1 where the pixel is resolved.
    #[arg(long)]
    pub resolved: Option<PathBuf>,
    /// Draw the pixels that are not resolved in grey (and say so in the PNG's metadata and
    /// an annotated map's subtitle).
    #[arg(long)]
    pub show_unresolved: bool,
}

/// Supersampling: several starts a pixel.
#[derive(Args, Debug, Clone)]
pub struct SampleArgs {
    /// N x N starts a pixel (the centres of its N x N sub-pixels, 1 to 16): flip times by
    /// the mean of their logs over those that flip, the flip kind by the majority, exponents
    /// and indicators by the mean; resolved (--resolved) where every sub-sample is. Costs N^2
    /// times the map (and its memory).
    #[arg(long, default_value = "1", value_parser = super::parse::parse_u32, allow_hyphen_values = true)]
    pub samples: u32,
}

/// A map into a .zarr store writes no PNG (`chaoscope render` makes it from the store):
/// `--output` with one is an error naming it.
pub fn no_picture_with_a_store(
    data: Option<&std::path::Path>,
    output: Option<&std::path::Path>,
) -> crate::Result<()> {
    let zarr = data.is_some_and(|d| d.extension().is_some_and(|e| e == "zarr"));
    if zarr && output.is_some() {
        return Err(crate::Error::invalid(
            "output",
            "a .zarr store's picture is made from the store: chaoscope render MAP.zarr --output PNG",
        ));
    }
    Ok(())
}

/// The model's flags as `fit` and `forecast` (which take a tracked file) tell them: a part
/// of a pendulum only with a model stated, and the model, unless stated, the pendulum's own
/// (`#[command(mut_args(tracked_model_help))]`).
pub fn tracked_model_help(a: clap::Arg) -> clap::Arg {
    let help = match a.get_id().as_str() {
        "m1" => "Upper bob mass (kg), with --preset or --params [default: the model's]",
        "m2" => "Lower bob mass (kg), with --preset or --params [default: the model's]",
        "l1" => "Upper arm length (m), with --preset or --params [default: fitted to the data]",
        "l2" => "Lower arm length (m), with --preset or --params [default: fitted to the data]",
        "rod_mass" => {
            "Masses of uniform rods along the arms, R or R1,R2 (kg), with --preset or --params [default: the model's]"
        }
        "preset" => {
            "The pendulum's model by name (lab: the lab report's apparatus) [default: none: the pendulum's own moments, found from its motion]"
        }
        _ => return a,
    };
    a.help(help)
}

/// How a tracked file's numbers become seconds and metres (`fit`, `forecast`).
#[derive(Args, Debug, Clone, Default)]
pub struct TrackedUnitsArgs {
    /// The positions are in pixels as images count them (x right, y down), this many to a
    /// metre; `motion`: the scale the swing implies under g at the file's times (a rigid
    /// pendulum's motion fixes l/g in seconds) [default: the positions are in metres, y up]
    #[arg(long, value_parser = parse_pixel_scale, allow_hyphen_values = true)]
    pub pixels_per_metre: Option<crate::fit::data::PixelScale>,
    /// The rows are numbered by a `frame` column, this many frames a second [default: a
    /// `t` column in seconds]
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub frame_rate: Option<f64>,
    /// Read the rows before the release too (the pendulum at rest and lifted by hand, not
    /// free motion) where `track` found one [default: from the release]
    #[arg(long)]
    pub before_release: bool,
    /// The pixels' y runs up, as Tracker exports them in its own frame [default: down, as
    /// images count it]
    #[arg(long)]
    pub y_up: bool,
}

impl TrackedUnitsArgs {
    pub fn units(&self) -> crate::fit::data::Units {
        crate::fit::data::Units {
            pixels_per_metre: self.pixels_per_metre,
            frame_rate: self.frame_rate,
            before_release: self.before_release,
            y_up: self.y_up,
        }
    }
}

/// A pixel scale: a number (pixels per metre) or `motion`.
pub(super) fn parse_pixel_scale(s: &str) -> Result<crate::fit::data::PixelScale, String> {
    use crate::fit::data::PixelScale;
    match s.trim() {
        "motion" => Ok(PixelScale::FromMotion),
        other => parse_number(other)
            .map(PixelScale::PerMetre)
            .map_err(|e| format!("{e}, or `motion` (the scale from the swing)")),
    }
}

/// The indicators' options, one flag each as the measures declare them
/// ([`crate::measure::options`]): a new option needs no line here. Given ones as (field,
/// value).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IndicatorOptions(pub Vec<(&'static str, f64)>);

impl clap::FromArgMatches for IndicatorOptions {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        Ok(IndicatorOptions(
            crate::measure::options()
                .into_iter()
                .filter_map(|o| matches.get_one::<f64>(o.field).map(|&v| (o.field, v)))
                .collect(),
        ))
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl clap::Args for IndicatorOptions {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        crate::measure::options().into_iter().fold(cmd, |cmd, o| {
            let flag = |field: &str| super::names::flag("lyapunov", field);
            let arg = clap::Arg::new(o.field)
                .long(flag(o.field).trim_start_matches("--").to_string())
                .help(crate::measure::spelt(o.help, &flag))
                .value_name(o.field.to_uppercase())
                .allow_hyphen_values(true);
            cmd.arg(match o.whole {
                Some((low, high)) => arg.value_parser(clap::builder::TypedValueParser::map(
                    clap::value_parser!(u8).range(i64::from(low)..=i64::from(high)),
                    f64::from,
                )),
                None => arg.value_parser(super::parse::parse_number),
            })
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}
