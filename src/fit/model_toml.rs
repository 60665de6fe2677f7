//! model.toml: a fitted pendulum as the parameter file `--params` reads back
//! (src/params.rs).

use super::pendulum::ModelSource;
use super::weighed::Weighed;
use crate::model::Params;

/// The model `p` as a parameter file that `--params` reads back (src/params.rs), headed by
/// `heading` (a comment: where it came from). A model found from the motion is written by
/// its moments over P (table `[moments]`: the masses' scale is not in the motion); a model
/// given by masses, by them, its losses included. A weighed model (`p` on its scale) also
/// states its P, so that the file reads back in kilograms.
pub fn model_file(
    p: &Params,
    source: &ModelSource,
    heading: &str,
    weighed: Option<&Weighed>,
) -> String {
    let mut out = String::new();
    for line in heading.lines() {
        out.push_str(&format!("# {line}\n"));
    }
    let l = &p.losses;
    match source {
        ModelSource::Identified => {
            let k = p.inertia();
            out.push_str(&format!(
                "l1 = {}  # the upper marker's distance from the pivot (m): the middle joint\n\
                 l2 = {}  # the lower marker's distance from the middle joint (m)\n\
                 g = {}  # the gravity under which the model follows the data's metres and seconds (m/s^2)\n\
                 \n\
                 [moments]  # over P, the upper arm's gravity moment\n\
                 a = {}  # A/P (s^2): the upper arm's inertia about the pivot, the lower arm's mass at the joint\n\
                 b = {}  # B/P (s^2): the lower arm's inertia about the middle joint\n\
                 c = {}  # C/P (s^2): the arms' coupling\n\
                 k1 = {}  # the pivot's damping over P (s)\n\
                 k2 = {}  # the middle joint's damping over P (s)\n",
                p.l1,
                p.l2,
                p.g,
                k.a / k.p,
                k.b / k.p,
                k.c / k.p,
                l.joint1 / k.p,
                l.joint2 / k.p
            ));
            if let Some(w) = weighed {
                out.push_str(&format!(
                    "p = {}  # P (J): the upper arm's gravity moment, from the weighed {} kg\n",
                    k.p, w.mass
                ));
            }
        }
        ModelSource::Given => {
            out.push_str(&format!(
                "m1 = {}\nm2 = {}\nl1 = {}\nl2 = {}\ng = {}\nrod_mass = [{}, {}]\njoint_damping = [{}, {}]  # N m s\n",
                p.m1, p.m2, p.l1, p.l2, p.g, p.rod1, p.rod2, l.joint1, l.joint2
            ));
            if l.has_bearings() {
                out.push_str(&format!(
                    "bearing_friction = {}\nbearing_radius = {}\n",
                    l.bearing, l.bearing_radius
                ));
            }
            if l.has_drag() {
                out.push_str(&format!(
                    "\n[air_drag]\nrho = {}\ncw = {}\nbob_area = [{}, {}]\nrod_area = [{}, {}]\n",
                    l.rho, l.cw, l.bob_area1, l.bob_area2, l.rod_area1, l.rod_area2
                ));
            }
        }
    }
    out
}
