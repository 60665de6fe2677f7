//! The physical flags every command shares, the `lab` preset and `--params FILE.toml`.
//! Precedence: defaults, then the preset, then the file, then single flags.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use serde::Deserialize;

use crate::cli::parse_number;
use crate::error::{Error, Result};
use crate::model::{Losses, Params};
use crate::spec::finite_positive;

/// `A` or `A,B` (one value for both).
pub fn parse_pair(s: &str) -> std::result::Result<(f64, f64), String> {
    match s.split_once(',') {
        Some((a, b)) => Ok((parse_number(a)?, parse_number(b)?)),
        None => parse_number(s).map(|v| (v, v)),
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Preset {
    /// The lab report's apparatus (../shared/data/README.md): bobs 0.301 and 0.297 kg, arms
    /// 0.30 and 0.195 m from the tracked data, acrylic plates as rods (0.140 kg: two plates on
    /// the upper arm, 0.070 kg), quadratic air drag on the plates (rho 1.2, c_w 2, 1.45e-3 m^2
    /// a plate), ball-bearing rolling friction c_R 0.75e-3 (the report: 0.5e-3 to 1e-3).
    Lab,
}

impl Preset {
    pub fn params(self) -> Params {
        match self {
            Preset::Lab => Params {
                m1: 0.301,
                m2: 0.297,
                l1: 0.30,
                l2: 0.195,
                g: 9.81,
                rod1: 0.140,
                rod2: 0.070,
                losses: Losses {
                    rho: 1.2,
                    cw: 2.0,
                    rod_area1: 2.0 * 1.45e-3,
                    rod_area2: 1.45e-3,
                    bearing: 0.75e-3,
                    bearing_radius: BEARING_RADIUS,
                    ..Losses::default()
                },
            },
        }
    }
}

/// Defaults of `--air-drag` when no value is given: the report's air and plates.
const RHO: f64 = 1.2;
const CW: f64 = 2.0;
const PLATE_AREA: f64 = 1.45e-3;
/// Bearing radius (m) where rolling friction acts: a 608 bearing's 8 mm bore.
const BEARING_RADIUS: f64 = 0.004;

/// The physical parameters, SI units.
#[derive(Args, Debug, Clone, Default)]
pub struct PhysicalArgs {
    /// Upper bob mass (kg) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub m1: Option<f64>,
    /// Lower bob mass (kg) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub m2: Option<f64>,
    /// Upper arm length (m) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub l1: Option<f64>,
    /// Lower arm length (m) [default 1].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub l2: Option<f64>,
    /// Gravitational acceleration (m/s^2) [default 9.81].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub g: Option<f64>,
    /// Masses of uniform rods along the arms, R or R1,R2 (kg) [default 0: massless arms].
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub rod_mass: Option<(f64, f64)>,
    /// Viscous joint damping, C or C1,C2 (N m s): torque -C1 w1 at the pivot, -C2 (w2 - w1)
    /// at the middle joint.
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub joint_damping: Option<(f64, f64)>,
    /// Quadratic air drag on bobs and rods (F = 1/2 rho c_w A v^2).
    #[arg(long)]
    pub air_drag: bool,
    /// Air density (kg/m^3) for --air-drag [default 1.2].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub rho: Option<f64>,
    /// Drag coefficient for --air-drag [default 2, the report's plates].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub cw: Option<f64>,
    /// Projected areas of the bobs, A or A1,A2 (m^2) [default 1.45e-3].
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub drag_area: Option<(f64, f64)>,
    /// Projected areas of the rods, A or A1,A2 (m^2) [default 0].
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub rod_drag_area: Option<(f64, f64)>,
    /// Rolling-friction coefficient c_R of the pivot and middle bearings (F = c_R F_N; the
    /// report: 0.5e-3 to 1e-3).
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub bearing_friction: Option<f64>,
    /// Radius (m) at which bearing friction acts [default 0.004].
    #[arg(long, value_parser = parse_number, allow_hyphen_values = true)]
    pub bearing_radius: Option<f64>,
    /// A named set of parameters (flags given as well override it).
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Parameters from a TOML file (keys: m1 m2 l1 l2 g rod_mass joint_damping
    /// bearing_friction bearing_radius, table [air_drag] with rho cw bob_area rod_area);
    /// flags given as well override it.
    #[arg(long)]
    pub params: Option<PathBuf>,
}

/// The TOML parameter file; every key optional, unknown keys are errors.
#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct ParamsFile {
    m1: Option<f64>,
    m2: Option<f64>,
    l1: Option<f64>,
    l2: Option<f64>,
    g: Option<f64>,
    rod_mass: Option<[f64; 2]>,
    joint_damping: Option<[f64; 2]>,
    bearing_friction: Option<f64>,
    bearing_radius: Option<f64>,
    air_drag: Option<AirDragFile>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct AirDragFile {
    rho: Option<f64>,
    cw: Option<f64>,
    bob_area: Option<[f64; 2]>,
    rod_area: Option<[f64; 2]>,
}

fn read_params_file(path: &Path, base: Params) -> Result<Params> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::invalid("--params", format!("cannot read {}: {e}", path.display())))?;
    let file: ParamsFile = toml::from_str(&text)
        .map_err(|e| Error::invalid("--params", format!("{}: {e}", path.display())))?;
    let mut p = base;
    let set = |slot: &mut f64, v: Option<f64>| {
        if let Some(v) = v {
            *slot = v;
        }
    };
    set(&mut p.m1, file.m1);
    set(&mut p.m2, file.m2);
    set(&mut p.l1, file.l1);
    set(&mut p.l2, file.l2);
    set(&mut p.g, file.g);
    if let Some([a, b]) = file.rod_mass {
        (p.rod1, p.rod2) = (a, b);
    }
    if let Some([a, b]) = file.joint_damping {
        (p.losses.joint1, p.losses.joint2) = (a, b);
    }
    if let Some(c) = file.bearing_friction {
        p.losses.bearing = c;
        p.losses.bearing_radius = file.bearing_radius.unwrap_or(BEARING_RADIUS);
    } else if let Some(r) = file.bearing_radius {
        p.losses.bearing_radius = r;
    }
    if let Some(air) = file.air_drag {
        p.losses.rho = air.rho.unwrap_or(RHO);
        p.losses.cw = air.cw.unwrap_or(CW);
        let [a1, a2] = air.bob_area.unwrap_or([0.0; 2]);
        let [r1, r2] = air.rod_area.unwrap_or([0.0; 2]);
        (p.losses.bob_area1, p.losses.bob_area2) = (a1, a2);
        (p.losses.rod_area1, p.losses.rod_area2) = (r1, r2);
    }
    // Impossible values name the key and the file.
    validate(&p).map_err(|e| match e {
        Error::InvalidSpec { flag, reason } => Error::invalid(
            "--params",
            format!("{}: key {}: {reason}", path.display(), key_of(flag)),
        ),
        e => e,
    })?;
    Ok(p)
}

/// The file key of a flag (`--rod-mass` -> `rod_mass`, air-drag keys in their table).
fn key_of(flag: &str) -> String {
    match flag {
        "--rho" => "air_drag.rho".into(),
        "--cw" => "air_drag.cw".into(),
        "--drag-area" => "air_drag.bob_area".into(),
        "--rod-drag-area" => "air_drag.rod_area".into(),
        f => f.trim_start_matches("--").replace('-', "_"),
    }
}

fn finite_non_negative(flag: &'static str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(
            flag,
            format!("{v} is not allowed; it must be a finite number >= 0"),
        ))
    }
}

/// Every parameter in its allowed range; the error names the flag.
pub fn validate(p: &Params) -> Result<()> {
    finite_positive("--m1", p.m1)?;
    finite_positive("--m2", p.m2)?;
    finite_positive("--l1", p.l1)?;
    finite_positive("--l2", p.l2)?;
    finite_positive("--g", p.g)?;
    finite_non_negative("--rod-mass", p.rod1)?;
    finite_non_negative("--rod-mass", p.rod2)?;
    let l = &p.losses;
    finite_non_negative("--joint-damping", l.joint1)?;
    finite_non_negative("--joint-damping", l.joint2)?;
    finite_non_negative("--rho", l.rho)?;
    finite_non_negative("--cw", l.cw)?;
    finite_non_negative("--drag-area", l.bob_area1)?;
    finite_non_negative("--drag-area", l.bob_area2)?;
    finite_non_negative("--rod-drag-area", l.rod_area1)?;
    finite_non_negative("--rod-drag-area", l.rod_area2)?;
    finite_non_negative("--bearing-friction", l.bearing)?;
    finite_non_negative("--bearing-radius", l.bearing_radius)
}

impl PhysicalArgs {
    /// Defaults, then --preset, then --params, then the single flags; validated.
    pub fn params(&self) -> Result<Params> {
        let mut p = self.preset.map(Preset::params).unwrap_or_default();
        if let Some(path) = &self.params {
            p = read_params_file(path, p)?;
        }
        let set = |slot: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *slot = v;
            }
        };
        set(&mut p.m1, self.m1);
        set(&mut p.m2, self.m2);
        set(&mut p.l1, self.l1);
        set(&mut p.l2, self.l2);
        set(&mut p.g, self.g);
        if let Some((a, b)) = self.rod_mass {
            (p.rod1, p.rod2) = (a, b);
        }
        if let Some((a, b)) = self.joint_damping {
            (p.losses.joint1, p.losses.joint2) = (a, b);
        }
        let drag_flags = self.rho.is_some()
            || self.cw.is_some()
            || self.drag_area.is_some()
            || self.rod_drag_area.is_some();
        if drag_flags && !self.air_drag && !p.losses.has_drag() {
            return Err(Error::invalid(
                "--air-drag",
                "--rho, --cw, --drag-area and --rod-drag-area need --air-drag (or a preset or file with drag)",
            ));
        }
        if self.air_drag && !p.losses.has_drag() {
            p.losses.rho = RHO;
            p.losses.cw = CW;
            p.losses.bob_area1 = PLATE_AREA;
            p.losses.bob_area2 = PLATE_AREA;
        }
        set(&mut p.losses.rho, self.rho);
        set(&mut p.losses.cw, self.cw);
        if let Some((a, b)) = self.drag_area {
            (p.losses.bob_area1, p.losses.bob_area2) = (a, b);
        }
        if let Some((a, b)) = self.rod_drag_area {
            (p.losses.rod_area1, p.losses.rod_area2) = (a, b);
        }
        if let Some(c) = self.bearing_friction {
            p.losses.bearing = c;
            if p.losses.bearing_radius == 0.0 {
                p.losses.bearing_radius = BEARING_RADIUS;
            }
        }
        set(&mut p.losses.bearing_radius, self.bearing_radius);
        validate(&p)?;
        Ok(p)
    }
}

/// The flags that reproduce `p` exactly (for PNG metadata and CSV headers).
pub fn flags(p: &Params) -> String {
    let mut out = format!(
        "--m1 {} --m2 {} --l1 {} --l2 {} --g {}",
        p.m1, p.m2, p.l1, p.l2, p.g
    );
    if p.rod1 != 0.0 || p.rod2 != 0.0 {
        out += &format!(" --rod-mass {},{}", p.rod1, p.rod2);
    }
    let l = &p.losses;
    if l.joint1 != 0.0 || l.joint2 != 0.0 {
        out += &format!(" --joint-damping {},{}", l.joint1, l.joint2);
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
