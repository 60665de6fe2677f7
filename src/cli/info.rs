//! `chaoscope info`: the adapters wgpu sees, the one a run would take, its limits.

use crate::error::Result;
use crate::gpu;

pub fn run() -> Result<()> {
    let adapters = gpu::list_adapters();
    println!("adapters found: {}", adapters.len());
    for a in &adapters {
        let i = a.get_info();
        println!(
            "  - {} ({:?}, {:?}, driver {} {})",
            i.name, i.backend, i.device_type, i.driver, i.driver_info
        );
    }
    match gpu::GpuContext::new() {
        Ok(ctx) => {
            println!("chosen: {}", ctx.adapter_name());
            let l = &ctx.limits;
            println!(
                "  max_storage_buffer_binding_size: {} MiB",
                l.max_storage_buffer_binding_size >> 20
            );
            println!("  max_buffer_size: {} MiB", l.max_buffer_size >> 20);
            println!(
                "  max_compute_workgroups_per_dimension: {}",
                l.max_compute_workgroups_per_dimension
            );
            println!(
                "  max_compute_invocations_per_workgroup: {}",
                l.max_compute_invocations_per_workgroup
            );
            let f = ctx.adapter_features;
            println!(
                "  adapter supports SHADER_F64: {}",
                f.contains(wgpu::Features::SHADER_F64)
            );
            println!("  adapter features: {f:?}");
        }
        Err(e) => println!("chosen: none ({e}); maps run on the CPU"),
    }
    Ok(())
}
