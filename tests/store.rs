//! Zarr stores of maps (`flip --data MAP.zarr`, `--tile I/N`, `status`, `render`): values
//! equal the .npy of the same command bit for bit however the map is split, a store is only
//! ever missing whole chunks (never holds a corrupt one), and what is missing is found and
//! filled again.

mod common;

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use chaoscope::render::store::MapStore;
use common::{argv, chaoscope, png_text, read_npy};

fn backend() -> &'static str {
    if common::gpu().is_some() {
        "gpu"
    } else {
        "cpu"
    }
}

/// A 1024 x 1024 map: chunks of 256 rows, mirrored in pairs (two units of work).
const MAP: [&str; 4] = ["--size", "1024", "--t-max", "4"];

fn flip(args: &[&str], extra: &[&str]) -> assert_cmd::assert::Assert {
    chaoscope()
        .arg("flip")
        .args(args)
        .args(["--backend", backend()])
        .args(extra)
        .assert()
}

/// Every value of the store's map, bit for bit.
fn store_bits(path: &Path) -> Vec<u32> {
    let s = MapStore::open(path).unwrap();
    s.read_rows(0, s.height)
        .unwrap()
        .iter()
        .map(|v| v.to_bits())
        .collect()
}

/// The map of `map`'s flags as .npy at `npy` (and its PNG beside it).
fn write_npy(map: &[&str], npy: &Path) {
    chaoscope()
        .arg("flip")
        .args(map)
        .args(["--backend", backend(), "--output"])
        .arg(npy.with_extension("png"))
        .arg("--data")
        .arg(npy)
        .assert()
        .success();
}

fn npy_bits(path: &Path) -> Vec<u32> {
    read_npy(path).1.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn stores_equal_the_npy_whole_or_in_tiles_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let npy = d("map.npy");
    write_npy(&MAP, &npy);
    let whole = d("whole.zarr");
    flip(&MAP, &["--data", whole.to_str().unwrap()]).success();
    assert_eq!(store_bits(&whole), npy_bits(&npy), "one process");
    // Three tasks (one of them has nothing to do: two units of work).
    let tiled = d("tiled.zarr");
    for i in 0..3 {
        let tile = format!("{i}/3");
        flip(&MAP, &["--data", tiled.to_str().unwrap(), "--tile", &tile]).success();
    }
    assert_eq!(store_bits(&tiled), npy_bits(&npy), "three tasks");
    // A chunk deleted by hand: status names it and the task that fills it; a re-run of
    // that task fills it (and only what is missing).
    std::fs::remove_file(tiled.join("map/c/3/0")).unwrap();
    let out = chaoscope()
        .args(["status", tiled.to_str().unwrap()])
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).unwrap();
    assert!(
        text.contains("3 of 4 chunks")
            && text.contains("768..1024")
            && text.contains("--tile I/3 for I in 0"),
        "{text}"
    );
    flip(&MAP, &["--data", tiled.to_str().unwrap(), "--tile", "0/3"]).success();
    assert_eq!(store_bits(&tiled), npy_bits(&npy), "after the re-run");
    chaoscope()
        .args(["status", tiled.to_str().unwrap()])
        .assert()
        .success()
        .stdout(predicates::str::contains("complete"));
    // The picture from the store is the flip command's picture, pixel for pixel, and says
    // which command makes the map.
    let png = d("from-store.png");
    chaoscope()
        .args(["render", tiled.to_str().unwrap(), "--output"])
        .arg(&png)
        .assert()
        .success();
    let a = chaoscope::render::read_png(&png).unwrap();
    let b = chaoscope::render::read_png(&d("map.png")).unwrap();
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert!(a.rgb == b.rgb, "render's pixels differ from flip's");
    assert!(png_text(&png, "chaoscope:command").starts_with("chaoscope flip --size 1024x1024"));
    // Downsampled: every 4th pixel each way.
    let small = d("small.png");
    chaoscope()
        .args([
            "render",
            tiled.to_str().unwrap(),
            "--max-size",
            "256",
            "--output",
        ])
        .arg(&small)
        .assert()
        .success();
    let s = chaoscope::render::read_png(&small).unwrap();
    assert_eq!((s.width, s.height), (256, 256));
    for (r, c) in [(0, 0), (100, 37), (255, 255)] {
        let (i, j) = ((r * 256 + c) * 3, ((4 * r) * 1024 + 4 * c) * 3);
        assert_eq!(s.rgb[i..i + 3], b.rgb[j..j + 3], "pixel ({r}, {c})");
    }
}

#[test]
fn stores_refuse_other_commands_and_bad_tiles() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    let s = store.to_str().unwrap();
    let small = ["--size", "64", "--t-max", "1"];
    flip(&small, &["--data", s]).success();
    // Another command into the same store: refused, naming what differs.
    flip(&["--size", "64", "--t-max", "2"], &["--data", s])
        .code(2)
        .stderr(predicates::str::contains("--data"))
        .stderr(predicates::str::contains("--t-max 1"))
        .stderr(predicates::str::contains("--t-max 2"));
    // Another version.
    let meta = store.join("zarr.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    let version = format!("\"chaoscope:version\": \"{}\"", env!("CARGO_PKG_VERSION"));
    std::fs::write(
        &meta,
        text.replace(&version, "\"chaoscope:version\": \"0.0.1\""),
    )
    .unwrap();
    flip(&small, &["--data", s])
        .code(2)
        .stderr(predicates::str::contains("0.0.1"));
    for (tile, why) in [
        ("4/4", "INDEX < COUNT"),
        ("0/0", "COUNT >= 1"),
        ("x", "INDEX/COUNT"),
    ] {
        flip(&small, &["--data", s, "--tile", tile])
            .code(2)
            .stderr(predicates::str::contains("--tile"))
            .stderr(predicates::str::contains(why));
    }
    flip(&small, &["--tile", "0/2"])
        .code(2)
        .stderr(predicates::str::contains("--tile"));
    flip(&small, &["--data", s, "--output", "x.png"])
        .code(2)
        .stderr(predicates::str::contains("chaoscope render"));
    chaoscope()
        .args(["status", dir.path().join("none.zarr").to_str().unwrap()])
        .assert()
        .code(1)
        .stderr(predicates::str::contains("no Zarr store here"));
}

/// Two tasks with the same index at once write the same chunks: each writes whole files of
/// its own and renames them, so the store is whole and right.
#[test]
fn two_tasks_with_one_index_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    let npy = dir.path().join("m.npy");
    write_npy(&MAP, &npy);
    let bin = assert_cmd::cargo::cargo_bin("chaoscope");
    let tasks: Vec<_> = (0..2)
        .map(|_| {
            std::process::Command::new(&bin)
                .arg("flip")
                .args(MAP)
                .args(["--backend", backend(), "--tile", "0/1", "--data"])
                .arg(&store)
                .env("XDG_RUNTIME_DIR", std::env::temp_dir())
                .stderr(Stdio::null())
                .spawn()
                .unwrap()
        })
        .collect();
    for mut t in tasks {
        assert!(t.wait().unwrap().success());
    }
    assert_eq!(store_bits(&store), npy_bits(&npy));
    let temporary = common::walk(&store)
        .into_iter()
        .filter(|f| f.contains(".tmp-"))
        .count();
    assert_eq!(temporary, 0, "temporary files left");
}

/// Killed (SIGKILL, no chance to clean up) in the middle of its work, a task leaves whole
/// chunks only; run again, it finishes the store, equal to an uninterrupted run.
#[test]
fn a_killed_task_resubmitted_equals_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    let npy = dir.path().join("m.npy");
    // Unsymmetric rows, so each 128-row chunk (2048 wide) is a unit of its own: many units,
    // a few seconds in all on lavapipe.
    let map = ["--size", "2048x1024", "--t-max", "8", "--theta2", "0:3"];
    write_npy(&map, &npy);
    let bin = assert_cmd::cargo::cargo_bin("chaoscope");
    let mut child = std::process::Command::new(&bin)
        .arg("flip")
        .args(map)
        .args(["--backend", backend(), "--data"])
        .arg(&store)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Kill once a few chunks are written (or give up waiting after a while).
    let started = Instant::now();
    let chunks = |s: &Path| {
        std::fs::read_dir(s.join("map/c"))
            .map(|d| d.count())
            .unwrap_or(0)
    };
    while chunks(&store) < 2 && started.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let s = MapStore::open(&store).unwrap();
    let missing = s.missing().unwrap();
    assert!(
        !missing.is_empty(),
        "the task finished before the kill: make it longer"
    );
    // Every chunk file that exists is whole (a chunk is 128 rows of 2048 f32 and its 4-byte
    // crc32c checksum).
    for f in common::walk(&store.join("map/c")) {
        if !f.contains(".tmp-") {
            assert_eq!(
                std::fs::metadata(&f).unwrap().len(),
                128 * 2048 * 4 + 4,
                "{f}"
            );
        }
    }
    chaoscope()
        .arg("flip")
        .args(map)
        .args(["--backend", backend(), "--data"])
        .arg(&store)
        .assert()
        .success();
    assert_eq!(store_bits(&store), npy_bits(&npy));
}

/// A full disk: a clean error, and no corrupt chunk (a small tmpfs; needs root and mount).
#[test]
fn a_full_disk_leaves_no_corrupt_chunk() {
    let dir = tempfile::tempdir().unwrap();
    let mount = dir.path().join("small");
    std::fs::create_dir(&mount).unwrap();
    let mounted = std::process::Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=3m", "tmpfs"])
        .arg(&mount)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("SKIPPED: cannot mount a tmpfs here (needs root)");
        return;
    }
    let store = mount.join("m.zarr");
    let result = chaoscope()
        .arg("flip")
        .args(MAP)
        .args(["--backend", backend(), "--no-symmetry", "--data"])
        .arg(&store)
        .assert();
    let files = common::walk(&store.join("map/c"));
    std::process::Command::new("umount")
        .arg(&mount)
        .status()
        .ok();
    result
        .code(1)
        .stderr(predicates::str::contains("No space left"));
    // Two of the four 1 MiB chunks fit; none is partial, no temporary file stays.
    assert!(!files.is_empty(), "no chunk was written");
    for f in &files {
        assert!(!f.contains(".tmp-"), "temporary file left: {f}");
    }
    let _ = files;
}

/// Runs `script` in `python`; it must print "ok".
fn python_says_ok(python: &str, script: &str) {
    let out = std::process::Command::new(python)
        .args(["-c", script])
        .output()
        .unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("ok"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// zarr-python and xarray read the store: named dimensions, coordinates at the pixel
/// centres, the values of the .npy bit for bit. The Python is scripts/test's venv (or
/// CHAOSCOPE_PYTHON); without zarr and xarray the test says so, and fails under CI=true.
#[test]
fn xarray_reads_the_store() {
    let python = std::env::var("CHAOSCOPE_PYTHON").unwrap_or_else(|_| {
        let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/pyenv/bin/python");
        venv.to_str().unwrap().to_string()
    });
    let has = std::process::Command::new(&python)
        .args(["-c", "import xarray, zarr"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !has {
        assert_ne!(
            std::env::var("CI").as_deref(),
            Ok("true"),
            "{python} has no xarray and zarr (scripts/test installs them)"
        );
        eprintln!("SKIPPED: {python} has no xarray and zarr (scripts/test installs them)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (store, npy) = (dir.path().join("m.zarr"), dir.path().join("m.npy"));
    let map = ["--size", "96x64", "--t-max", "3", "--theta1", "-2:3"];
    flip(&map, &["--data", store.to_str().unwrap()]).success();
    write_npy(&map, &npy);
    let script = format!(
        r#"
import numpy as np, xarray as xr
ds = xr.open_zarr({store:?}, consolidated=False)
m = ds["map"]
assert m.dims == ("theta2", "theta1"), m.dims
assert m.attrs["units"] == "s"
t1, t2 = ds["theta1"].values, ds["theta2"].values
assert len(t1) == 96 and len(t2) == 64
assert abs(t1[0] - (-2 + 5 / 192)) < 1e-15 and t2[0] > t2[-1]
assert ds.attrs["chaoscope:command"].startswith("chaoscope flip --size 96x64")
n = np.load({npy:?})
assert np.array_equal(m.values.view(np.uint32), n.view(np.uint32))
# The chunks are checksummed (crc32c), and zarr-python reads them through the checksum.
import zarr
codecs = [c.to_dict()["name"] for c in zarr.open_array({store:?} + "/map", mode="r").metadata.codecs]
assert "crc32c" in codecs, codecs
print("ok")
"#
    );
    python_says_ok(&python, &script);
    // Any other plane: dimensions and coordinates named by its axes, with their units.
    let (store, npy) = (dir.path().join("p.zarr"), dir.path().join("p.npy"));
    let map = [
        "--size",
        "24x16",
        "--t-max",
        "2",
        "--x",
        "m2/m1=0.5:2",
        "--y",
        "omega1=-3:3",
        "--theta1",
        "1",
        "--theta2",
        "1",
    ];
    flip(&map, &["--data", store.to_str().unwrap()]).success();
    write_npy(&map, &npy);
    let script = format!(
        r#"
import numpy as np, xarray as xr
ds = xr.open_zarr({store:?}, consolidated=False)
m = ds["map"]
assert m.dims == ("omega1", "mass_ratio"), m.dims
assert ds["mass_ratio"].attrs["units"] == "1" and ds["omega1"].attrs["units"] == "rad/s"
r, w = ds["mass_ratio"].values, ds["omega1"].values
assert abs(r[0] - (0.5 + 1.5 / 48)) < 1e-15 and w[0] > w[-1] and len(w) == 16
assert "--x m2/m1=0.5:2 --y omega1=-3:3" in ds.attrs["chaoscope:command"]
n = np.load({npy:?})
assert np.array_equal(m.values.view(np.uint32), n.view(np.uint32))
print("ok")
"#
    );
    python_says_ok(&python, &script);
}

/// The verdict goes into the store as the array `resolved`, equal to the .npy mask; a store
/// made without it refuses a task that asks for it.
#[test]
fn the_verdict_goes_into_the_store() {
    let dir = tempfile::tempdir().unwrap();
    let (store, npy, mask) = (
        dir.path().join("m.zarr"),
        dir.path().join("m.npy"),
        dir.path().join("mask.npy"),
    );
    let s = store.to_str().unwrap();
    let map = ["--size", "128", "--t-max", "20"];
    flip(&map, &["--data", s, "--resolved", s])
        .success()
        .stderr(predicates::str::contains("% resolved"));
    chaoscope()
        .arg("flip")
        .args(map)
        .args(["--backend", backend(), "--output"])
        .arg(dir.path().join("m.png"))
        .arg("--data")
        .arg(&npy)
        .arg("--resolved")
        .arg(&mask)
        .assert()
        .success();
    let st = MapStore::open(&store).unwrap();
    let ours = st.read_resolved(0, st.height).unwrap().unwrap();
    assert_eq!(ours, common::read_mask(&mask).1);
    assert!(
        ours.contains(&0) && ours.contains(&1),
        "a 20 s map has both"
    );
    assert_eq!(store_bits(&store), npy_bits(&npy));
    let other = dir.path().join("n.zarr");
    let o = other.to_str().unwrap();
    flip(&map, &["--data", o]).success();
    flip(&map, &["--data", o, "--resolved", o])
        .code(2)
        .stderr(predicates::str::contains("without the verdict"));
    flip(&map, &["--data", o, "--resolved", "x.npy"])
        .code(2)
        .stderr(predicates::str::contains("--resolved"));
}

/// A --vary sweep's maps as one store (frame, theta2, theta1): each frame equals its single
/// map (the command in its PNG) bit for bit; a zoom sweep is refused.
#[test]
fn sweeps_go_into_one_store() {
    let dir = tempfile::tempdir().unwrap();
    let (out, store) = (dir.path().join("sweep"), dir.path().join("sweep.zarr"));
    let sweep = argv("sweep --vary m2/m1=0.5:2 --frames 3 --size 48x32 --t-max 4");
    chaoscope()
        .args(sweep)
        .args(["--backend", backend(), "--output"])
        .arg(&out)
        .arg("--data")
        .arg(&store)
        .assert()
        .success();
    let s = chaoscope::render::store::SweepStore::open_existing(&store).unwrap();
    for k in 0..3u32 {
        let command = png_text(&out.join(format!("frame_{k:04}.png")), "chaoscope:command");
        let npy = dir.path().join(format!("f{k}.npy"));
        chaoscope()
            .args(command.split_whitespace().skip(1))
            .arg("--output")
            .arg(npy.with_extension("png"))
            .arg("--data")
            .arg(&npy)
            .assert()
            .success();
        let frame: Vec<u32> = s
            .read_frame(k)
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect();
        assert_eq!(frame, npy_bits(&npy), "frame {k}");
    }
}

/// Divergence maps go into stores the same way: two tasks equal the .npy, and the store
/// renders.
#[test]
fn divergence_maps_go_into_stores() {
    let dir = tempfile::tempdir().unwrap();
    let (store, npy) = (dir.path().join("l.zarr"), dir.path().join("l.npy"));
    let s = store.to_str().unwrap();
    let map = ["lyapunov", "--size", "96x64", "--t-max", "2"];
    for tile in ["0/2", "1/2"] {
        chaoscope()
            .args(map)
            .args(["--backend", backend(), "--data", s, "--tile", tile])
            .assert()
            .success();
    }
    chaoscope()
        .args(map)
        .args(["--backend", backend(), "--output"])
        .arg(npy.with_extension("png"))
        .arg("--data")
        .arg(&npy)
        .assert()
        .success();
    assert_eq!(store_bits(&store), npy_bits(&npy));
    chaoscope()
        .args(["render", s, "--output"])
        .arg(dir.path().join("r.png"))
        .assert()
        .success();
    let png = chaoscope::render::read_png(&dir.path().join("r.png")).unwrap();
    assert_eq!((png.width, png.height), (96, 64));
}

/// Regression: a height that is not a whole number of chunks (2048 wide: chunks of 128
/// rows, so 200 rows end in a chunk of 72) was refused on writing the last chunk, and a
/// reopened store misread its chunks' height from their count.
#[test]
fn a_store_whose_last_chunk_is_shorter_equals_the_npy() {
    let dir = tempfile::tempdir().unwrap();
    let map = ["--size", "2048x200", "--t-max", "2", "--theta1", "-1:3"];
    let npy = dir.path().join("map.npy");
    write_npy(&map, &npy);
    let store = dir.path().join("map.zarr");
    let path = store.to_str().unwrap();
    flip(&map, &["--data", path, "--tile", "0/2"]).success();
    flip(&map, &["--data", path, "--tile", "1/2"]).success();
    let s = MapStore::open(&store).unwrap();
    assert_eq!((s.chunk_rows, s.chunks()), (128, 2));
    assert_eq!(s.missing().unwrap(), Vec::<u32>::new());
    assert_eq!(store_bits(&store), npy_bits(&npy));
}

/// A store's identity is data, not a command to run (issue 25's audit: a store whose command
/// said `--params /etc/shadow` made `render` read that file and print its first line, and
/// `--params /dev/zero` took 4 GB): `render` and `serve --store` read the map from the
/// recorded settings and never open a path named inside a store; recorded settings out of
/// range are refused like flags; a task with other settings is refused naming the flags.
#[test]
fn a_store_is_read_as_data_and_never_opens_what_it_names() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    let s = store.to_str().unwrap();
    let map = ["--size", "48", "--t-max", "2"];
    flip(&map, &["--data", s]).success();
    let meta = store.join("zarr.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    let secret = dir.path().join("secret.toml");
    std::fs::write(&secret, "m1 = \"the secret first line\"\n").unwrap();
    let hostile = text.replace(
        "\"chaoscope:command\": \"chaoscope flip",
        &format!(
            "\"chaoscope:command\": \"chaoscope flip --params {} --params /dev/zero",
            secret.display()
        ),
    );
    assert_ne!(hostile, text, "the command was rewritten");
    std::fs::write(&meta, &hostile).unwrap();
    let png = dir.path().join("r.png");
    let out = chaoscope()
        .args(["render", s, "--output"])
        .arg(&png)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{said}");
    assert!(!said.contains("secret"), "{said}");
    // The picture is the map's, from its recorded settings.
    let direct = dir.path().join("d.png");
    flip(&map, &["--output", direct.to_str().unwrap()]).success();
    let (a, b) = (
        chaoscope::render::read_png(&png).unwrap(),
        chaoscope::render::read_png(&direct).unwrap(),
    );
    assert!(a.rgb == b.rgb, "render's pixels differ from flip's");
    // Recorded settings out of range are refused as a flag would be.
    let bad = text.replace("\"t_max\": 2.0", "\"t_max\": -1.0");
    assert_ne!(bad, text, "t_max was rewritten");
    std::fs::write(&meta, &bad).unwrap();
    chaoscope()
        .args(["render", s, "--output"])
        .arg(&png)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("--t-max"));
    // Another task with other physics: refused, naming the flags that differ.
    std::fs::write(&meta, &text).unwrap();
    flip(
        &["--size", "48", "--t-max", "2", "--m2", "1.5"],
        &["--data", s],
    )
    .code(2)
    .stderr(predicates::str::contains(
        "`--m2 1` where this run has `--m2 1.5`",
    ));
}

/// Issue 25's audit: a chunk that was truncated, emptied, overwritten with garbage of the
/// right size, or replaced by a directory counted as written (`status` said complete, a
/// resume left it, `render` drew garbage). Chunks now carry Zarr's crc32c checksum and must
/// decode: `status` lists such a chunk as missing, `render` refuses naming it, and running
/// the command again rewrites it, after which the store equals the `.npy` bit for bit.
#[test]
fn a_damaged_chunk_is_missing_until_rewritten() {
    let dir = tempfile::tempdir().unwrap();
    let (store, npy) = (dir.path().join("m.zarr"), dir.path().join("m.npy"));
    let s = store.to_str().unwrap();
    let map = ["--size", "1024", "--t-max", "2"];
    flip(&map, &["--data", s]).success();
    flip(&map, &["--data", npy.to_str().unwrap()]).success();
    let chunk = store.join("map/c/1/0");
    let size = std::fs::metadata(&chunk).unwrap().len() as usize;
    let damages: [(&str, &dyn Fn()); 4] = [
        ("truncated", &|| {
            std::fs::write(&chunk, vec![0u8; 100]).unwrap()
        }),
        ("empty", &|| std::fs::write(&chunk, []).unwrap()),
        ("garbage of the right size", &|| {
            std::fs::write(&chunk, vec![0x5au8; size]).unwrap()
        }),
        ("a directory", &|| {
            std::fs::remove_file(&chunk).unwrap();
            std::fs::create_dir(&chunk).unwrap();
        }),
    ];
    for (what, damage) in damages {
        damage();
        chaoscope()
            .args(["status", s])
            .assert()
            .success()
            .stdout(predicates::str::contains("missing rows: 256..512"));
        chaoscope()
            .args(["render", s, "--output"])
            .arg(dir.path().join("r.png"))
            .assert()
            .failure()
            .stderr(predicates::str::contains(
                "chunk 1 (rows 256..512) is damaged",
            ));
        flip(&map, &["--data", s]).success();
        chaoscope()
            .args(["status", s])
            .assert()
            .success()
            .stdout(predicates::str::contains("complete"));
        assert_eq!(store_bits(&store), npy_bits(&npy), "{what}, rewritten");
    }
}

/// Issue 25's audit: the memory check counted the whole map for a store run, which holds one
/// band, so a 65536^2 store could not be made on a 24 GB machine, though maps past one
/// machine are what stores exist for. A task of it runs as its band; `status` follows it
/// (and ends quietly when its reader leaves early).
#[test]
fn a_65536_square_store_runs_as_tiles() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("big.zarr");
    let s = store.to_str().unwrap();
    flip(
        &["--size", "65536", "--t-max", "0.01"],
        &["--data", s, "--tile", "8191/8192"],
    )
    .success();
    chaoscope()
        .args(["status", s])
        .assert()
        .success()
        .stdout(predicates::str::contains(
            "65536x65536 map, 2 of 16384 chunks written",
        ));
}

/// Issue 25's audit: metadata that disagreed with the map was taken as it stood (a 0-d shape
/// panicked, other shapes made status report nonsense, resumes wrote maps unlike the
/// command's, a store narrower than its command made the explorer's worker panic). Every
/// reader now checks the arrays' layout (shape, data type, chunk rows, endianness, checksum)
/// and the recorded map against the arrays (size, mirrored chunks) before any work; a mismatch
/// is an error naming the field, never a panic.
#[test]
fn metadata_unlike_the_map_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("m.zarr");
    let s = store.to_str().unwrap();
    let map = ["--size", "256", "--t-max", "2"];
    flip(&map, &["--data", s]).success();
    let edit = |file: &str, change: &dyn Fn(&mut serde_json::Value)| {
        let path = store.join(file);
        let mut meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let before = meta.clone();
        change(&mut meta);
        std::fs::write(&path, meta.to_string()).unwrap();
        move || std::fs::write(&path, before.to_string()).unwrap()
    };
    // (the metadata file, what is changed, the change, what the error names)
    type Case<'a> = (
        &'a str,
        &'a str,
        &'a dyn Fn(&mut serde_json::Value),
        &'a str,
    );
    let cases: [Case; 7] = [
        (
            "map/zarr.json",
            "0-d shape",
            &|m| {
                m["shape"] = serde_json::json!([]);
                m["chunk_grid"]["configuration"]["chunk_shape"] = serde_json::json!([]);
            },
            "dimensionality",
        ),
        (
            "map/zarr.json",
            "chunk rows",
            &|m| {
                m["chunk_grid"]["configuration"]["chunk_shape"] = serde_json::json!([3, 256]);
            },
            "chunk_shape",
        ),
        (
            "map/zarr.json",
            "big endian",
            &|m| {
                m["codecs"][0]["configuration"]["endian"] = "big".into();
            },
            "little endian",
        ),
        (
            "map/zarr.json",
            "data type",
            &|m| m["data_type"] = "float64".into(),
            "data_type",
        ),
        (
            "map/zarr.json",
            "no checksum",
            &|m| {
                m["codecs"] = serde_json::json!([m["codecs"][0].clone()]);
            },
            "crc32c",
        ),
        (
            "map/zarr.json",
            "narrower than its map",
            &|m| {
                m["shape"] = serde_json::json!([256, 128]);
                m["chunk_grid"]["configuration"]["chunk_shape"] = serde_json::json!([256, 128]);
            },
            "256x256",
        ),
        (
            "zarr.json",
            "mirrored",
            &|m| {
                m["attributes"]["chaoscope:mirrored"] = false.into();
            },
            "mirrored",
        ),
    ];
    for (file, what, change, named) in cases {
        let restore = edit(file, change);
        for args in [
            vec!["status".to_string(), s.to_string()],
            vec![
                "render".into(),
                s.into(),
                "--output".into(),
                dir.path().join("r.png").to_string_lossy().into(),
            ],
            [
                "flip",
                "--size",
                "256",
                "--t-max",
                "2",
                "--backend",
                backend(),
                "--data",
                s,
            ]
            .map(String::from)
            .to_vec(),
        ] {
            let out = chaoscope().args(&args).output().unwrap();
            let said = String::from_utf8_lossy(&out.stderr);
            assert!(
                !out.status.success() && said.contains(named) && !said.contains("panicked"),
                "{what}, {}: {said}",
                args[0]
            );
        }
        restore();
    }
    chaoscope().args(["status", s]).assert().success();
}
