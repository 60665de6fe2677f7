//! An ensemble: one pendulum run from many starts, each run perhaps with its own joint
//! damping, and what is kept of every run. Built with its defaults and changed by name, so
//! that a new setting touches one place.

use crate::model::{Params, State};

/// What an ensemble keeps of each run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Keep<'a> {
    /// The start and every n-th state (the steps a multiple of n).
    Every(u32),
    /// The bobs' positions (x1, y1, x2, y2) at these times (s from the start, ascending,
    /// within the run's steps).
    At(&'a [f64]),
}

/// Runs of `params` from each of `starts` over `steps` steps of `dt`. The precision of the
/// arithmetic is the lent engine's (made once per door for a backend and a precision).
#[derive(Clone, Copy, Debug)]
pub struct EnsembleSpec<'a> {
    pub params: Params,
    pub starts: &'a [State],
    /// Joint damping (N m s at the pivot and at the middle joint) of each run, one pair a
    /// start, in place of `params`' when given.
    pub damping: Option<&'a [(f64, f64)]>,
    /// Time step (s).
    pub dt: f64,
    pub steps: u32,
    pub keep: Keep<'a>,
}

impl<'a> EnsembleSpec<'a> {
    /// Every state of every run kept, all runs sharing `params`' damping.
    pub fn new(params: Params, starts: &'a [State], dt: f64, steps: u32) -> Self {
        EnsembleSpec {
            params,
            starts,
            damping: None,
            dt,
            steps,
            keep: Keep::Every(1),
        }
    }

    /// Keeping `keep` of each run.
    pub fn keeping(self, keep: Keep<'a>) -> Self {
        EnsembleSpec { keep, ..self }
    }

    /// Run i with joint damping `damping[i]` (one pair a start).
    pub fn damped(self, damping: &'a [(f64, f64)]) -> Self {
        assert_eq!(damping.len(), self.starts.len(), "one damping pair a start");
        EnsembleSpec {
            damping: Some(damping),
            ..self
        }
    }

    /// The runs `first..first + n` alone (their starts and damping).
    pub fn runs(&self, first: usize, n: usize) -> Self {
        EnsembleSpec {
            starts: &self.starts[first..first + n],
            damping: self.damping.map(|d| &d[first..first + n]),
            ..*self
        }
    }

    /// The parameters of run i (its own damping when the runs have their own).
    pub fn params_of(&self, i: usize) -> Params {
        let mut q = self.params;
        if let Some(d) = self.damping {
            (q.losses.joint1, q.losses.joint2) = d[i];
        }
        q
    }

    /// States (or sets of four f32 positions, as large) each run keeps.
    pub fn kept(&self) -> u64 {
        match self.keep {
            Keep::Every(stride) => (self.steps / stride.max(1) + 1) as u64,
            Keep::At(times) => times.len() as u64,
        }
    }

    /// The stride of a spec keeping every n-th state. Panics for a spec keeping positions:
    /// the caller's own spec says which it kept.
    pub fn stride(&self) -> u32 {
        match self.keep {
            Keep::Every(stride) => stride,
            Keep::At(_) => panic!("this ensemble keeps positions at given times, not states"),
        }
    }

    /// The times of a spec keeping positions (panics for one keeping states).
    pub fn times(&self) -> &'a [f64] {
        match self.keep {
            Keep::At(times) => times,
            Keep::Every(_) => panic!("this ensemble keeps states, not positions"),
        }
    }
}

/// A chunk of an ensemble's runs as the engine hands it on, in what the spec keeps.
#[derive(Debug)]
pub enum Chunk<'a> {
    /// Each run's kept states.
    States(Vec<Vec<State>>),
    /// Positions time-major: time j, coordinate c, run i of the chunk's n at (4 j + c) n + i.
    Positions(&'a [f32]),
}

impl Chunk<'_> {
    /// The runs of a spec keeping states (panics for positions: the caller's own spec says
    /// which it kept).
    pub fn into_states(self) -> Vec<Vec<State>> {
        match self {
            Chunk::States(runs) => runs,
            Chunk::Positions(_) => panic!("this ensemble keeps positions, not states"),
        }
    }

    /// The positions of a spec keeping them (panics for states).
    pub fn positions(&self) -> &[f32] {
        match self {
            Chunk::Positions(v) => v,
            Chunk::States(_) => panic!("this ensemble keeps states, not positions"),
        }
    }
}
