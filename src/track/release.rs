//! Where free motion begins. A film made as the guide recommends starts with the pendulum
//! hanging still, then lifted by hand and let go: only what follows the release is the
//! pendulum's own motion, which `fit` and `forecast` model.

use super::geometry::Named;

/// A step (px a frame) below which a marker stands still (the centroid's noise is some
/// 0.05 px; a pendulum let go from rest moves g sin(theta) dt^2 / 2 in its first frame,
/// over a pixel at 60 frames a second on a 300 px arm).
const STILL: f64 = 0.5;

/// Still steps in a row that make a hold: a tenth of a second at 30 frames a second (a
/// swing's turning point is still for a step at most, where a hand holds the pendulum for
/// a moment before it lets go).
const HOLD: usize = 3;

/// How soon (s) after a hold the pendulum must swing fast for the hold to be a release.
const SOON: f64 = 0.5;

/// The release: the end of the last hold (both markers still for [`HOLD`] steps or more:
/// hanging at rest, or held up by hand) that is followed within [`SOON`] by a fast swing
/// (a step over half the film's 90th percentile); the last still frame's time (s). The
/// last such hold, since a hand's lift between the rest and the release may be as fast as
/// a swing; a pendulum coming to rest at the film's end swings after none. None where the
/// film shows no such hold: it swings from the first frame, or was thrown.
pub fn release(named: &[(Named, Named)], times: &[f64]) -> Option<f64> {
    let place = |m: Named| m.map(|b| (b.x, b.y));
    // Each frame's largest step to the next, of the masses seen in both.
    let steps: Vec<Option<f64>> = named
        .windows(2)
        .map(|w| {
            [(w[0].0, w[1].0), (w[0].1, w[1].1)]
                .into_iter()
                .filter_map(|(a, b)| {
                    let (a, b) = (place(a)?, place(b)?);
                    Some((a.0 - b.0).hypot(a.1 - b.1))
                })
                .reduce(f64::max)
        })
        .collect();
    let mut known: Vec<f64> = steps.iter().flatten().copied().collect();
    if known.len() < 10 {
        return None;
    }
    let k = known.len() * 9 / 10;
    let fast = 0.5 * *known.select_nth_unstable_by(k, f64::total_cmp).1;
    if fast <= 2.0 * STILL {
        return None;
    }
    // A hold is both markers still: a step with one of them unseen (a fast-whirling lower
    // arm blurred away) says nothing of it, whatever the other did at its turning point.
    let both_seen: Vec<bool> = named
        .windows(2)
        .map(|w| [w[0].0, w[0].1, w[1].0, w[1].1].iter().all(Option::is_some))
        .collect();
    let mut release = None;
    let mut run = 0;
    for (i, step) in steps.iter().enumerate() {
        if both_seen[i] && step.is_some_and(|s| s <= STILL) {
            run += 1;
            continue;
        }
        // Step i is the first after a hold of `run` still steps: frame i its last still one.
        if run >= HOLD {
            let soon = steps[i..]
                .iter()
                .zip(&times[i..])
                .take_while(|(_, t)| **t <= times[i] + SOON)
                .any(|(s, _)| s.is_some_and(|s| s > fast));
            if soon {
                release = Some(times[i]);
            }
        }
        run = 0;
    }
    release
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::detect::{Blob, Role};

    /// Frames at 60 a second: the pendulum swinging fast, then for `still` frames the upper
    /// marker at a turning point while the lower one is seen every other frame (far apart:
    /// a fast whirl, blurred away in between), then swinging fast again.
    fn whirl(still: usize, lower_seen: bool) -> (Vec<Named>, Vec<Named>) {
        let mut upper = Vec::new();
        let mut lower = Vec::new();
        for k in 0..60 {
            let held = (20..20 + still).contains(&k);
            let x = if held {
                100.0
            } else {
                100.0 + 20.0 * (k as f64).sin()
            };
            upper.push(Some(Blob::round(x, 50.0, Role::Either)));
            let seen = !held || lower_seen || k % 2 == 0;
            let y = if held && lower_seen {
                150.0
            } else {
                150.0 + 30.0 * (k as f64).cos()
            };
            lower.push(seen.then(|| Blob::round(200.0, y, Role::Either)));
        }
        (upper, lower)
    }

    /// One marker still at its turning point while the other is out of sight is no hold:
    /// no release is found in the middle of a swing; both still for as long is one.
    #[test]
    fn a_hold_needs_both_markers_still() {
        let times: Vec<f64> = (0..60).map(|k| k as f64 / 60.0).collect();
        let (upper, lower) = whirl(6, false);
        let named: Vec<(Named, Named)> = upper.into_iter().zip(lower).collect();
        assert_eq!(release(&named, &times), None);
        let (upper, lower) = whirl(6, true);
        let named: Vec<(Named, Named)> = upper.into_iter().zip(lower).collect();
        assert_eq!(release(&named, &times), Some(times[25]));
    }
}
