//! From fields to files: colour maps, PNG with the run's specification, raw .npy; every file
//! written to a temporary name first and renamed, so no half-written output is left behind.

mod colormap;
mod files;

pub use colormap::{FlipColors, flip_colors, ftle_colors, ftle_range};
pub use files::{write_atomic, write_npy, write_png};
