//! Job -> the command line that reproduces it: the one inverse of the flags (args.rs and the
//! commands' own), written into every output's metadata. Output paths are not part of it.
//! Flags at their defaults are left out unless they always were (so that pictures made
//! before keep their bytes).

use super::shell::word;
use crate::app::boundary::BoundaryJob;
use crate::app::fit::FitJob;
use crate::app::flip::FlipJob;
use crate::app::forecast::ForecastJob;
use crate::app::lyapunov::{LyapunovMapJob, LyapunovPointJob};
use crate::app::phase::PhaseJob;
use crate::app::sweep::SweepJob;
use crate::app::traces::TracesJob;
use crate::app::trajectory::TrajectoryJob;
use crate::app::twin::TwinJob;
use crate::app::zoom::ZoomJob;
use crate::engine::Backend;
use crate::model::{Params, State};
use crate::params::ParamSources;
use crate::render::PictureSpec;
use crate::spec::AnyMap;
use crate::spec::{
    FlipMeasure, FlipSpec, Grid, Indicator, Integrator, LyapunovSpec, Method, Precision, Spread,
    Stepping, Var,
};

/// The flags that reproduce `p` exactly.
pub fn params(p: &Params) -> String {
    params_on(p, &[])
}

/// The flags of a pendulum's parameters, as every command takes them.
pub fn physics(p: &Params) -> String {
    params_on(p, &[])
}

/// The flags that reproduce `p` beside axes (or a sweep) that vary `along`: what they set is
/// left out (given with them, it would be refused), a pair's part they set given as 0.
pub fn params_on(p: &Params, along: &[Var]) -> String {
    let set = |name: &str| along.iter().any(|v| v.writes().contains(&name));
    let mut out = [
        ("m1", p.m1),
        ("m2", p.m2),
        ("l1", p.l1),
        ("l2", p.l2),
        ("g", p.g),
    ]
    .into_iter()
    .filter(|(name, _)| !set(name))
    .map(|(name, v)| format!("--{name} {v}"))
    .collect::<Vec<_>>()
    .join(" ");
    let l = &p.losses;
    for (flag, [a, b], [v1, v2]) in [
        ("rod-mass", ["rod1", "rod2"], [p.rod1, p.rod2]),
        ("joint-damping", ["joint1", "joint2"], [l.joint1, l.joint2]),
    ] {
        let (v1, v2) = (if set(a) { 0.0 } else { v1 }, if set(b) { 0.0 } else { v2 });
        if v1 != 0.0 || v2 != 0.0 {
            out += &format!(" --{flag} {v1},{v2}");
        }
    }
    if l.has_bearings() {
        out += &format!(
            " --bearing-friction {} --bearing-radius {}",
            l.bearing, l.bearing_radius
        );
    }
    if l.has_drag() {
        out += &format!(
            " --air-drag --rho {} --cw {} --drag-area {},{} --rod-drag-area {},{}",
            l.rho, l.cw, l.bob_area1, l.bob_area2, l.rod_area1, l.rod_area2
        );
    }
    out
}

/// The flags of the sources as given (a preset and a file stay named).
pub fn sources(s: &ParamSources) -> String {
    let mut out = String::new();
    let mut one = |name: &str, v: Option<f64>| {
        if let Some(v) = v {
            out += &format!(" --{name} {v}");
        }
    };
    one("m1", s.m1);
    one("m2", s.m2);
    one("l1", s.l1);
    one("l2", s.l2);
    one("g", s.g);
    one("rho", s.rho);
    one("cw", s.cw);
    one("bearing-friction", s.bearing_friction);
    one("bearing-radius", s.bearing_radius);
    for (name, pair) in [
        ("rod-mass", s.rod_mass),
        ("joint-damping", s.joint_damping),
        ("drag-area", s.drag_area),
        ("rod-drag-area", s.rod_drag_area),
    ] {
        if let Some((a, b)) = pair {
            out += &format!(" --{name} {a},{b}");
        }
    }
    if s.air_drag {
        out += " --air-drag";
    }
    if let Some(p) = s.preset {
        out += &format!(" --preset {}", p.name());
    }
    if let Some(f) = &s.params {
        out += &format!(" --params {}", word(f));
    }
    out
}

fn picture(p: &PictureSpec) -> String {
    let mut out = String::new();
    if p.annotate {
        out.push_str(" --annotate");
    }
    if let Some(c) = p.colormap {
        out.push_str(&format!(" --colormap {}", c.name()));
    }
    out
}

/// The (theta1, theta2) plane as its own flags have always written it; any other plane by
/// --x and --y and the start's values that lie along no axis.
fn grid(g: &Grid) -> String {
    format!("--size {}x{} {}", g.width, g.height, plane(g))
}

/// The plane's flags, without the size.
fn plane(g: &Grid) -> String {
    let s = g.fixed;
    if g.is_angle_plane() {
        return format!(
            "--theta1 {}:{} --theta2 {}:{} --omega1 {} --omega2 {}",
            g.x.range.min, g.x.range.max, g.y.range.min, g.y.range.max, s.omega1, s.omega2
        );
    }
    let mut out = String::new();
    for (flag, a) in [("x", g.x), ("y", g.y)] {
        out += &format!("--{flag} {}={}:{} ", a.var.name(), a.range.min, a.range.max);
    }
    for var in [Var::Theta1, Var::Theta2, Var::Omega1, Var::Omega2] {
        if var != g.x.var && var != g.y.var {
            out += &format!("--{} {} ", var.name(), var.get(&Default::default(), &s));
        }
    }
    out.trim_end().to_string()
}

fn start(s: &State) -> String {
    format!(
        "--theta1 {} --theta2 {} --omega1 {} --omega2 {}",
        s.theta1, s.theta2, s.omega1, s.omega2
    )
}

fn steps(s: &Stepping) -> String {
    format!("--t-max {} --dt {}", s.t_max, s.dt)
}

/// A flip map on `backend`.
pub fn flip_map(spec: &FlipSpec, backend: Backend, pic: &PictureSpec) -> String {
    let mut out = format!(
        "chaoscope flip {} {} {} --backend {}",
        grid(&spec.grid),
        steps(&spec.stepping),
        params_on(&spec.params, &[spec.grid.x.var, spec.grid.y.var]),
        backend.name()
    );
    if spec.measure != FlipMeasure::Time {
        out += &format!(" --colour-by {}", spec.measure.name());
    }
    if !spec.early_exit {
        out += " --full";
    } else if !spec.use_symmetry {
        out += " --no-symmetry";
    }
    out += &precision(spec.precision);
    out += &integrator(&spec.integrator);
    out + &picture(pic)
}

/// An adaptive integrator's flags; nothing for RK4, the default.
fn integrator(i: &Integrator) -> String {
    match i.tolerances() {
        Some((rtol, atol)) => format!(" --integrator {} --rtol {rtol} --atol {atol}", i.name()),
        None => String::new(),
    }
}

pub fn flip(job: &FlipJob) -> String {
    flip_map(&job.spec, job.backend, &job.picture)
        + show_unresolved(job.files.show_unresolved)
        + &samples(job.samples)
}

/// ` --samples N` when not 1.
fn samples(n: u32) -> String {
    match n {
        1 => String::new(),
        n => format!(" --samples {n}"),
    }
}

fn show_unresolved(on: bool) -> &'static str {
    if on { " --show-unresolved" } else { "" }
}

fn method(m: Method) -> String {
    match m {
        Method::Tangent => "--method tangent".into(),
        Method::Twin { eps } => format!("--method twin --eps {eps}"),
    }
}

/// A divergence map on `backend`.
pub fn lyapunov_map_of(spec: &LyapunovSpec, backend: Backend, pic: &PictureSpec) -> String {
    let mut out = format!(
        "chaoscope lyapunov {} {} --renorm {} {} {} --backend {}",
        grid(&spec.grid),
        steps(&spec.stepping),
        spec.renorm,
        method(spec.method),
        params_on(&spec.params, &[spec.grid.x.var, spec.grid.y.var]),
        backend.name()
    );
    if !spec.use_symmetry {
        out += " --no-symmetry";
    }
    out += &precision(spec.precision);
    out += &integrator(&spec.integrator);
    out += &indicator(spec.indicator);
    out + &picture(pic)
}

/// `--indicator` and its settings (nothing for the FTLE, the default).
pub fn indicator(i: Indicator) -> String {
    let (name, options) = i.spelled();
    if i == Indicator::default() {
        return String::new();
    }
    let mut out = format!(" --indicator {name}");
    for (opt, value) in options {
        out += &format!(" --{} {value}", opt.field.replace('_', "-"));
    }
    out
}

pub fn lyapunov_map(job: &LyapunovMapJob) -> String {
    let range = job
        .colour_range
        .map(|(lo, hi)| format!(" --colour-range {lo}:{hi}"))
        .unwrap_or_default();
    lyapunov_map_of(&job.spec, job.backend, &job.picture)
        + &range
        + show_unresolved(job.files.show_unresolved)
        + &samples(job.samples)
}

pub fn lyapunov_point(job: &LyapunovPointJob) -> String {
    let s = &job.spec;
    format!(
        "chaoscope lyapunov {} {} --renorm {} {} {} --backend {}",
        start(&job.start),
        steps(&s.stepping),
        s.renorm,
        method(s.method),
        params(&s.params),
        job.backend.name()
    ) + &precision(s.precision)
        + &indicator(s.indicator)
}

pub fn trajectory(job: &TrajectoryJob) -> String {
    let mut out = format!(
        "chaoscope trajectory {} {} {} --backend {}",
        start(&job.start),
        steps(&job.stepping),
        params(&job.params),
        job.backend.name()
    );
    if let Some(every) = job.every {
        out += &format!(" --every {every}");
    }
    out + &precision(job.precision)
}

fn spread(s: Spread) -> String {
    match s {
        Spread::Radians(r) => format!("{r}"),
        Spread::Metres(m) => format!("{m}m"),
    }
}

pub fn traces(job: &TracesJob) -> String {
    let mut out = format!(
        "chaoscope traces {} --runs {} --spread {} --exposure {} --dt {} --size {} {}",
        start(&job.start),
        job.runs,
        spread(job.spread),
        job.stepping.t_max,
        job.stepping.dt,
        job.size,
        params(&job.params)
    );
    if job.backend != Backend::Auto {
        out += &format!(" --backend {}", job.backend.name());
    }
    if let Some(f) = &job.film {
        out += &film(f, crate::app::traces::FILM_FORMATS);
    }
    out + &precision(job.precision)
}

/// ` --fps F`, and ` --crf Q` for an MP4: how a film plays (its file is the run's output,
/// named by the user as any other).
fn film(f: &crate::app::film::FilmSpec, formats: &[crate::app::film::Format]) -> String {
    match f.format("film", formats) {
        Ok(crate::app::film::Format::Mp4) => format!(" --fps {} --crf {}", f.fps, f.crf),
        _ => format!(" --fps {}", f.fps),
    }
}

/// ` --precision P` when not the default.
fn precision(p: Precision) -> String {
    match p == Precision::default() {
        true => String::new(),
        false => format!(" --precision {}", p.name()),
    }
}

/// `phase`'s default spread, left out of its command.
pub const PHASE_SPREAD: Spread = Spread::Radians(0.01);

pub fn phase(job: &PhaseJob) -> String {
    let mut out = if job.single {
        format!(
            "chaoscope phase --single {} --size {} --l1 {} --g {}",
            steps(&job.stepping),
            job.size,
            job.params.l1,
            job.params.g
        )
    } else {
        let mut out = format!(
            "chaoscope phase {} --runs {} {} --size {} {}",
            start(&job.start),
            job.runs,
            steps(&job.stepping),
            job.size,
            params(&job.params)
        );
        if job.spread != PHASE_SPREAD {
            out += &format!(" --spread {}", spread(job.spread));
        }
        if job.backend != Backend::Auto {
            out += &format!(" --backend {}", job.backend.name());
        }
        out + &precision(job.precision)
    };
    if let Some(c) = job.colormap {
        out += &format!(" --colormap {}", c.name());
    }
    out
}

/// One sweep frame as a single map.
pub fn frame(map: &AnyMap, backend: Backend, pic: &PictureSpec) -> String {
    match map {
        AnyMap::Flip(spec) => flip_map(spec, backend, pic),
        AnyMap::Lyapunov(spec) => lyapunov_map_of(spec, backend, pic),
    }
}

/// A zoom: its own flags, then `map` (the first frame's command, `chaoscope flip ...`).
pub fn zoom<S>(job: &ZoomJob<S>, map: &str) -> String {
    let mut out = String::from("chaoscope zoom");
    for v in &job.to {
        out += &format!(" --to {},{},{}", v.x, v.y, v.width);
    }
    out += &format!(" --frames {} --fps {}", job.frames, job.film.fps);
    if matches!(
        job.film.format("film", crate::app::zoom::FILM_FORMATS),
        Ok(crate::app::film::Format::Mp4)
    ) {
        out += &format!(" --crf {}", job.film.crf);
    }
    if job.verdict {
        out += " --verdict";
    }
    out + " " + map.strip_prefix("chaoscope ").unwrap_or(map)
}

pub fn sweep(job: &SweepJob) -> String {
    let varied = job.vary.param.var();
    let along: Vec<Var> = [Some(job.grid.x.var), Some(job.grid.y.var), varied]
        .into_iter()
        .flatten()
        .collect();
    let mut out = format!("chaoscope sweep --map {}", job.map.name());
    let v = job.vary;
    out += &format!(" --vary {}={}:{}", v.param.name(), v.from, v.to);
    out += &format!(
        " --frames {} --fps {} {} {} --renorm {} --ftle-max {} {} --backend {}",
        job.frames,
        job.film.fps,
        grid(&job.grid),
        steps(&job.stepping),
        job.renorm,
        job.ftle_max,
        params_on(&job.params, &along),
        job.backend.name()
    );
    if matches!(
        job.film.format("film", crate::app::sweep::FILM_FORMATS),
        Ok(crate::app::film::Format::Mp4)
    ) {
        out += &format!(" --crf {}", job.film.crf);
    }
    out + &picture(&job.picture)
}

pub fn boundary(job: &BoundaryJob) -> String {
    let s = &job.spec;
    format!(
        "chaoscope boundary {} {} {} --class {} --pairs {} --eps {}:{} --levels {} --seed {} --backend {} --precision {}",
        plane(&s.grid),
        steps(&s.stepping),
        params_on(&s.params, &[s.grid.x.var, s.grid.y.var]),
        job.class.name(),
        job.pairs,
        job.eps.0,
        job.eps.1,
        job.levels,
        job.seed,
        job.backend.name(),
        s.precision.name()
    ) + &match job.class {
        crate::app::boundary::BoundaryClass::Chaotic => format!(
            " --indicator {} --renorm {}",
            job.divergence.indicator.spelled().0,
            job.divergence.renorm
        ),
        _ => String::new(),
    }
}

/// ` --NAME VALUE` where a value is given; nothing where the data's default stands.
fn given<T: std::fmt::Display>(name: &str, v: Option<T>) -> String {
    v.map_or(String::new(), |v| format!(" --{name} {v}"))
}

/// A tracked file's units as flags.
fn units(u: &crate::fit::data::Units) -> String {
    use crate::fit::data::PixelScale;
    let scale = u.pixels_per_metre.map(|s| match s {
        PixelScale::PerMetre(p) => p.to_string(),
        PixelScale::FromMotion => "motion".to_string(),
    });
    given("pixels-per-metre", scale)
        + &given("frame-rate", u.frame_rate)
        + if u.y_up { " --y-up" } else { "" }
}

pub fn fit(job: &FitJob) -> String {
    format!(
        "chaoscope fit {}{}{}{}{}{} --candidates {} --held-out {} --lead {} --velocity-error {}{}{} --backend {}",
        word(&job.file),
        units(&job.units),
        given("until", job.until),
        given("start", job.start),
        given("window", job.window),
        given("tolerance", job.tolerance),
        job.candidates,
        job.held_out,
        job.lead,
        job.velocity_error,
        given("mass", job.mass),
        sources(&job.params),
        job.backend.name()
    ) + &precision(job.precision)
}

pub fn forecast(job: &ForecastJob) -> String {
    let noise = job
        .settings
        .tracking_error
        .map_or(String::new(), |e| format!(" --tracking-error {e}"));
    format!(
        "chaoscope forecast {}{}{}{}{} --members {} --seed {}{}{noise} --candidates {} --held-out {}{} --backend {}",
        word(&job.file),
        units(&job.units),
        given(
            "window",
            job.settings.window.map(|(a, b)| format!("{a}:{b}"))
        ),
        given("ahead", job.settings.ahead),
        if job.settings.in_sample {
            " --in-sample"
        } else {
            ""
        },
        job.settings.members,
        job.settings.seed,
        given("tolerance", job.settings.tolerance),
        job.settings.candidates,
        job.settings.held_out,
        sources(&job.params),
        job.backend.name()
    ) + &precision(job.precision)
        // A film drawn on says which, and where it went: its comment makes it again.
        + &job.video.as_ref().map_or(String::new(), |v| {
            format!(" --video {} --output {}", word(v), word(&job.output))
        })
}

pub fn twin(job: &TwinJob) -> String {
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    format!(
        "chaoscope twin --sigma {} --rate {} --replicates {}{} --duration {} --theta1 {} --omega1 {} --theta2 {} --omega2 {} --members {} --seed {}{} --candidates {}{} --backend {}",
        list(&job.sigmas),
        list(&job.rates),
        job.replicates,
        given(
            "window",
            job.settings.window.map(|(a, b)| format!("{a}:{b}"))
        ),
        job.duration,
        job.start.theta1,
        job.start.omega1,
        job.start.theta2,
        job.start.omega2,
        job.settings.members,
        job.settings.seed,
        given("tolerance", job.settings.tolerance),
        job.settings.candidates,
        sources(&job.params),
        job.backend.name()
    ) + &precision(job.precision)
}

/// The command that reproduces a track (the CSV's first line).
pub fn track(job: &crate::app::track::TrackJob) -> String {
    let mut out = format!("chaoscope track {}", word(&job.video));
    match job.scale {
        crate::track::Scale::UpperArm(l1) => out += &format!(" --l1 {l1}"),
        crate::track::Scale::PixelsPerMetre(p) => out += &format!(" --pixels-per-metre {p}"),
        crate::track::Scale::FromMotion(_) => out += " --pixels-per-metre motion",
    }
    if job.markers != crate::track::Markers::Bright {
        out += &format!(" --markers {}", job.markers);
    }
    if let Some((x0, y0, x1, y1)) = job.region {
        out += &format!(" --region {x0},{y0},{x1},{y1}");
    }
    if let Some(model) = &job.bridge {
        out += " --bridge";
        if let Some(preset) = model.preset {
            out += &format!(" --preset {}", preset.name());
        }
        if let Some(file) = &model.params {
            out += &format!(" --params {}", word(file));
        }
    }
    out
}
