//! What an axis of a map may vary: a component of the start or a physical parameter.

use crate::model::{Params, State};

/// What an axis of a map varies: a component of the start or a physical parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Var {
    Theta1,
    Omega1,
    Theta2,
    Omega2,
    M1,
    M2,
    /// m2 / m1, m1 held.
    MassRatio,
    L1,
    L2,
    /// l2 / l1, l1 held.
    LengthRatio,
    G,
    /// Both joints' damping at once (N m s).
    Damping,
    Joint1,
    Joint2,
    Rod1,
    Rod2,
}

impl Var {
    pub const ALL: [Var; 16] = [
        Var::Theta1,
        Var::Omega1,
        Var::Theta2,
        Var::Omega2,
        Var::M1,
        Var::M2,
        Var::MassRatio,
        Var::L1,
        Var::L2,
        Var::LengthRatio,
        Var::G,
        Var::Damping,
        Var::Joint1,
        Var::Joint2,
        Var::Rod1,
        Var::Rod2,
    ];

    /// How the command line and the explorer spell it.
    pub fn name(self) -> &'static str {
        match self {
            Var::Theta1 => "theta1",
            Var::Omega1 => "omega1",
            Var::Theta2 => "theta2",
            Var::Omega2 => "omega2",
            Var::M1 => "m1",
            Var::M2 => "m2",
            Var::MassRatio => "m2/m1",
            Var::L1 => "l1",
            Var::L2 => "l2",
            Var::LengthRatio => "l2/l1",
            Var::G => "g",
            Var::Damping => "damping",
            Var::Joint1 => "joint1",
            Var::Joint2 => "joint2",
            Var::Rod1 => "rod1",
            Var::Rod2 => "rod2",
        }
    }

    /// Its name as an array's name (a Zarr store's coordinate, which may not hold `/`).
    pub fn key(self) -> &'static str {
        match self {
            Var::MassRatio => "mass_ratio",
            Var::LengthRatio => "length_ratio",
            v => v.name(),
        }
    }

    /// Its label on a picture's axis.
    pub fn symbol(self) -> &'static str {
        match self {
            Var::Theta1 => "θ1",
            Var::Omega1 => "ω1",
            Var::Theta2 => "θ2",
            Var::Omega2 => "ω2",
            Var::Damping => "joint damping",
            Var::Joint1 => "pivot damping",
            Var::Joint2 => "joint damping c2",
            Var::Rod1 => "rod mass 1",
            Var::Rod2 => "rod mass 2",
            v => v.name(),
        }
    }

    pub fn unit(self) -> &'static str {
        match self {
            Var::Theta1 | Var::Theta2 => "rad",
            Var::Omega1 | Var::Omega2 => "rad/s",
            Var::M1 | Var::M2 | Var::Rod1 | Var::Rod2 => "kg",
            Var::MassRatio | Var::LengthRatio => "1",
            Var::L1 | Var::L2 => "m",
            Var::G => "m/s^2",
            Var::Damping | Var::Joint1 | Var::Joint2 => "N m s",
        }
    }

    /// The range the explorer first shows along an axis (the command line asks for one):
    /// a turn for angles, and around the default pendulum (1 kg, 1 m, g = 9.81) otherwise.
    pub fn default_range(self) -> super::Range {
        let (min, max) = match self {
            Var::Theta1 | Var::Theta2 => (-std::f64::consts::PI, std::f64::consts::PI),
            Var::Omega1 | Var::Omega2 => (-8.0, 8.0),
            Var::M1 | Var::M2 | Var::L1 | Var::L2 => (0.1, 2.0),
            Var::MassRatio | Var::LengthRatio => (0.1, 3.0),
            Var::G => (1.0, 25.0),
            Var::Damping | Var::Joint1 | Var::Joint2 => (0.0, 0.05),
            Var::Rod1 | Var::Rod2 => (0.0, 1.0),
        };
        super::Range { min, max }
    }

    /// The values an axis may take in an explorer: a turn for angles (a start beyond pi has
    /// already flipped), any speed (the step's stability bounds those, per plane), and a
    /// parameter's own range ([`crate::params::RANGES`]; a ratio takes its numerator's, as
    /// over a denominator of 1). The command line accepts these; of what lies beyond a
    /// parameter's range it takes only an equivalent pendulum's negative masses.
    pub fn limits(self) -> super::Range {
        use std::f64::consts::PI;
        let field = match self {
            Var::Theta1 | Var::Theta2 => return super::Range { min: -PI, max: PI },
            Var::Omega1 | Var::Omega2 => {
                return super::Range {
                    min: f64::NEG_INFINITY,
                    max: f64::INFINITY,
                };
            }
            Var::M1 => "m1",
            Var::M2 | Var::MassRatio => "m2",
            Var::L1 => "l1",
            Var::L2 | Var::LengthRatio => "l2",
            Var::G => "g",
            Var::Damping | Var::Joint1 | Var::Joint2 => "joint_damping",
            Var::Rod1 | Var::Rod2 => "rod_mass",
        };
        let (min, max) = crate::params::range_of(field);
        super::Range { min, max }
    }

    pub fn is_angle(self) -> bool {
        matches!(self, Var::Theta1 | Var::Theta2)
    }

    /// A component of the start (not a parameter).
    pub fn is_state(self) -> bool {
        (self.code() as usize) < 4
    }

    /// Its code in the shaders' `Params.x_var`/`y_var` (shaders/common.wgsl `VAR_*`): the
    /// state's components first, in the order of the state vector.
    pub fn code(self) -> u32 {
        Var::ALL.iter().position(|&v| v == self).expect("listed") as u32
    }

    /// Measured in mass, so the GPU's mass scale applies to it (src/gpu/layout.rs).
    pub fn is_mass(self) -> bool {
        matches!(
            self,
            Var::M1 | Var::M2 | Var::Rod1 | Var::Rod2 | Var::Damping | Var::Joint1 | Var::Joint2
        )
    }

    /// A ratio, set after the value it multiplies (so m1 and m2/m1 compose either way).
    pub fn is_ratio(self) -> bool {
        matches!(self, Var::MassRatio | Var::LengthRatio)
    }

    /// The values it sets (parameters by name, the damping by joint): two axes may not set
    /// one, nor an axis and a value given beside it.
    pub fn writes(self) -> &'static [&'static str] {
        match self {
            Var::Theta1 => &["theta1"],
            Var::Omega1 => &["omega1"],
            Var::Theta2 => &["theta2"],
            Var::Omega2 => &["omega2"],
            Var::M1 => &["m1"],
            Var::M2 | Var::MassRatio => &["m2"],
            Var::L1 => &["l1"],
            Var::L2 | Var::LengthRatio => &["l2"],
            Var::G => &["g"],
            Var::Damping => &["joint1", "joint2"],
            Var::Joint1 => &["joint1"],
            Var::Joint2 => &["joint2"],
            Var::Rod1 => &["rod1"],
            Var::Rod2 => &["rod2"],
        }
    }

    /// Whether it sets a value that `other` sets too.
    pub fn overlaps(self, other: Var) -> bool {
        self.writes().iter().any(|w| other.writes().contains(w))
    }

    /// Sets it to `v` in a start and its parameters.
    pub fn set(self, v: f64, p: &mut Params, s: &mut State) {
        match self {
            Var::Theta1 => s.theta1 = v,
            Var::Omega1 => s.omega1 = v,
            Var::Theta2 => s.theta2 = v,
            Var::Omega2 => s.omega2 = v,
            Var::M1 => p.m1 = v,
            Var::M2 => p.m2 = v,
            Var::MassRatio => p.m2 = v * p.m1,
            Var::L1 => p.l1 = v,
            Var::L2 => p.l2 = v,
            Var::LengthRatio => p.l2 = v * p.l1,
            Var::G => p.g = v,
            Var::Damping => (p.losses.joint1, p.losses.joint2) = (v, v),
            Var::Joint1 => p.losses.joint1 = v,
            Var::Joint2 => p.losses.joint2 = v,
            Var::Rod1 => p.rod1 = v,
            Var::Rod2 => p.rod2 = v,
        }
    }

    /// Its value in a start and its parameters.
    pub fn get(self, p: &Params, s: &State) -> f64 {
        match self {
            Var::Theta1 => s.theta1,
            Var::Omega1 => s.omega1,
            Var::Theta2 => s.theta2,
            Var::Omega2 => s.omega2,
            Var::M1 => p.m1,
            Var::M2 => p.m2,
            Var::MassRatio => p.m2 / p.m1,
            Var::L1 => p.l1,
            Var::L2 => p.l2,
            Var::LengthRatio => p.l2 / p.l1,
            Var::G => p.g,
            Var::Damping | Var::Joint1 => p.losses.joint1,
            Var::Joint2 => p.losses.joint2,
            Var::Rod1 => p.rod1,
            Var::Rod2 => p.rod2,
        }
    }

    pub fn parse(name: &str) -> Option<Var> {
        let name = name.trim().to_ascii_lowercase();
        Var::ALL
            .into_iter()
            .find(|v| v.name() == name || v.key() == name)
    }
}
