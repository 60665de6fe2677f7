//! `chaoscope web`: the explorer as a static site.

use std::path::PathBuf;

use clap::Args;

use super::args::PhysicalArgs;
use super::{command_line, json};
use crate::app::web::{self, WebJob};
use crate::error::{Error, Result};
use crate::model::Params;
use crate::monitor::Monitor;
use crate::params::{ParamSources, Preset};
use crate::spec::MapKind;
use crate::web::{Pendulum, SiteSpec};

#[derive(Args, Debug, Clone)]
pub struct WebArgs {
    /// The folder for the site (index.html, its script, the kernels, manifest.json): new,
    /// empty, or a site written before (a folder of other files is refused); serve it from
    /// any static web host, or `python3 -m http.server -d DIR`.
    #[arg(long, default_value = "out/web")]
    pub output: PathBuf,
    /// A pendulum the page offers first, besides the equal arms and the lab's.
    #[command(flatten)]
    pub physical: PhysicalArgs,
    /// The name the page gives that pendulum ("our pendulum"; 1 to 60 characters) [default:
    /// its parameters].
    #[arg(long)]
    pub name: Option<String>,
}

impl WebArgs {
    pub fn job(&self) -> Result<WebJob> {
        Ok(WebJob {
            site: site(&self.physical, self.name.as_deref())?,
            output: self.output.clone(),
        })
    }
}

/// The static explorer: the equal arms, the lab's and the `physical` flags' pendulum (when
/// any is given, first, called `name` where one is given), and the command lines its views
/// and clicks fill in.
pub fn site(physical: &PhysicalArgs, name: Option<&str>) -> Result<SiteSpec> {
    let pendulum = |name: String, params: Params| Pendulum {
        flags: crate::web::parameter_axes()
            .into_iter()
            .map(|axes| {
                let key: Vec<&str> = axes.iter().map(|v| v.name()).collect();
                (key.join(","), command_line::params_on(&params, &axes))
            })
            .collect(),
        name,
        params,
    };
    let mut pendulums = Vec::new();
    let given = physical.sources();
    if let Some(name) = name {
        let length = name.chars().count();
        if !(1..=60).contains(&length) || name.chars().any(char::is_control) {
            return Err(Error::invalid(
                "name",
                format!("must be 1 to 60 printable characters ({length} given)"),
            ));
        }
        if given == ParamSources::default() {
            return Err(Error::invalid(
                "name",
                "names the pendulum the other flags give: give its --params FILE (fit's model.toml) or its parameters",
            ));
        }
    }
    if given != ParamSources::default() {
        let params = given.resolve()?;
        let flags = command_line::physics(&params);
        let called = name.map_or_else(|| format!("given: {flags}"), str::to_string);
        pendulums.push(pendulum(called, params));
    }
    pendulums.push(pendulum("equal arms: 1 kg, 1 m".into(), Params::default()));
    pendulums.push(pendulum(
        "the lab's (--preset lab)".into(),
        Preset::Lab.params(),
    ));
    let plane = "--size {width}x{height} --x {x}={x_min}:{x_max} --y {y}={y_min}:{y_max} --t-max {t_max} --dt {dt}{start} {pendulum}";
    // Every divergence-family map of the kinds' table, each setting the page offers with
    // its indicator's flags spelt out.
    let indicator_commands = MapKind::all()
        .iter()
        .filter(|k| k.entry().indicator.is_some())
        .map(|&k| {
            let offered = crate::web::variants(k)
                .into_iter()
                .map(|i| {
                    let flags = command_line::indicator(i);
                    (i, format!("chaoscope lyapunov{flags} {plane}{{verdict}}"))
                })
                .collect();
            (k, offered)
        })
        .collect();
    Ok(SiteSpec {
        pendulums,
        command: format!("chaoscope flip {plane} --colormap {{colours}}{{verdict}}"),
        indicator_commands,
        swing_command: "chaoscope trajectory --theta1 {theta1} --omega1 {omega1} --theta2 {theta2} --omega2 {omega2} --t-max {t_max} --dt {dt} {pendulum}".into(),
    })
}

pub fn run(args: &WebArgs, monitor: &Monitor) -> Result<serde_json::Value> {
    let s = web::run(&args.job()?, monitor)?;
    eprintln!(
        "{} files, {:.0} kB -> {} (serve it, e.g. python3 -m http.server -d {}, and open it in a browser with WebGPU)",
        s.files.len(),
        s.bytes as f64 / 1e3,
        s.output.display(),
        s.output.display()
    );
    json(&s)
}
