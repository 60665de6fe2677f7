//! The GPU path: WGSL compute shaders in f32, one invocation per pendulum.

mod context;
mod flip_time;
pub mod layout;
mod lyapunov;
mod pipeline;
mod trajectory;

pub use context::{GpuContext, list_adapters};
pub use flip_time::{FlipTimeKernel, STEPS_PER_DISPATCH};
pub use lyapunov::{LyapunovKernel, jacobians};
pub use trajectory::{strided_trajectories, trajectories, trajectory};
