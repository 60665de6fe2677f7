//! The GPU path: WGSL compute shaders in f32, one invocation per pendulum. Every kernel is
//! built once per context ([`Kernels`]) and its pipelines compiled on first use.

mod context;
mod flip_time;
pub mod layout;
mod lyapunov;
mod pipeline;
mod tiled;
mod trajectory;

use std::sync::OnceLock;

pub use context::{GpuContext, list_adapters, read_buffer};
pub use flip_time::FlipTimeKernel;
pub use lyapunov::{JacobianKernel, LyapunovKernel};
pub use tiled::STEPS_PER_DISPATCH;
pub use trajectory::TrajectoryKernel;

use crate::spec::{Method, Precision};

/// A context and its kernels, each built on first use and kept.
pub struct Kernels {
    pub ctx: GpuContext,
    flip: OnceLock<FlipTimeKernel>,
    flip64: OnceLock<FlipTimeKernel>,
    /// Tangent and twin, f32 and f64.
    lyapunov: [OnceLock<LyapunovKernel>; 4],
    trajectory: OnceLock<TrajectoryKernel>,
    trajectory64: OnceLock<TrajectoryKernel>,
    jacobian: OnceLock<JacobianKernel>,
}

impl Kernels {
    pub fn new(ctx: GpuContext) -> Self {
        Kernels {
            ctx,
            flip: OnceLock::new(),
            flip64: OnceLock::new(),
            lyapunov: Default::default(),
            trajectory: OnceLock::new(),
            trajectory64: OnceLock::new(),
            jacobian: OnceLock::new(),
        }
    }

    pub fn flip(&self) -> &FlipTimeKernel {
        self.flip.get_or_init(|| FlipTimeKernel::new(&self.ctx))
    }

    /// The f64 flip kernel (the context must have f64).
    pub fn flip64(&self) -> &FlipTimeKernel {
        self.flip64
            .get_or_init(|| FlipTimeKernel::with_precision(&self.ctx, Precision::F64))
    }

    /// The divergence kernel of `method` in `precision` (f64: the context must have it).
    pub fn lyapunov(&self, method: Method, precision: Precision) -> &LyapunovKernel {
        let slot = match method {
            Method::Tangent => 0,
            Method::Twin { .. } => 1,
        } + 2 * (precision == Precision::F64) as usize;
        self.lyapunov[slot]
            .get_or_init(|| LyapunovKernel::with_precision(&self.ctx, method, precision))
    }

    pub fn trajectory(&self) -> &TrajectoryKernel {
        self.trajectory
            .get_or_init(|| TrajectoryKernel::new(&self.ctx))
    }

    /// The f64 trajectory kernel (the context must have f64).
    pub fn trajectory64(&self) -> &TrajectoryKernel {
        self.trajectory64
            .get_or_init(|| TrajectoryKernel::with_precision(&self.ctx, Precision::F64))
    }

    pub fn jacobian(&self) -> &JacobianKernel {
        self.jacobian.get_or_init(|| JacobianKernel::new(&self.ctx))
    }
}
