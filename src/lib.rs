//! chaoscope explores chaos in the double pendulum by integrating one pendulum per pixel of an
//! initial-condition grid, on the GPU (WGSL compute shaders through wgpu, f32) or on the CPU
//! (an f64 reference that solves the mass-matrix system with nalgebra). Both paths return the
//! same [`Field`], which [`render`] turns into PNG images and raw `.npy` data.
//!
//! Layers, one way: [`cli`] (flags, the only place that prints) -> a job of [`app`]
//! (validated specs of [`spec`]) -> [`engine`] (the one place that picks the CPU or the GPU)
//! -> [`Field`] -> [`render`] -> files. The library is usable without the command line:
//!
//! ```
//! use chaoscope::{engine::{Backend, Engine}, model::Params, monitor::Monitor};
//! use chaoscope::spec::{FlipSpec, Grid, Stepping};
//! let spec = FlipSpec::new(Params::default(), Grid::square(8), Stepping { dt: 0.01, t_max: 2.0 });
//! spec.validate().unwrap();
//! let map = Engine::new(Backend::Cpu).unwrap().map(&spec, &Monitor::hidden()).unwrap();
//! // The centre of the grid hangs nearly straight down: it can never flip.
//! assert!(map.get(4, 4).is_infinite());
//! ```

pub mod app;
pub mod boundary;
pub mod cli;
pub mod cpu;
pub mod engine;
pub mod error;
pub mod field;
pub mod fit;
pub mod forecast;
pub mod gpu;
pub mod input;
pub mod measure;
pub mod model;
pub mod monitor;
pub mod params;
pub mod plan;
pub mod quantity;
pub mod render;
pub mod serve;
pub mod spec;
pub mod stats;
pub mod tableau;
pub mod track;
pub mod verdict;
pub mod video;
pub mod web;

pub use error::{Error, Result};
pub use field::Field;
