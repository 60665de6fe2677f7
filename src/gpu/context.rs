//! The adapter and device. Kernels take a context; they never create one.

use std::sync::{Arc, Mutex};

use crate::error::{Error, Result};

pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// What the adapter could offer (the device requests SHADER_F64 of it when offered).
    pub adapter_features: wgpu::Features,
    /// Errors raised outside an error scope, kept so that a run fails instead of going on
    /// with garbage.
    uncaptured: Arc<Mutex<Option<String>>>,
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
}

impl GpuContext {
    /// The default adapter (honours `WGPU_BACKEND` and `WGPU_ADAPTER_NAME`), with its own
    /// limits so that large grids need fewer tiles.
    pub fn new() -> Result<Self> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<Self> {
        let instance = instance();
        // As wgpu::util::initialize_adapter_from_env_or_default, which panics when no adapter
        // has the name asked for: here that is no adapter, and `auto` falls back.
        let adapter = match std::env::var("WGPU_ADAPTER_NAME") {
            Ok(name) => {
                let name = name.to_lowercase();
                instance
                    .enumerate_adapters(wgpu::Backends::all())
                    .await
                    .into_iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&name))
                    .ok_or(Error::NoAdapter)?
            }
            Err(_) => instance
                .request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::from_env().unwrap_or_default(),
                    ..Default::default()
                })
                .await
                .map_err(|_| Error::NoAdapter)?,
        };
        let limits = adapter.limits();
        // f64 kernels run where the adapter offers f64; the f32 ones need nothing.
        let features = adapter.features() & wgpu::Features::SHADER_F64;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("chaoscope"),
                required_features: features,
                required_limits: limits.clone(),
                ..Default::default()
            })
            .await
            .map_err(|e| Error::Gpu(format!("request_device: {e}")))?;
        let uncaptured = Arc::new(Mutex::new(None));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = sink.lock().expect("error slot");
            slot.get_or_insert_with(|| e.to_string());
        }));
        Ok(GpuContext {
            device,
            queue,
            info: adapter.get_info(),
            limits,
            adapter_features: adapter.features(),
            uncaptured,
        })
    }

    /// Whether the device runs f64 kernels (`Features::SHADER_F64`).
    pub fn has_f64(&self) -> bool {
        self.device.features().contains(wgpu::Features::SHADER_F64)
    }

    /// One line naming the adapter, for notices and PNG metadata.
    pub fn adapter_name(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// Waits for all submitted work; fails on any error the device reported.
    pub fn wait(&self) -> Result<()> {
        loop {
            match self.device.poll(wgpu::PollType::wait_indefinitely()) {
                Ok(_) => break,
                // The GL backend caps a wait at about 2 s; just wait again.
                Err(wgpu::PollError::Timeout) => continue,
                Err(e) => return Err(Error::Gpu(format!("poll: {e}"))),
            }
        }
        self.take_error()
    }

    pub fn take_error(&self) -> Result<()> {
        match self.uncaptured.lock().expect("error slot").take() {
            Some(e) => Err(Error::Gpu(e)),
            None => Ok(()),
        }
    }

    /// Largest storage buffer a single binding may hold (bytes).
    pub fn max_binding(&self) -> u64 {
        self.limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size)
    }
}

/// Every adapter wgpu can see, for `chaoscope info`.
pub fn list_adapters() -> Vec<wgpu::Adapter> {
    pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()))
}

/// Reads back `len` bytes of `buffer` (which must allow COPY_SRC) through a staging buffer.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer, len: u64) -> Result<Vec<u8>> {
    read_buffer_with(ctx, buffer, len, <[u8]>::to_vec)
}

/// Reads back the first `len` bytes of `buffer` and hands them to `f` where they are mapped
/// (no copy of the bytes on the host).
pub fn read_buffer_with<T>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    len: u64,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: len,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, len);
    ctx.queue.submit([encoder.finish()]);
    map_read_with(ctx, &staging, f)
}

/// Reads back the first `count` f32 values of `buffer`.
pub fn read_f32s(ctx: &GpuContext, buffer: &wgpu::Buffer, count: u64) -> Result<Vec<f32>> {
    let bytes = read_buffer(ctx, buffer, count * 4)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// Maps a MAP_READ buffer and copies its bytes out.
pub fn map_read(ctx: &GpuContext, staging: &wgpu::Buffer) -> Result<Vec<u8>> {
    map_read_with(ctx, staging, <[u8]>::to_vec)
}

/// Maps a MAP_READ buffer and hands its bytes to `f`.
pub fn map_read_with<T>(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    f: impl FnOnce(&[u8]) -> T,
) -> Result<T> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv()
        .map_err(|e| Error::Gpu(format!("map: {e}")))?
        .map_err(|e| Error::Gpu(format!("map: {e}")))?;
    let out = f(&staging
        .get_mapped_range(..)
        .map_err(|e| Error::Gpu(format!("map range: {e}")))?);
    staging.unmap();
    Ok(out)
}
