//! How much memory this process may still take, and the check of a need against it.

use crate::error::{Error, Result};

/// Memory this process can still take (bytes): the least of what the system has available
/// (MemAvailable), what its cgroup allows beyond its use (v2 memory.max, v1
/// memory.limit_in_bytes), and what its address-space limit (RLIMIT_AS, as `ulimit -v`
/// sets) leaves beyond its current size; 16 GiB where none can be read.
///
/// A reading is kept for [`MEMORY_FRESH`]: a run that checks thousands of maps in a row (a
/// zoom's 100,000 frames, planned before any work) reads the seven files once, not once a map.
pub fn available_memory() -> u64 {
    use std::sync::Mutex;
    use std::time::Instant;
    static LAST: Mutex<Option<(Instant, u64)>> = Mutex::new(None);
    let mut last = LAST.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((at, bytes)) = *last
        && at.elapsed() < MEMORY_FRESH
    {
        return bytes;
    }
    let bytes = read_available_memory();
    *last = Some((Instant::now(), bytes));
    bytes
}

/// How long a reading of [`available_memory`] stands: short against how fast a machine's
/// free memory changes under a run's checks, long against a loop of them.
const MEMORY_FRESH: std::time::Duration = std::time::Duration::from_millis(500);

fn read_available_memory() -> u64 {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let number = |s: Option<String>| s.and_then(|s| s.trim().parse::<u64>().ok());
    let field_kb = |text: &Option<String>, key: &str| {
        text.as_ref().and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
                .map(|kb| kb * 1024)
        })
    };
    let mut limits = vec![field_kb(&read("/proc/meminfo"), "MemAvailable:")];
    // The cgroup: its own directory (v2 "0::/path", v1 "N:memory:/path"), or the mounted
    // root when the container shows its cgroup there.
    let cgroup = read("/proc/self/cgroup").unwrap_or_default();
    let own = |prefix: &str| {
        cgroup
            .lines()
            .find_map(|l| l.split_once(prefix).map(|(_, p)| p.to_string()))
            .unwrap_or_default()
    };
    for (dir, max, used) in [
        (
            format!("/sys/fs/cgroup{}", own("::")),
            "memory.max",
            "memory.current",
        ),
        ("/sys/fs/cgroup".to_string(), "memory.max", "memory.current"),
        (
            format!("/sys/fs/cgroup/memory{}", own(":memory:")),
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
        ),
        (
            "/sys/fs/cgroup/memory".to_string(),
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
        ),
    ] {
        // "max" (v2) or a huge number (v1) means no limit: it does not parse or never binds.
        if let (Some(max), Some(used)) = (
            number(read(&format!("{dir}/{max}"))),
            number(read(&format!("{dir}/{used}"))),
        ) {
            limits.push(Some(max.saturating_sub(used)));
        }
    }
    let address_space = read("/proc/self/limits").and_then(|s| {
        s.lines()
            .find(|l| l.starts_with("Max address space"))
            .and_then(|l| l.split_whitespace().nth(3))
            .and_then(|soft| soft.parse::<u64>().ok())
    });
    if let Some(limit) = address_space {
        let size = field_kb(&read("/proc/self/status"), "VmSize:").unwrap_or(0);
        limits.push(Some(limit.saturating_sub(size)));
    }
    limits.into_iter().flatten().min().unwrap_or(16 << 30)
}

/// `need` bytes for `what` fit in [`available_memory`], else an error naming `field`.
pub fn check_memory(field: &'static str, need: u64, what: &str) -> Result<()> {
    let have = available_memory();
    if need > have {
        return Err(Error::invalid(
            field,
            format!(
                "{what} needs about {} MiB but only {} MiB of memory are available to this process",
                need >> 20,
                have >> 20
            ),
        ));
    }
    Ok(())
}
