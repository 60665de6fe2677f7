//! The point-mass double pendulum: parameters, state, energy, positions.
//!
//! Angles are measured from the downward vertical, counter-clockwise positive; the pivot is
//! the origin and y points up. With D = theta1 - theta2 and M = m1 + m2 the Lagrangian gives
//!
//! ```text
//! T = 1/2 M l1^2 omega1^2 + 1/2 m2 l2^2 omega2^2 + m2 l1 l2 omega1 omega2 cos D
//! V = -M g l1 cos theta1 - m2 g l2 cos theta2
//! ```

/// Physical parameters, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
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
}

impl Default for Params {
    fn default() -> Self {
        Params {
            m1: 1.0,
            m2: 1.0,
            l1: 1.0,
            l2: 1.0,
            g: 9.81,
        }
    }
}

/// State `(theta1, omega1, theta2, omega2)` in rad and rad/s.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
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
    /// Total mass M = m1 + m2 (kg).
    pub fn total_mass(&self) -> f64 {
        self.m1 + self.m2
    }

    pub fn kinetic_energy(&self, s: &State) -> f64 {
        let m = self.total_mass();
        let c = (s.theta1 - s.theta2).cos();
        0.5 * m * self.l1 * self.l1 * s.omega1 * s.omega1
            + 0.5 * self.m2 * self.l2 * self.l2 * s.omega2 * s.omega2
            + self.m2 * self.l1 * self.l2 * s.omega1 * s.omega2 * c
    }

    pub fn potential_energy(&self, theta1: f64, theta2: f64) -> f64 {
        -self.total_mass() * self.g * self.l1 * theta1.cos()
            - self.m2 * self.g * self.l2 * theta2.cos()
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
    /// or lost with damping). On {theta1 = pi}, V = M g l1 - m2 g l2 cos theta2 is least at
    /// theta2 = 0; on {theta2 = pi}, V = -M g l1 cos theta1 + m2 g l2 is least at theta1 = 0.
    /// Both minima together: E* = -|M g l1 - m2 g l2|, for any masses and lengths.
    pub fn flip_energy(&self) -> f64 {
        let upper = self.total_mass() * self.g * self.l1 - self.m2 * self.g * self.l2;
        let lower = -self.total_mass() * self.g * self.l1 + self.m2 * self.g * self.l2;
        upper.min(lower)
    }

    /// Scale of the potential energy (J): the size of the numbers the energy is made of,
    /// which sets its round-off.
    pub fn energy_scale(&self) -> f64 {
        self.total_mass() * self.g * self.l1 + self.m2 * self.g * self.l2
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
    /// Linearising gives M_0 x'' + K x = 0 with M_0 = [[M l1^2, m2 l1 l2], [m2 l1 l2, m2 l2^2]]
    /// and K = diag(M g l1, m2 g l2); the eigenvalues of M_0^-1 K solve
    /// det(K - w^2 M_0) = 0, a quadratic in w^2.
    pub fn normal_modes_squared(&self) -> (f64, f64) {
        let (m, m2, l1, l2, g) = (self.total_mass(), self.m2, self.l1, self.l2, self.g);
        // a w^4 + b w^2 + c = 0
        let a = m * m2 * l1 * l1 * l2 * l2 - m2 * m2 * l1 * l1 * l2 * l2;
        let b = -(m * l1 * l1 * m2 * g * l2 + m2 * l2 * l2 * m * g * l1);
        let c = m * g * l1 * m2 * g * l2;
        let disc = (b * b - 4.0 * a * c).sqrt();
        ((-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a))
    }

    /// Angular accelerations from the report's closed form (the one the shader uses).
    pub fn accelerations_closed_form(&self, s: &State) -> (f64, f64) {
        let (m, m2, l1, l2, g) = (self.total_mass(), self.m2, self.l1, self.l2, self.g);
        let d = s.theta1 - s.theta2;
        let (sd, cd) = d.sin_cos();
        let (s1, s2) = (s.theta1.sin(), s.theta2.sin());
        let (w1sq, w2sq) = (s.omega1 * s.omega1, s.omega2 * s.omega2);
        let den = m - m2 * cd * cd;
        let a1 = (-m2 * l2 * w2sq * sd - g * m * s1 - m2 * l1 * w1sq * sd * cd + g * m2 * s2 * cd)
            / (l1 * den);
        let a2 = (m2 * l2 * w2sq * sd * cd + g * m * s1 * cd + m * l1 * w1sq * sd - g * m * s2)
            / (l2 * den);
        (a1, a2)
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
