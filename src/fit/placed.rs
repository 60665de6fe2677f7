//! Where the markers sit on the arms and where gravity's down lies in the picture, as the
//! learned rows (or a calibration) show it, and the rows with both taken out: the middle joint
//! where the upper marker is off it ([`super::joint`]), the markers' small offsets from the
//! axes, the picture's roll ([`super::level`]).

use super::joint::{Joint, Offsets, joint_off_marker, marker_offsets};
use super::level::{Roll, levelled, roll};
use super::{TrackedRow, angles, fit_pivot};
use crate::error::Result;

/// `frames` with the upper marker moved out to the middle joint where it is not on it
/// ([`super::joint`]), the markers' small offsets from the axes taken out and the picture
/// levelled ([`super::level`]), all as the first `learn` rows show them (rows too few to
/// place the pivot show nothing: the markers are taken to be on the axes, the picture level).
/// A calibration's offsets (m) and roll (`theirs`) stand where the rows show them less
/// precisely.
pub fn on_axes(
    frames: &[TrackedRow],
    learn: usize,
    theirs: &Placed,
    unit: f64,
) -> Result<(Vec<TrackedRow>, Placed)> {
    let Ok(pivot) = fit_pivot(&frames[..learn]) else {
        return Ok((frames.to_vec(), Placed::default()));
    };
    let pivot = (pivot.x, pivot.y);
    let (mut frames, joint) = match joint_off_marker(&frames[..learn], pivot) {
        Some(j) => (j.moved(frames, pivot), Some(j)),
        None => (frames.to_vec(), None),
    };
    // The calibration's, in the frames' units (`unit` of them a metre), where it knows more.
    let spread = |o: &Offsets| o.errors.iter().sum::<f64>();
    let scaled = theirs
        .offsets
        .filter(|_| unit.is_finite())
        .map(|o| o.scaled(unit));
    let offsets = match (marker_offsets(&frames[..learn], pivot), scaled) {
        (Some(own), Some(k)) if spread(&own) <= spread(&k) => Some(own),
        (_, Some(k)) => Some(k),
        (own, None) => own,
    }
    .filter(Offsets::any);
    if let Some(o) = &offsets {
        frames = o.moved(&frames, pivot);
    }
    let t: Vec<f64> = frames[..learn].iter().map(|f| f.t).collect();
    let roll = match (roll(&t, &angles(&frames[..learn], pivot)), theirs.roll) {
        (Some(own), Some(k)) if own.error <= k.error => Some(own),
        (_, Some(k)) => Some(k),
        (own, None) => own,
    };
    if let Some(r) = roll.filter(|r| r.applied != 0.0) {
        frames = levelled(&frames, pivot, r.applied);
    }
    Ok((
        frames,
        Placed {
            joint,
            offsets,
            roll,
        },
    ))
}

/// Where the learned rows (or a calibration) put the markers against the arms and gravity's
/// down.
#[derive(Clone, Copy, Debug, Default)]
pub struct Placed {
    /// The middle joint, where the upper marker is not on it (m).
    pub joint: Option<Joint>,
    /// The markers' small offsets from the arms' axes (m).
    pub offsets: Option<Offsets>,
    /// The picture's roll against gravity.
    pub roll: Option<Roll>,
}
