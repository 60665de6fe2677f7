//! Where a run's physical parameters come from: defaults, the `lab` preset, a TOML parameter
//! file, single values given on top ([`ParamSources`]), and the allowed range of each.
//! Precedence: defaults, then the preset, then the file, then single values.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::model::{Losses, Params};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// The lab report's apparatus (../shared/data/README.md): bobs 0.301 and 0.297 kg, arms
    /// 0.30 and 0.195 m from the tracked data, acrylic plates as rods (0.140 kg: two plates on
    /// the upper arm, 0.070 kg), quadratic air drag on the plates (rho 1.2, c_w 2, 1.45e-3 m^2
    /// a plate), ball-bearing rolling friction c_R 0.75e-3 (the report: 0.5e-3 to 1e-3).
    Lab,
}

impl Preset {
    pub const ALL: [Preset; 1] = [Preset::Lab];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Lab => "lab",
        }
    }

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

/// The sources of a run's parameters, each optional: a preset, a TOML file, and single
/// values (SI units) that override both. `Default` is the plain default pendulum.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParamSources {
    pub m1: Option<f64>,
    pub m2: Option<f64>,
    pub l1: Option<f64>,
    pub l2: Option<f64>,
    pub g: Option<f64>,
    /// Masses of uniform rods along the arms (kg).
    pub rod_mass: Option<(f64, f64)>,
    /// Viscous joint damping (N m s) at the pivot and the middle joint.
    pub joint_damping: Option<(f64, f64)>,
    /// Quadratic air drag on, with the report's air and plates unless given below.
    pub air_drag: bool,
    pub rho: Option<f64>,
    pub cw: Option<f64>,
    /// Projected areas of the bobs and of the rods (m^2).
    pub drag_area: Option<(f64, f64)>,
    pub rod_drag_area: Option<(f64, f64)>,
    /// Rolling-friction coefficient c_R and the radius (m) it acts at.
    pub bearing_friction: Option<f64>,
    pub bearing_radius: Option<f64>,
    pub preset: Option<Preset>,
    /// A TOML parameter file (keys as the fields here, air drag in a table `[air_drag]`).
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
    rod_mass: Option<Vec<f64>>,
    joint_damping: Option<Vec<f64>>,
    bearing_friction: Option<f64>,
    bearing_radius: Option<f64>,
    air_drag: Option<AirDragFile>,
    moments: Option<MomentsFile>,
    /// What `fit` learned of the pendulum beyond its model, for a forecast
    /// (`fit::calibration`, which reads and checks it).
    #[allow(dead_code)]
    calibration: Option<toml::Value>,
}

/// A pendulum stated by its moments over the upper arm's gravity moment P, as `fit` writes
/// a model found from the motion (the motion cannot see P itself: a 1 kg scale is taken).
#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct MomentsFile {
    /// A/P, B/P, C/P (s^2): the arms' inertias about their joints and their coupling.
    a: f64,
    b: f64,
    c: f64,
    /// The joints' damping over P (s).
    k1: Option<f64>,
    k2: Option<f64>,
    /// P itself (J), where the pendulum was weighed ([`crate::fit::weighed`]).
    p: Option<f64>,
}

#[derive(Deserialize, Debug, Default)]
#[serde(deny_unknown_fields)]
struct AirDragFile {
    rho: Option<f64>,
    cw: Option<f64>,
    bob_area: Option<Vec<f64>>,
    rod_area: Option<Vec<f64>>,
}

fn read_params_file(path: &Path, base: Params) -> Result<Params> {
    let text = crate::input::read_text("params", path, crate::input::TOML_CAP)?;
    let file: ParamsFile = toml::from_str(&text)
        .map_err(|e| Error::invalid("params", format!("{}: {e}", path.display())))?;
    let in_file =
        |reason: String| Error::invalid("params", format!("{}: {reason}", path.display()));
    // serde takes the first two of a longer array silently: pairs are read as lists.
    let pair = |key: &str, v: &Option<Vec<f64>>| -> Result<Option<[f64; 2]>> {
        match v.as_deref() {
            None => Ok(None),
            Some([a, b]) => Ok(Some([*a, *b])),
            Some(other) => Err(in_file(format!(
                "key {key}: {} values given; it takes two, e.g. [0.1, 0.05]",
                other.len()
            ))),
        }
    };
    let mut p = base;
    let mut no_area = false;
    let set = |slot: &mut f64, v: Option<f64>| {
        if let Some(v) = v {
            *slot = v;
        }
    };
    // Impossible values name the key and the file.
    let as_key = |e: Error| match e {
        Error::InvalidSpec { field, reason } => in_file(format!("key {}: {reason}", key_of(field))),
        e => e,
    };
    // Masses given one by one are each in their range (only a model stated by its moments
    // may hold a negative one).
    let rods = pair("rod_mass", &file.rod_mass)?;
    let given = [("m1", file.m1), ("m2", file.m2)]
        .into_iter()
        .chain(rods.into_iter().flatten().map(|r| ("rod_mass", Some(r))));
    for (field, v) in given {
        v.map(|v| in_range(field, v)).transpose().map_err(as_key)?;
    }
    set(&mut p.m1, file.m1);
    set(&mut p.m2, file.m2);
    set(&mut p.l1, file.l1);
    set(&mut p.l2, file.l2);
    set(&mut p.g, file.g);
    if let Some([a, b]) = rods {
        (p.rod1, p.rod2) = (a, b);
    }
    if let Some([a, b]) = pair("joint_damping", &file.joint_damping)? {
        (p.losses.joint1, p.losses.joint2) = (a, b);
    }
    if let Some(c) = file.bearing_friction {
        p.losses.bearing = c;
        p.losses.bearing_radius = file.bearing_radius.unwrap_or(BEARING_RADIUS);
    } else if let Some(r) = file.bearing_radius {
        p.losses.bearing_radius = r;
    }
    if let Some(air) = &file.air_drag {
        p.losses.rho = air.rho.unwrap_or(RHO);
        p.losses.cw = air.cw.unwrap_or(CW);
        let bob = pair("air_drag.bob_area", &air.bob_area)?;
        let rod = pair("air_drag.rod_area", &air.rod_area)?;
        no_area = bob.is_none() && rod.is_none();
        let [a1, a2] = bob.unwrap_or([0.0; 2]);
        let [r1, r2] = rod.unwrap_or([0.0; 2]);
        (p.losses.bob_area1, p.losses.bob_area2) = (a1, a2);
        (p.losses.rod_area1, p.losses.rod_area2) = (r1, r2);
    }
    if let Some(m) = &file.moments {
        let stated = [
            ("m1", file.m1.is_some()),
            ("m2", file.m2.is_some()),
            ("rod_mass", file.rod_mass.is_some()),
            ("joint_damping", file.joint_damping.is_some()),
            ("air_drag", file.air_drag.is_some()),
            ("bearing_friction", file.bearing_friction.is_some()),
        ];
        if let Some((key, _)) = stated.iter().find(|k| k.1) {
            return Err(in_file(format!(
                "key {key} beside the table [moments]: the moments state the whole pendulum (its masses and damping as k1, k2); give one or the other"
            )));
        }
        for (key, v) in [("a", m.a), ("b", m.b), ("c", m.c)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(in_file(format!(
                    "key moments.{key}: {v} is not allowed; a moment over P must be > 0 (s^2)"
                )));
            }
        }
        let (k1, k2) = (m.k1.unwrap_or(0.0), m.k2.unwrap_or(0.0));
        for (key, v) in [("k1", k1), ("k2", k2)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(in_file(format!(
                    "key moments.{key}: {v} is not allowed; a damping over P must be >= 0 (s)"
                )));
            }
        }
        // P as weighed, else one kilogram's scale: P = 1 kg g l1.
        if let Some(v) = m.p.filter(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(in_file(format!(
                "key moments.p: {v} is not allowed; the gravity moment P must be > 0 (J)"
            )));
        }
        let unit = m.p.unwrap_or(p.g * p.l1);
        p = Params::from_moments(
            [m.a * unit, m.b * unit, m.c * unit, unit],
            (p.l1, p.l2, p.g),
            Losses {
                joint1: k1 * unit,
                joint2: k2 * unit,
                ..Losses::default()
            },
        );
        validate(&p).map_err(|e| match e {
            Error::InvalidSpec { reason, .. } => in_file(format!("table [moments]: {reason}")),
            e => e,
        })?;
    }
    validate(&p).map_err(as_key)?;
    if no_area {
        return Err(in_file(
            "table [air_drag] needs bob_area or rod_area (m^2): without an area there is no drag"
                .into(),
        ));
    }
    Ok(p)
}

/// The file key of a field (air-drag keys in their table).
fn key_of(field: &str) -> &str {
    match field {
        "rho" => "air_drag.rho",
        "cw" => "air_drag.cw",
        "drag_area" => "air_drag.bob_area",
        "rod_drag_area" => "air_drag.rod_area",
        f => f,
    }
}

/// The range each parameter may take: wide enough for any pendulum on a bench or in a
/// textbook (masses far beyond: they drop out of the motion, and the GPU's coefficients are
/// scaled by a power of two, tests/hardening.rs), narrow enough that every coefficient the
/// runs form from them (inertias up to M l^2, torques up to M g l, the energies and the
/// stability limits) stays finite in f64 and, scaled, in f32. `--help` states them.
pub const RANGES: [(&str, f64, f64); 13] = [
    ("m1", 1e-30, 1e30),
    ("m2", 1e-30, 1e30),
    ("l1", 1e-4, 1e4),
    ("l2", 1e-4, 1e4),
    ("g", 1e-6, 1e6),
    ("rod_mass", 0.0, 1e30),
    ("joint_damping", 0.0, 1e30),
    ("rho", 0.0, 1e4),
    ("cw", 0.0, 100.0),
    ("drag_area", 0.0, 1e4),
    ("rod_drag_area", 0.0, 1e4),
    ("bearing_friction", 0.0, 1.0),
    ("bearing_radius", 0.0, 1.0),
];

/// The range [`RANGES`] gives `field` (lowest, highest); 0..f64::MAX for one it does not
/// name.
pub fn range_of(field: &str) -> (f64, f64) {
    RANGES
        .iter()
        .find(|r| r.0 == field)
        .map_or((0.0, f64::MAX), |r| (r.1, r.2))
}

/// `v` within the range [`RANGES`] gives `field`, else an error naming it and the range.
fn in_range(field: &'static str, v: f64) -> Result<()> {
    let (lo, hi) = range_of(field);
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(Error::invalid(
            field,
            format!(
                "{} is not allowed; it must be between {} and {}",
                short(v),
                short(lo),
                short(hi)
            ),
        ))
    }
}

/// A number as a person writes it: plain when moderate, else in exponent form.
fn short(x: f64) -> String {
    match x == 0.0 || (1e-3..1e4).contains(&x.abs()) {
        true => format!("{x}"),
        false => format!("{x:e}"),
    }
}

/// Every parameter in its allowed range ([`RANGES`]); the error names the field of
/// [`ParamSources`].
///
/// A pendulum stated by its moments (a model identified from data, [`Params::from_moments`])
/// may have a negative bob or rod: it is accepted where its moments are a real pendulum's
/// (A, B, P, Q > 0, A B > C^2, each within the masses' range), without air drag or bearing
/// friction (which act on the masses themselves). Masses given one by one are checked
/// against their ranges by [`check_masses`] first.
pub fn validate(p: &Params) -> Result<()> {
    for (field, v) in [("l1", p.l1), ("l2", p.l2), ("g", p.g)] {
        in_range(field, v)?;
    }
    let masses = [p.m1, p.m2, p.rod1, p.rod2];
    if masses.iter().all(|&m| m >= 0.0) || masses.iter().any(|m| !m.is_finite()) {
        check_masses(p)?;
    } else {
        equivalent(p)?;
    }
    let l = &p.losses;
    in_range("joint_damping", l.joint1)?;
    in_range("joint_damping", l.joint2)?;
    in_range("rho", l.rho)?;
    in_range("cw", l.cw)?;
    in_range("drag_area", l.bob_area1)?;
    in_range("drag_area", l.bob_area2)?;
    in_range("rod_drag_area", l.rod_area1)?;
    in_range("rod_drag_area", l.rod_area2)?;
    in_range("bearing_friction", l.bearing)?;
    in_range("bearing_radius", l.bearing_radius)?;
    if l.bearing > 0.0 && l.bearing_radius == 0.0 {
        return Err(Error::invalid(
            "bearing_radius",
            "0 is not allowed with bearing friction: the friction acts at a radius > 0",
        ));
    }
    Ok(())
}

/// The bobs' and rods' masses within their ranges ([`RANGES`]).
pub fn check_masses(p: &Params) -> Result<()> {
    in_range("m1", p.m1)?;
    in_range("m2", p.m2)?;
    in_range("rod_mass", p.rod1)?;
    in_range("rod_mass", p.rod2)
}

/// A pendulum with a negative bob or rod: an equivalent one, accepted where its moments are
/// a real pendulum's and nothing acts on its masses one by one.
fn equivalent(p: &Params) -> Result<()> {
    let k = p.inertia();
    // The masses' own bound, and that of a moment formed from them (up to M l^2 and M g l).
    let hi = RANGES[0].2;
    let real = [k.a, k.b, k.p, k.q]
        .iter()
        .all(|&x| x > 0.0 && x < hi * 1e8)
        && k.a * k.b > k.c * k.c
        && [p.m1, p.m2, p.rod1, p.rod2].iter().all(|m| m.abs() < hi);
    if !real {
        return Err(Error::invalid(
            "m1",
            format!(
                "bobs {} and {} kg with rods {} and {} kg are no pendulum: a negative mass is allowed only in a model stated by its moments, and those must be a real pendulum's (inertias and gravity's moments > 0, A B > C^2; here A {:e}, B {:e}, C {:e}, P {:e}, Q {:e})",
                short(p.m1),
                short(p.m2),
                short(p.rod1),
                short(p.rod2),
                k.a,
                k.b,
                k.c,
                k.p,
                k.q
            ),
        ));
    }
    if p.losses.has_drag() || p.losses.has_bearings() {
        return Err(Error::invalid(
            "air_drag",
            "a pendulum stated by its moments (with a negative bob or rod) takes joint damping only: air drag and bearing friction act on the masses themselves",
        ));
    }
    Ok(())
}

impl ParamSources {
    /// Defaults, then the preset, then the file, then the single values; validated.
    pub fn resolve(&self) -> Result<Params> {
        let mut p = self.preset.map(Preset::params).unwrap_or_default();
        if let Some(path) = &self.params {
            p = read_params_file(path, p)?;
        }
        let set = |slot: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *slot = v;
            }
        };
        // Masses given one by one are each in their range (only a model stated by its
        // moments may hold a negative one).
        for (field, v) in [("m1", self.m1), ("m2", self.m2)] {
            v.map(|v| in_range(field, v)).transpose()?;
        }
        if let Some((a, b)) = self.rod_mass {
            in_range("rod_mass", a)?;
            in_range("rod_mass", b)?;
        }
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
                "air_drag",
                "rho, cw, drag area and rod drag area need air drag switched on (or a preset or file with drag)",
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

/// The model's parameters as JSON, SI units.
pub fn to_json(p: &Params) -> serde_json::Value {
    let l = &p.losses;
    serde_json::json!({
        "m1": p.m1, "m2": p.m2, "l1": p.l1, "l2": p.l2, "g": p.g,
        "rod_mass": [p.rod1, p.rod2],
        "joint_damping": [l.joint1, l.joint2],
        "air_drag": { "rho": l.rho, "cw": l.cw, "bob_area": [l.bob_area1, l.bob_area2],
                      "rod_area": [l.rod_area1, l.rod_area2] },
        "bearing_friction": l.bearing, "bearing_radius": l.bearing_radius,
    })
}
