//! `chaoscope info`: the adapters wgpu sees, the one a run would take, its backend, limits
//! and features.

use serde_json::json;

use crate::error::Result;
use crate::gpu;

pub fn run(as_json: bool) -> Result<serde_json::Value> {
    let adapters: Vec<_> = gpu::list_adapters()
        .iter()
        .map(|a| {
            let i = a.get_info();
            json!({
                "name": i.name, "backend": format!("{:?}", i.backend),
                "device_type": format!("{:?}", i.device_type),
                "driver": i.driver, "driver_info": i.driver_info,
            })
        })
        .collect();
    let chosen = gpu::GpuContext::new().map(|ctx| {
        let l = &ctx.limits;
        let f = ctx.adapter_features;
        json!({
            "adapter": ctx.adapter_name(),
            "backend": format!("{:?}", ctx.info.backend),
            "max_storage_buffer_binding_size": l.max_storage_buffer_binding_size,
            "max_buffer_size": l.max_buffer_size,
            "max_compute_workgroups_per_dimension": l.max_compute_workgroups_per_dimension,
            "max_compute_invocations_per_workgroup": l.max_compute_invocations_per_workgroup,
            "shader_f64": f.contains(wgpu::Features::SHADER_F64),
            "features": format!("{f:?}"),
        })
    });
    if !as_json {
        println!("adapters found: {}", adapters.len());
        for a in &adapters {
            println!(
                "  - {} ({}, {}, driver {} {})",
                a["name"].as_str().unwrap_or(""),
                a["backend"].as_str().unwrap_or(""),
                a["device_type"].as_str().unwrap_or(""),
                a["driver"].as_str().unwrap_or(""),
                a["driver_info"].as_str().unwrap_or("")
            );
        }
        match &chosen {
            Ok(c) => {
                println!(
                    "chosen: {} (backend {})",
                    c["adapter"].as_str().unwrap_or(""),
                    c["backend"].as_str().unwrap_or("")
                );
                println!(
                    "  max_storage_buffer_binding_size: {} MiB",
                    c["max_storage_buffer_binding_size"].as_u64().unwrap_or(0) >> 20
                );
                println!(
                    "  max_buffer_size: {} MiB",
                    c["max_buffer_size"].as_u64().unwrap_or(0) >> 20
                );
                for key in [
                    "max_compute_workgroups_per_dimension",
                    "max_compute_invocations_per_workgroup",
                ] {
                    println!("  {key}: {}", c[key]);
                }
                println!("  adapter supports SHADER_F64: {}", c["shader_f64"]);
                println!(
                    "  adapter features: {}",
                    c["features"].as_str().unwrap_or("")
                );
            }
            Err(e) => println!("chosen: none ({e}); maps run on the CPU"),
        }
    }
    Ok(json!({
        "adapters": adapters,
        "chosen": chosen.ok(),
    }))
}
