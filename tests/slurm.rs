//! A real single-node Slurm (tests/slurm/cluster.sh: munged, slurmctld, slurmd started by
//! the test and stopped by their PIDs) runs examples/slurm/flip_array.sbatch as a 4-task
//! array into one Zarr store; the store equals a single process's map value for value.
//! scripts/test installs Slurm; without it the test says so, and fails under CI=true.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use chaoscope::render::store::MapStore;

/// The cluster, stopped when dropped (also when an assertion fails).
struct Cluster {
    work: PathBuf,
    script: PathBuf,
}

impl Cluster {
    fn start(work: &Path) -> Cluster {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/slurm/cluster.sh");
        let cluster = Cluster {
            work: work.to_path_buf(),
            script,
        };
        let out = Command::new(&cluster.script)
            .arg("start")
            .arg(work)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "slurm did not start: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        cluster
    }

    fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", self.work.join("slurm.conf"));
        c
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        Command::new(&self.script)
            .arg("stop")
            .arg(&self.work)
            .status()
            .ok();
    }
}

fn has_slurm() -> bool {
    ["slurmctld", "slurmd", "sbatch", "munged"].iter().all(|p| {
        Command::new("sh")
            .args(["-c", &format!("command -v {p}")])
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

#[test]
fn a_slurm_array_fills_one_store() {
    if !has_slurm() {
        assert_ne!(
            std::env::var("CI").as_deref(),
            Ok("true"),
            "Slurm is not installed (scripts/test installs it)"
        );
        eprintln!("SKIPPED: Slurm is not installed (scripts/test installs it)");
        return;
    }
    let backend = if common::gpu().is_some() {
        "gpu"
    } else {
        return;
    };
    // On an exec mount (the spool holds the batch scripts), not /tmp.
    let dir = tempfile::tempdir_in(env!("CARGO_TARGET_TMPDIR")).unwrap();
    let work = dir.path().join("slurm");
    let map = "--size 2048 --t-max 10";
    // The single process first, for the values and the time.
    let npy = dir.path().join("single.npy");
    let started = Instant::now();
    common::chaoscope()
        .arg("flip")
        .args(map.split(' '))
        .args(["--backend", backend, "--output"])
        .arg(dir.path().join("single.png"))
        .arg("--data")
        .arg(&npy)
        .assert()
        .success();
    let single = started.elapsed();
    let cluster = Cluster::start(&work);
    let store = work.join("map.zarr");
    let sbatch = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slurm/flip_array.sbatch");
    let started = Instant::now();
    let out = cluster
        .command("sbatch")
        .arg("--parsable")
        .arg("--chdir")
        .arg(&work)
        .arg(&sbatch)
        .env("MAP_ARGS", map)
        .env("STORE", &store)
        .env("CHAOSCOPE", assert_cmd::cargo::cargo_bin("chaoscope"))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "sbatch: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let job = String::from_utf8_lossy(&out.stdout).trim().to_string();
    // squeue every 0.2 s (sbatch --wait polls ever more slowly).
    loop {
        let queued = cluster
            .command("squeue")
            .args(["-h", "-j", &job])
            .output()
            .unwrap();
        if String::from_utf8_lossy(&queued.stdout).trim().is_empty() {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(300),
            "the array did not finish"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    let array = started.elapsed();
    let shown = cluster
        .command("scontrol")
        .args(["-o", "show", "job", &job])
        .output()
        .unwrap();
    let shown = String::from_utf8_lossy(&shown.stdout).to_string();
    let tasks: Vec<&str> = shown.lines().collect();
    assert_eq!(tasks.len(), 4, "{shown}");
    for t in &tasks {
        assert!(
            t.contains("JobState=COMPLETED") && t.contains("ExitCode=0:0"),
            "{t}\nlogs: {:?}",
            std::fs::read_dir(&work).map(|d| d.count())
        );
    }
    let s = MapStore::open(&store).unwrap();
    assert!(s.missing().unwrap().is_empty());
    let bits: Vec<u32> = s
        .read_rows(0, s.height)
        .unwrap()
        .iter()
        .map(|v| v.to_bits())
        .collect();
    let expected: Vec<u32> = common::read_npy(&npy)
        .1
        .iter()
        .map(|v| v.to_bits())
        .collect();
    assert!(
        bits == expected,
        "the array's store differs from the single process's map"
    );
    // A figure for the record, not a timed assertion (bench and the closing notes measure).
    eprintln!(
        "single process {:.2} s, 4-task Slurm array {:.2} s (submission to the last task's end)",
        single.as_secs_f64(),
        array.as_secs_f64()
    );
    drop(cluster);
}
