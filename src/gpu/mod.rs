//! The GPU path: WGSL compute shaders in f32, one invocation per pendulum. Every kernel is
//! built once per context ([`Kernels`]) and its pipelines compiled on first use.

mod context;
mod flip_time;
mod indicators;
pub mod layout;
mod lyapunov;
mod pipeline;
mod positions;
pub mod shaders;
mod tiled;
mod trajectory;

use std::sync::OnceLock;

pub use context::{GpuContext, list_adapters, read_buffer};
pub use flip_time::FlipTimeKernel;
pub use indicators::{IndicatorKernel, LEFT_BELOW};
pub use lyapunov::{JacobianKernel, LyapunovKernel, STALLED_BELOW, STEP_COST as TANGENT_STEP_COST};
pub use positions::PositionsKernel;
pub use tiled::{MIN_STEPS, STEPS_PER_DISPATCH, STEPS_PER_INVOCATION};
pub use trajectory::TrajectoryKernel;

use crate::spec::{Method, Precision};

/// A context and its kernels, each built on first use and kept: the kernels' table, one
/// slot a kernel and precision.
pub struct Kernels {
    pub ctx: GpuContext,
    /// f32 and f64.
    flip: [OnceLock<FlipTimeKernel>; 2],
    /// Tangent and twin, f32 and f64.
    lyapunov: [OnceLock<LyapunovKernel>; 4],
    /// f32 and f64.
    indicators: [OnceLock<IndicatorKernel>; 2],
    /// f32 and f64.
    trajectory: [OnceLock<TrajectoryKernel>; 2],
    /// f32 and f64.
    positions: [OnceLock<PositionsKernel>; 2],
    jacobian: OnceLock<JacobianKernel>,
}

impl Kernels {
    pub fn new(ctx: GpuContext) -> Self {
        Kernels {
            ctx,
            flip: Default::default(),
            lyapunov: Default::default(),
            indicators: Default::default(),
            trajectory: Default::default(),
            positions: Default::default(),
            jacobian: OnceLock::new(),
        }
    }

    /// The flip kernel in `precision` (f64: the context must have it).
    pub fn flip(&self, precision: Precision) -> &FlipTimeKernel {
        self.flip[precision as usize]
            .get_or_init(|| FlipTimeKernel::with_precision(&self.ctx, precision))
    }

    /// The divergence kernel of `method` in `precision` (f64: the context must have it).
    pub fn lyapunov(&self, method: Method, precision: Precision) -> &LyapunovKernel {
        let slot = match method {
            Method::Tangent => 0,
            Method::Twin { .. } => 1,
        } + 2 * precision as usize;
        self.lyapunov[slot]
            .get_or_init(|| LyapunovKernel::with_precision(&self.ctx, method, precision))
    }

    /// The indicators' kernel in `precision` (f64: the context must have it).
    pub fn indicators(&self, precision: Precision) -> &IndicatorKernel {
        self.indicators[precision as usize]
            .get_or_init(|| IndicatorKernel::with_precision(&self.ctx, precision))
    }

    /// The trajectory kernel in `precision` (f64: the context must have it).
    pub fn trajectory(&self, precision: Precision) -> &TrajectoryKernel {
        self.trajectory[precision as usize]
            .get_or_init(|| TrajectoryKernel::with_precision(&self.ctx, precision))
    }

    /// The ensembles' positions kernel in `precision` (f64: the context must have it).
    pub fn positions(&self, precision: Precision) -> &PositionsKernel {
        self.positions[precision as usize]
            .get_or_init(|| PositionsKernel::with_precision(&self.ctx, precision))
    }

    pub fn jacobian(&self) -> &JacobianKernel {
        self.jacobian.get_or_init(|| JacobianKernel::new(&self.ctx))
    }
}
