//! Fitting the model to a camera's tracked positions, as the lab report did by hand: pivot
//! and arm lengths, angles, velocities and energies with error bars, the energy decay laws, and
//! the model's state and damping fitted to the positions. `app::fit` puts it together.

pub mod bridge;
mod correlation;
pub mod data;
pub mod identify;
pub mod joint;
pub mod level;
mod lsq;
mod model;
pub mod model_toml;
pub mod pendulum;
mod placed;
pub mod plots;
mod refine;
pub mod report;
pub mod verdict;
pub mod weighed;
pub mod window;

pub use data::{
    DecayFits, Energies, TrackedRow, angles, arm_lengths, energies, fit_decay, fit_pivot,
    grid_pivot, read_frames,
};
pub use lsq::{Fit, least_squares};
pub use model::{ModelFit, ModelFitSpec, fit_model, measured};
