//! The double pendulum: parameters (bobs, optional uniform rods, energy losses), state,
//! energy, positions.
//!
//! Angles are measured from the downward vertical, counter-clockwise positive; the pivot is
//! the origin and y points up. Arm i carries a bob of mass m_i at its end (length l_i) and,
//! optionally, a uniform rod of mass r_i from its joint to the bob. With D = theta1 - theta2
//! the Lagrangian is
//!
//! ```text
//! T = 1/2 A omega1^2 + 1/2 B omega2^2 + C omega1 omega2 cos D
//! V = -P cos theta1 - Q cos theta2
//! A = (m1 + m2 + r2 + r1/3) l1^2      B = (m2 + r2/3) l2^2      C = (m2 + r2/2) l1 l2
//! P = (m1 + m2 + r2 + r1/2) g l1      Q = (m2 + r2/2) g l2
//! ```
//! (a rod's moment of inertia about its end is r l^2/3, its centre of mass at l/2). Point
//! masses are r1 = r2 = 0: A = M l1^2, B = m2 l2^2, C = m2 l1 l2, P = M g l1, Q = m2 g l2.
//! Losses enter the Lagrange equations as generalised forces (torques) tau1, tau2; see
//! [`Losses`].

/// Energy losses (section 2.4 of the lab report), all off by default.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Losses {
    /// Viscous joint damping (N m s): torque -c1 omega1 at the pivot and -c2 (omega2 - omega1)
    /// at the middle joint (equal and opposite on the two arms).
    pub joint1: f64,
    pub joint2: f64,
    /// Quadratic air drag, F = 1/2 rho c_w A v^2 against the local velocity: air density
    /// (kg/m^3), drag coefficient, projected areas of the bobs and of the rods (m^2).
    pub rho: f64,
    pub cw: f64,
    pub bob_area1: f64,
    pub bob_area2: f64,
    pub rod_area1: f64,
    pub rod_area2: f64,
    /// Rolling friction of the ball bearings (pivot and middle joint): a force c_R F_N at
    /// the bearing radius r (m), F_N the load on the bearing, i.e. a torque c_R r F_N against
    /// the joint's relative rotation, its sign smoothed as w / sqrt(w^2 + BEARING_SMOOTH^2).
    pub bearing: f64,
    pub bearing_radius: f64,
}

/// Angular speed (rad/s) over which bearing friction turns on: the torque is
/// c_R r F_N w / sqrt(w^2 + BEARING_SMOOTH^2), so the equations stay smooth through w = 0
/// (and non-stiff: the friction's slope c_R r F_N / 0.01 is far below the arms' inertia / dt).
/// (An algebraic sign rather than tanh, whose dual-number derivative overflows at w / 0.01
/// of a few hundred.)
pub const BEARING_SMOOTH: f64 = 0.01;

impl Losses {
    pub fn any(&self) -> bool {
        self.joint1 != 0.0 || self.joint2 != 0.0 || self.has_drag() || self.has_bearings()
    }

    /// Which losses a GPU pipeline must compile in: bit 0 joint damping, bit 1 air drag,
    /// bit 2 bearing friction (the shaders' `override LOSSES`).
    pub fn kinds(&self) -> u32 {
        (self.joint1 != 0.0 || self.joint2 != 0.0) as u32
            | (self.has_drag() as u32) << 1
            | (self.has_bearings() as u32) << 2
    }

    pub fn has_bearings(&self) -> bool {
        self.bearing * self.bearing_radius != 0.0
    }

    pub fn has_drag(&self) -> bool {
        self.rho * self.cw * (self.bob_area1 + self.bob_area2 + self.rod_area1 + self.rod_area2)
            != 0.0
    }

    /// 1/2 rho c_w A for each bob and rod (N s^2/m^2): the drag force is this times v^2.
    pub fn drag_factors(&self) -> [f64; 4] {
        let k = 0.5 * self.rho * self.cw;
        [
            k * self.bob_area1,
            k * self.bob_area2,
            k * self.rod_area1,
            k * self.rod_area2,
        ]
    }
}

/// Physical parameters, SI units.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Params {
    /// Upper bob mass (kg).
    pub m1: f64,
    /// Lower bob mass (kg).
    pub m2: f64,
    /// Upper arm length (m).
    pub l1: f64,
    /// Lower arm length (m).
    pub l2: f64,
    /// Gravitational acceleration (m/s^2).
    pub g: f64,
    /// Masses of uniform rods along the upper and lower arm (kg); 0 for massless arms.
    pub rod1: f64,
    pub rod2: f64,
    pub losses: Losses,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            m1: 1.0,
            m2: 1.0,
            l1: 1.0,
            l2: 1.0,
            g: 9.81,
            rod1: 0.0,
            rod2: 0.0,
            losses: Losses::default(),
        }
    }
}

/// The coefficients of T and V (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub p: f64,
    pub q: f64,
}

/// State `(theta1, omega1, theta2, omega2)` in rad and rad/s.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct State {
    pub theta1: f64,
    pub omega1: f64,
    pub theta2: f64,
    pub omega2: f64,
}

impl State {
    pub fn at_rest(theta1: f64, theta2: f64) -> Self {
        State {
            theta1,
            theta2,
            ..Default::default()
        }
    }

    pub fn to_array(self) -> [f64; 4] {
        [self.theta1, self.omega1, self.theta2, self.omega2]
    }

    pub fn from_array(a: [f64; 4]) -> Self {
        State {
            theta1: a[0],
            omega1: a[1],
            theta2: a[2],
            omega2: a[3],
        }
    }
}

/// Bob positions `(x1, y1, x2, y2)` in m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Positions {
    pub x1: f64,
    pub y1: f64,
    pub x2: f64,
    pub y2: f64,
}

impl Params {
    /// Total mass M = m1 + m2 (kg) of the bobs.
    pub fn total_mass(&self) -> f64 {
        self.m1 + self.m2
    }

    /// All moving mass (kg), and the part below the middle joint.
    pub fn moving_mass(&self) -> (f64, f64) {
        let lower = self.m2 + self.rod2;
        (self.m1 + self.rod1 + lower, lower)
    }

    pub fn inertia(&self) -> Inertia {
        let (r1, r2) = (self.rod1, self.rod2);
        let outer = self.m2 + r2 / 2.0;
        Inertia {
            a: (self.m1 + self.m2 + r2 + r1 / 3.0) * self.l1 * self.l1,
            b: (self.m2 + r2 / 3.0) * self.l2 * self.l2,
            c: outer * self.l1 * self.l2,
            p: (self.m1 + self.m2 + r2 + r1 / 2.0) * self.g * self.l1,
            q: outer * self.g * self.l2,
        }
    }

    /// Bobs and rods whose moments are `moments` = [A, B, C, P] (kg m^2, kg m^2, kg m^2,
    /// J) at arm lengths l1, l2 (m) and gravity g (m/s^2); Q follows as C g / l1, as for any
    /// rigid lower arm. Any pendulum of rigid arms has such an equivalent: a rod's mass sits
    /// at a third of its arm's inertia, a bar's may sit nearer the joint, and then a bob or a
    /// rod comes out negative (a uniform bar from joint to marker is a rod and no bob). The
    /// moments must be a real pendulum's: the caller checks them
    /// (`crate::params::validate`), naming where they came from.
    pub fn from_moments(
        [a, b, c, p]: [f64; 4],
        (l1, l2, g): (f64, f64, f64),
        losses: Losses,
    ) -> Params {
        let rod2 = 6.0 * (c / (l1 * l2) - b / (l2 * l2));
        let m2 = b / (l2 * l2) - rod2 / 3.0;
        let rod1 = 6.0 * (p / (g * l1) - a / (l1 * l1));
        let m1 = p / (g * l1) - (m2 + rod2) - rod1 / 2.0;
        Params {
            m1,
            m2,
            l1,
            l2,
            g,
            rod1,
            rod2,
            losses,
        }
    }

    pub fn kinetic_energy(&self, s: &State) -> f64 {
        let k = self.inertia();
        let c = (s.theta1 - s.theta2).cos();
        0.5 * k.a * s.omega1 * s.omega1
            + 0.5 * k.b * s.omega2 * s.omega2
            + k.c * s.omega1 * s.omega2 * c
    }

    pub fn potential_energy(&self, theta1: f64, theta2: f64) -> f64 {
        let k = self.inertia();
        -k.p * theta1.cos() - k.q * theta2.cos()
    }

    /// Total mechanical energy (J).
    pub fn energy(&self, s: &State) -> f64 {
        self.kinetic_energy(s) + self.potential_energy(s.theta1, s.theta2)
    }

    pub fn positions(&self, s: &State) -> Positions {
        let x1 = self.l1 * s.theta1.sin();
        let y1 = -self.l1 * s.theta1.cos();
        Positions {
            x1,
            y1,
            x2: x1 + self.l2 * s.theta2.sin(),
            y2: y1 - self.l2 * s.theta2.cos(),
        }
    }

    /// The lowest energy (J) at which either arm can reach the top.
    ///
    /// Kinetic energy is never negative, so a pendulum whose energy E is below the minimum of V
    /// over the set {|theta1| = pi} or {|theta2| = pi} can never reach it (energy is conserved,
    /// or lost with damping). On {theta1 = pi}, V = P - Q cos theta2 is least at theta2 = 0;
    /// on {theta2 = pi}, V = -P cos theta1 + Q is least at theta1 = 0. Both minima together:
    /// E* = -|P - Q| (point masses: -|M g l1 - m2 g l2|), for any masses, rods and lengths.
    pub fn flip_energy(&self) -> f64 {
        let k = self.inertia();
        -(k.p - k.q).abs()
    }

    /// Scale of the potential energy (J): the size of the numbers the energy is made of,
    /// which sets its round-off.
    pub fn energy_scale(&self) -> f64 {
        let k = self.inertia();
        k.p + k.q
    }

    /// Below this energy (J) a start is certain never to flip, in a precision with relative
    /// round-off `epsilon`. The margin of 100 epsilon times the energy scale covers the rounding
    /// of the few products and cosines that make up the energy, so no start that could flip is
    /// ever skipped.
    pub fn no_flip_threshold(&self, epsilon: f64) -> f64 {
        self.flip_energy() - 100.0 * epsilon * self.energy_scale()
    }

    /// Small-angle normal-mode angular frequencies squared (1/s^2), slow then fast.
    ///
    /// Linearising gives M_0 x'' + K x = 0 with M_0 = [[A, C], [C, B]] and K = diag(P, Q);
    /// the eigenvalues of M_0^-1 K solve det(K - w^2 M_0) = 0, a quadratic in w^2.
    pub fn normal_modes_squared(&self) -> (f64, f64) {
        let k = self.inertia();
        // a w^4 + b w^2 + c = 0
        let a = k.a * k.b - k.c * k.c;
        let b = -(k.a * k.q + k.b * k.p);
        let c = k.p * k.q;
        let disc = (b * b - 4.0 * a * c).sqrt();
        ((-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a))
    }

    /// Angular accelerations without losses from the closed form the shader uses:
    /// a1 = (B f1 - C cos D f2) / det, a2 = (A f2 - C cos D f1) / det, det = A B - C^2 cos^2 D,
    /// f1 = -C sin D omega2^2 - P sin theta1, f2 = C sin D omega1^2 - Q sin theta2.
    pub fn accelerations_closed_form(&self, s: &State) -> (f64, f64) {
        let k = self.inertia();
        let (sd, cd) = (s.theta1 - s.theta2).sin_cos();
        let f1 = -k.c * sd * s.omega2 * s.omega2 - k.p * s.theta1.sin();
        let f2 = k.c * sd * s.omega1 * s.omega1 - k.q * s.theta2.sin();
        let det = k.a * k.b - k.c * k.c * cd * cd;
        (
            (k.b * f1 - k.c * cd * f2) / det,
            (k.a * f2 - k.c * cd * f1) / det,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flip_energy_equal_arms_is_minus_mgl() {
        let p = Params::default();
        // M g l1 - m2 g l2 = 2g - g = g, so E* = -g.
        assert!((p.flip_energy() + p.g).abs() < 1e-12);
    }

    #[test]
    fn positions_hang_down_at_rest() {
        let p = Params::default();
        let pos = p.positions(&State::at_rest(0.0, 0.0));
        assert_eq!((pos.x1, pos.y1, pos.x2, pos.y2), (0.0, -1.0, 0.0, -2.0));
    }
}
