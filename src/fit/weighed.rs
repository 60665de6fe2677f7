//! The scale of a model found from the motion, from the pendulum's weighed mass. The motion
//! fixes the moments over the upper arm's gravity moment P only ([`super::identify`]), so
//! the model is kept on a 1 kg scale; one mass in kilograms fixes P, and the moments then
//! come in kg m^2 and J, the joints' damping in N m s and the energies in joules. Scaling
//! every mass and damping by one factor leaves the motion as it is: nothing else changes.

use crate::model::Params;

/// The weighed mass and the factor it puts on the model's 1 kg scale.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Weighed {
    /// What was weighed (kg): everything that swings, both arms with their bobs.
    pub mass: f64,
    /// What every mass and damping of the model on its 1 kg scale is multiplied by.
    pub factor: f64,
    /// The upper arm's gravity moment P (J) on the weighed scale.
    pub p: f64,
}

impl Weighed {
    /// The scale at which the equivalent pendulum `p` (point bobs on uniform rods,
    /// [`Params::from_moments`]) weighs `mass` in all: exact where the real arms are bobs on
    /// uniform rods, whose equivalent is themselves. Where a mass of the equivalent comes out
    /// negative (a bar's mass nearer its joint than a rod's) its total is no real mass, and
    /// the reason is returned instead.
    pub fn of(p: &Params, mass: f64) -> Result<Weighed, String> {
        let masses = [p.m1, p.m2, p.rod1, p.rod2];
        if !masses.iter().all(|&m| m >= 0.0) {
            return Err(format!(
                "the weighed {mass} kg cannot set the moments' scale: no pendulum of point bobs on uniform rods has these moments (its masses would be {:.3}, {:.3}, {:.3} and {:.3} on a 1 kg scale), so no total mass is known to match; the moments stay over P",
                p.m1, p.m2, p.rod1, p.rod2
            ));
        }
        let factor = mass / masses.iter().sum::<f64>();
        Ok(Weighed {
            mass,
            factor,
            p: factor * p.inertia().p,
        })
    }

    /// `p` on the weighed scale: every mass and damping times the factor (the same motion).
    pub fn scaled(&self, p: &Params) -> Params {
        let mut out = *p;
        for m in [&mut out.m1, &mut out.m2, &mut out.rod1, &mut out.rod2] {
            *m *= self.factor;
        }
        out.losses.joint1 *= self.factor;
        out.losses.joint2 *= self.factor;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bobs on uniform rods are their own equivalent: scaled to their own total they are
    /// themselves, P included, to rounding.
    #[test]
    fn a_pendulum_of_bobs_and_rods_is_scaled_to_itself() {
        let truth = Params {
            m1: 0.01,
            m2: 0.002,
            rod1: 0.2,
            rod2: 0.03,
            l1: 0.1,
            l2: 0.08,
            ..Params::default()
        };
        let k = truth.inertia();
        // The 1 kg scale of the same moments, as a fit finds them.
        let unit = truth.g * truth.l1;
        let one_kg = Params::from_moments(
            [k.a / k.p * unit, k.b / k.p * unit, k.c / k.p * unit, unit],
            (truth.l1, truth.l2, truth.g),
            Default::default(),
        );
        let w = Weighed::of(&one_kg, 0.242).unwrap();
        let back = w.scaled(&one_kg);
        for (got, want) in [
            (back.m1, truth.m1),
            (back.m2, truth.m2),
            (back.rod1, truth.rod1),
            (back.rod2, truth.rod2),
            (w.p, k.p),
        ] {
            // Rounding only: a few operations in f64.
            assert!((got / want - 1.0).abs() < 1e-12, "{got} against {want}");
        }
    }

    /// A negative mass in the equivalent is no total to match: refused in words.
    #[test]
    fn an_equivalent_with_a_negative_mass_sets_no_scale() {
        let p = Params {
            m1: 0.5,
            m2: -0.1,
            rod1: 0.3,
            rod2: 0.4,
            ..Params::default()
        };
        let why = Weighed::of(&p, 1.0).unwrap_err();
        assert!(why.contains("stay over P"), "{why}");
    }
}
