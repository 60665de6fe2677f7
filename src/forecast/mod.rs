//! The forecast room: from a track file and a model (`crate::fit`) to how long the model
//! follows the pendulum. An ensemble drawn from a window fit's uncertainty (ensemble.rs: its
//! members, bands and headline horizon; scores.rs: how it did on the rows after its window), the model's own error measured on held-out
//! windows (model_error.rs), a calibration that carries both to other recordings
//! (calibration.rs: the data and its TOML; calibrate.rs: how `fit` makes it), one track's fit and forecast (outcome.rs), twin
//! experiments (twin.rs), and the pictures: the bands (plot.rs) and the forecast drawn on the
//! film (overlay.rs). It imports `fit` and `track`; neither imports it.

pub mod calibrate;
pub mod calibration;
pub mod ensemble;
pub mod files;
pub mod members;
pub mod model_error;
pub mod outcome;
pub mod overlay;
pub mod plot;
pub mod scores;
pub mod twin;

pub use ensemble::*;
pub use scores::*;
