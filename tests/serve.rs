//! `chaoscope serve`, end to end: the server started as users start it, asked over HTTP.
//! Tiles must equal the pixels of `chaoscope flip` / `lyapunov` over the same region, the
//! trajectory endpoint the command it names, a saved view the command in its metadata; bad
//! queries get 400, paths outside the assets 404; a burst of requests is bounded; and a real
//! headless Chromium shows the map and a clicked pixel's pendulum.

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use chaoscope::render::read_png;
use common::{browser_report, browser_tools, chaoscope, gpu, png_text};

/// A running `chaoscope serve --port 0`, killed when dropped.
struct Server {
    child: Child,
    url: String,
    agent: ureq::Agent,
}

impl Server {
    fn start(args: &[&str]) -> Server {
        let bin = assert_cmd::cargo::cargo_bin("chaoscope");
        let mut child = Command::new(bin)
            .args(["serve", "--port", "0"])
            .args(args)
            .env("XDG_RUNTIME_DIR", std::env::temp_dir())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("chaoscope serve starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("the URL on stdout");
        let url = line.trim().trim_end_matches('/').to_string();
        assert!(url.starts_with("http://"), "no URL printed: {line:?}");
        let agent = ureq::Agent::new_with_config(
            ureq::Agent::config_builder()
                .http_status_as_error(false)
                .timeout_global(Some(Duration::from_secs(120)))
                .build(),
        );
        Server { child, url, agent }
    }

    /// (status, headers' precision, body) of GET `path`.
    fn get(&self, path: &str) -> (u16, Option<String>, Vec<u8>) {
        let mut r = self
            .agent
            .get(&format!("{}{path}", self.url))
            .call()
            .unwrap_or_else(|e| panic!("GET {path}: {e}"));
        let precision = r
            .headers()
            .get("x-chaoscope-precision")
            .map(|v| v.to_str().unwrap().to_string());
        let body = r
            .body_mut()
            .with_config()
            .limit(64 << 20)
            .read_to_vec()
            .unwrap();
        (r.status().as_u16(), precision, body)
    }

    /// GET `path` is refused with 400 naming `key`.
    fn refuses(&self, path: &str, key: &str) {
        let (status, _, body) = self.get(path);
        let body = String::from_utf8_lossy(&body);
        assert_eq!(status, 400, "{path}: {body}");
        assert!(
            body.starts_with(&format!("invalid value for {key}:")),
            "{path}: {body}"
        );
    }

    fn rss_kib(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id()))
            .expect("/proc status");
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.split_whitespace().next()?.parse().ok())
            .expect("VmRSS")
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// RGB bytes of a PNG file or of PNG bytes.
fn rgb_of_bytes(bytes: &[u8], dir: &Path, name: &str) -> (u32, u32, Vec<u8>) {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let png = read_png(&path).unwrap();
    (png.width, png.height, png.rgb)
}

/// Tile (z, x, y)'s theta ranges as `--theta1 MIN:MAX --theta2 MIN:MAX` (the server's own
/// arithmetic, printed shortest-exact so the command gets the same numbers).
fn tile_ranges(z: u32, x: u64, y: u64) -> [String; 4] {
    let g = chaoscope::serve::world::World::turn()
        .tile_grid(z, x, y, 256)
        .unwrap();
    [
        "--theta1".into(),
        format!("{}:{}", g.x.range.min, g.x.range.max),
        "--theta2".into(),
        format!("{}:{}", g.y.range.min, g.y.range.max),
    ]
}

fn first_differing_pixel(a: &[u8], b: &[u8], width: u32) -> Option<(usize, usize)> {
    a.chunks(3)
        .zip(b.chunks(3))
        .position(|(p, q)| p != q)
        .map(|k| (k % width as usize, k / width as usize))
}

/// (what, tile (z, x, y), its query, the map command's flags, the precision it runs in).
type Case<'a> = (&'a str, (u32, u64, u64), &'a str, &'a [&'a str], &'a str);

#[test]
fn tiles_equal_the_pixels_of_the_map_commands() {
    if gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let server = Server::start(&["--backend", "gpu", "--m2", "1.5"]);
    // Level 16's pixels (3.7e-7 rad) are finer than f32 resolves: the f64 kernels take over.
    let cases: &[Case] = &[
        (
            "flip",
            (2, 1, 2),
            "t_max=8",
            &["flip", "--t-max", "8"],
            "f32",
        ),
        (
            "flip, deep zoom",
            (16, 58_843, 6_692),
            "t_max=4&cmap=viridis",
            &["flip", "--t-max", "4", "--colormap", "viridis"],
            "f64",
        ),
        (
            "flip kind",
            (2, 3, 1),
            "kind=flip-kind&t_max=8",
            &["flip", "--t-max", "8", "--colour-by", "kind"],
            "f32",
        ),
        (
            "flip, unresolved grey",
            (1, 0, 1),
            "t_max=6&unresolved=1&damping=0.05",
            &[
                "flip",
                "--t-max",
                "6",
                "--joint-damping",
                "0.05",
                "--show-unresolved",
            ],
            "f32",
        ),
        (
            "divergence",
            (1, 1, 0),
            "kind=ftle&t_max=5&lo=0&hi=1.5",
            &["lyapunov", "--t-max", "5", "--colour-range", "0:1.5"],
            "f32",
        ),
        (
            "accurate flip",
            (3, 2, 3),
            "t_max=5&accurate=1",
            &["flip", "--t-max", "5", "--accurate"],
            "f64",
        ),
        (
            "accurate divergence",
            (2, 1, 2),
            "kind=ftle&t_max=1&lo=0&hi=3&accurate=1",
            &[
                "lyapunov",
                "--t-max",
                "1",
                "--colour-range",
                "0:3",
                "--accurate",
            ],
            "f64",
        ),
    ];
    for (k, &(what, (z, x, y), query, flags, precision)) in cases.iter().enumerate() {
        let (status, ran, body) = server.get(&format!("/tile/{z}/{x}/{y}.png?{query}&m2=1.5"));
        assert_eq!(status, 200, "{what}: {}", String::from_utf8_lossy(&body));
        assert_eq!(ran.as_deref(), Some(precision), "{what}: precision");
        let (w, h, tile) = rgb_of_bytes(&body, dir.path(), &format!("tile{k}.png"));
        assert_eq!((w, h), (256, 256), "{what}");
        let out = dir.path().join(format!("map{k}.png"));
        chaoscope()
            .args(flags)
            .args(tile_ranges(z, x, y))
            .args("--size 256 --m2 1.5 --backend gpu --output".split(' '))
            .arg(&out)
            .assert()
            .success();
        let map = read_png(&out).unwrap();
        assert_eq!(
            first_differing_pixel(&tile, &map.rgb, 256),
            None,
            "{what}: tile {z}/{x}/{y} differs from the command's map at (x, y)"
        );
    }
    // The verdict's tile is the --resolved mask: white where 1.
    let (status, _, body) = server.get("/tile/1/1/1.png?kind=resolved&t_max=6&m2=1.5");
    assert_eq!(status, 200);
    let (_, _, tile) = rgb_of_bytes(&body, dir.path(), "mask.png");
    let mask = dir.path().join("mask.npy");
    chaoscope()
        .args("flip --t-max 6 --size 256 --m2 1.5 --backend gpu".split(' '))
        .args(tile_ranges(1, 1, 1))
        .arg("--output")
        .arg(dir.path().join("m.png"))
        .arg("--resolved")
        .arg(&mask)
        .assert()
        .success();
    let (_, m) = common::read_mask(&mask);
    let want: Vec<u8> = m.iter().flat_map(|&v| [255 * v; 3]).collect();
    assert_eq!(
        first_differing_pixel(&tile, &want, 256),
        None,
        "verdict tile"
    );
    assert!(m.contains(&0) && m.contains(&1), "the mask has both kinds");
    // A second request comes from the cache, the same bytes.
    let (_, ran, again) = server.get("/tile/1/1/1.png?kind=resolved&t_max=6&m2=1.5");
    assert_eq!((ran.as_deref(), again), (Some("cached"), body));
}

/// Issue 22: the page's planes. A tile of the (theta1, omega1) plane at a fixed theta2, and of
/// the (m2/m1, l2/l1) parameter plane at a fixed start, equal `chaoscope flip --x .. --y ..`
/// over the tile's ranges pixel for pixel; a clicked point of the parameter plane is the
/// pendulum with that pixel's parameters (its trajectory's command says so and reproduces it).
#[test]
fn a_planes_tiles_and_points_equal_the_map_commands() {
    if gpu().is_none() {
        return;
    }
    use chaoscope::spec::{Axis, Grid, Var};
    let dir = tempfile::tempdir().unwrap();
    let server = Server::start(&["--backend", "gpu"]);
    let fixed = |theta1: f64, theta2: f64| Grid {
        fixed: chaoscope::model::State {
            theta1,
            theta2,
            ..Default::default()
        },
        ..Grid::square(1)
    };
    let cases = [
        (
            "x=theta1&y=omega1&y_min=-6&y_max=6&theta2=0.5&t_max=5",
            Grid {
                x: Axis::new(Var::Theta1, -std::f64::consts::PI, std::f64::consts::PI),
                y: Axis::new(Var::Omega1, -6.0, 6.0),
                ..fixed(0.0, 0.5)
            },
            (1, 1, 0),
            vec!["--theta2", "0.5"],
        ),
        (
            "x=m2/m1&y=l2/l1&x_min=0.5&x_max=2.5&y_min=0.5&y_max=2&theta1=2&theta2=1&t_max=5",
            Grid {
                x: Axis::new(Var::MassRatio, 0.5, 2.5),
                y: Axis::new(Var::LengthRatio, 0.5, 2.0),
                ..fixed(2.0, 1.0)
            },
            (1, 0, 1),
            vec!["--theta1", "2", "--theta2", "1"],
        ),
    ];
    for (k, (query, plane, (z, x, y), start)) in cases.into_iter().enumerate() {
        let (status, ran, body) = server.get(&format!("/tile/{z}/{x}/{y}.png?{query}&size=64"));
        assert_eq!(status, 200, "{query}: {}", String::from_utf8_lossy(&body));
        assert_eq!(ran.as_deref(), Some("f32"));
        let (_, _, tile) = rgb_of_bytes(&body, dir.path(), &format!("plane{k}.png"));
        let g = chaoscope::serve::world::World::of_plane(&plane)
            .tile_grid(z, x, y, 64)
            .unwrap();
        let axis = |a: Axis| format!("{}={}:{}", a.var.name(), a.range.min, a.range.max);
        let out = dir.path().join(format!("plane_map{k}.png"));
        chaoscope()
            .args(["flip", "--t-max", "5", "--size", "64", "--backend", "gpu"])
            .args(["--x", &axis(g.x), "--y", &axis(g.y)])
            .args(start)
            .arg("--output")
            .arg(&out)
            .assert()
            .success();
        let map = read_png(&out).unwrap();
        assert_eq!(
            first_differing_pixel(&tile, &map.rgb, 64),
            None,
            "{query}: tile {z}/{x}/{y} differs from the command's map at (x, y)"
        );
    }
    let point = "x=m2/m1&y=l2/l1&theta1=2&theta2=1&t_max=5&px=1.75&py=1.25";
    let (status, _, body) = server.get(&format!("/api/point?{point}&pixel=0.01"));
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    let answer: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(answer["params"]["m2"], 1.75, "{answer}");
    assert_eq!(answer["params"]["l2"], 1.25, "{answer}");
    assert_eq!(answer["start"]["theta1"], 2.0, "{answer}");
    let (status, _, csv) = server.get(&format!("/api/trajectory?{point}"));
    assert_eq!(status, 200);
    let csv = String::from_utf8(csv).unwrap();
    let command = csv
        .lines()
        .next()
        .unwrap()
        .strip_prefix("# chaoscope ")
        .unwrap();
    assert!(
        command.contains("--m2 1.75") && command.contains("--l2 1.25"),
        "{command}"
    );
    let out = chaoscope()
        .args(command.split_whitespace())
        .output()
        .unwrap();
    assert_eq!(String::from_utf8(out.stdout).unwrap(), csv, "{command}");
}

/// A store of any plane is served: its axes in /api/info (the page's), its tiles read from
/// it; its region is its own (a tile asking another is refused naming the key).
#[test]
fn a_store_of_any_plane_is_served_with_its_axes() {
    if gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("plane.zarr");
    chaoscope()
        .args(["flip", "--size", "64", "--t-max", "3", "--backend", "gpu"])
        .args("--x theta1 --y omega1=-4:4 --theta2 0.3 --data".split(' '))
        .arg(&store)
        .assert()
        .success();
    let server = Server::start(&["--backend", "gpu", "--store", store.to_str().unwrap()]);
    let (_, _, info) = server.get("/api/info");
    let info: serde_json::Value = serde_json::from_slice(&info).unwrap();
    let s = &info["store"];
    assert_eq!(
        (&s["x"]["name"], &s["y"]["name"], &s["y"]["range"]),
        (
            &serde_json::json!("theta1"),
            &serde_json::json!("omega1"),
            &serde_json::json!([-4.0, 4.0])
        ),
        "{info}"
    );
    assert_eq!(s["start"]["theta2"], 0.3, "{info}");
    let (status, ran, _) = server.get("/tile/0/0/0.png");
    assert_eq!((status, ran.as_deref()), (200, Some("stored")));
    server.refuses("/tile/0/0/0.png?x_min=0&x_max=1", "x_min");
    server.refuses("/tile/0/0/0.png?y=omega2", "y");
}

#[test]
fn trajectory_and_saved_view_equal_their_commands() {
    if gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let server = Server::start(&["--backend", "gpu"]);
    let (status, _, csv) = server.get("/api/trajectory?px=2.1&py=-0.7&t_max=3&l2=0.8&damping=0.01");
    assert_eq!(status, 200);
    let csv = String::from_utf8(csv).unwrap();
    let command = csv
        .lines()
        .next()
        .unwrap()
        .strip_prefix("# chaoscope ")
        .unwrap();
    let out = chaoscope()
        .args(command.split_whitespace())
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(String::from_utf8(out.stdout).unwrap(), csv, "{command}");

    let (status, _, png) = server.get(
        "/api/save?t_max=5&x_min=-1&x_max=2&y_min=0.5&y_max=3\
         &width=96&height=80&annotate=1&cmap=turbo",
    );
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&png));
    let saved = dir.path().join("saved.png");
    std::fs::write(&saved, &png).unwrap();
    let command = png_text(&saved, "chaoscope:command");
    assert!(
        command.contains("--theta1 -1:2") && command.contains("--size 96x80"),
        "{command}"
    );
    let again = dir.path().join("again.png");
    chaoscope()
        .args(
            command
                .strip_prefix("chaoscope ")
                .unwrap()
                .split_whitespace(),
        )
        .arg("--output")
        .arg(&again)
        .assert()
        .success();
    let (a, b) = (read_png(&saved).unwrap(), read_png(&again).unwrap());
    assert_eq!((a.width, a.height), (b.width, b.height));
    assert!(
        a.rgb == b.rgb,
        "the saved view differs from its command's PNG"
    );

    // The clicked pixel's flip time is the one-pixel map's, with its verdict.
    let (status, _, point) = server.get("/api/point?px=2.5&py=2.5&pixel=0.01&t_max=10");
    assert_eq!(status, 200);
    let point: serde_json::Value = serde_json::from_slice(&point).unwrap();
    let t = point["flip_time"].as_f64().expect("(2.5, 2.5) flips");
    assert!(t > 0.0 && t < 10.0, "{point}");
    assert_eq!(point["precision"], "f32");
}

#[test]
fn bad_queries_get_400_naming_the_key() {
    if gpu().is_none() {
        return;
    }
    let server = Server::start(&["--backend", "gpu"]);
    for (path, key) in [
        ("/tile/0/0/0.png?kind=mandelbrot", "kind"),
        ("/tile/0/0/0.png?kind=flip-kind&accurate=1", "accurate"),
        ("/tile/0/0/0.png?t_max=NaN", "t_max"),
        ("/tile/0/0/0.png?t_max=1e6", "t_max"),
        ("/tile/0/0/0.png?dt=0", "dt"),
        ("/tile/0/0/0.png?size=100000", "size"),
        ("/tile/1/2/0.png", "x"),
        ("/tile/1/0/7.png", "y"),
        ("/tile/99/0/0.png", "z"),
        ("/tile/a/0/0.png", "z"),
        ("/tile/0/0/0.png?m1=-1", "m1"),
        ("/tile/0/0/0.png?damping=inf", "damping"),
        ("/tile/0/0/0.png?tmax=3", "query"),
        ("/tile/0/0/0.png?kind=ftle&lo=2&hi=1", "hi"),
        ("/api/point?py=1", "px"),
        ("/tile/0/0/0.png?x=speed", "x"),
        ("/tile/0/0/0.png?y=theta1", "y"),
        ("/tile/0/0/0.png?theta1=1", "theta1"),
        ("/tile/0/0/0.png?x=m2/m1&m2=2", "m2"),
        ("/tile/0/0/0.png?x=damping&damping=0.1", "damping"),
        ("/tile/0/0/0.png?x_min=1", "x_min"),
        ("/tile/0/0/0.png?y_max=1", "y_max"),
        ("/tile/0/0/0.png?x_min=-4&x_max=1", "x_min"),
        ("/api/legend?cmap=plaid", "cmap"),
        ("/api/trajectory?px=1&py=1e9", "py"),
        (
            "/api/save?x_min=0&x_max=1&y_min=0&y_max=1&width=1e5",
            "width",
        ),
        ("/api/save?x_min=1&x_max=0&y_min=0&y_max=1", "x_max"),
        ("/api/zoom?cx=0.5&cy=0.5", "w"),
        // Past f64's resolution: the zoom's own refusal, naming the width.
        ("/api/zoom?cx=0.5&cy=0.5&w=1e-15", "w"),
        ("/api/zoom?cx=0.5&cy=0.5&w=1e-3&frames=1", "frames"),
    ] {
        server.refuses(path, key);
    }
}

#[test]
fn only_the_assets_are_served() {
    if gpu().is_none() {
        return;
    }
    let server = Server::start(&["--backend", "gpu"]);
    assert!(
        server.url.starts_with("http://127.0.0.1:"),
        "{}",
        server.url
    );
    let (status, _, page) = server.get("/");
    assert_eq!(status, 200);
    assert!(String::from_utf8_lossy(&page).contains("/assets/vendor/leaflet/leaflet.js"));
    // The colour bar: the tiles' own table, ticks inside the bar.
    let (status, _, bar) = server.get("/api/legend?t_max=20");
    assert_eq!(status, 200);
    let bar: serde_json::Value = serde_json::from_slice(&bar).unwrap();
    assert_eq!(bar["colors"].as_array().unwrap().len(), 64, "{bar}");
    assert!(
        bar["ticks"]
            .as_array()
            .unwrap()
            .iter()
            .all(|t| (0.0..=1.0).contains(&t[0].as_f64().unwrap())),
        "{bar}"
    );
    let (status, _, licence) = server.get("/assets/vendor/leaflet/LICENSE");
    assert_eq!(status, 200);
    assert!(String::from_utf8_lossy(&licence).contains("BSD 2-Clause"));
    for path in [
        "/assets/../Cargo.toml",
        "/assets/%2e%2e/Cargo.toml",
        "/assets/%2e%2e/%2e%2e/etc/passwd",
        "/assets/vendor/leaflet/../../../src/main.rs",
        "/assets/vendor%2fleaflet%2f..%2f..%2fapp.js",
        "/assets/",
        "/assets/app.js/",
        "/etc/passwd",
        "/src/main.rs",
        "/tile/0/0/0.png/../../../Cargo.toml",
        "/index.html",
    ] {
        let (status, _, body) = server.get(path);
        assert_eq!(status, 404, "{path}: {}", String::from_utf8_lossy(&body));
    }
}

#[test]
fn a_burst_of_requests_is_bounded_and_the_server_still_answers() {
    if gpu().is_none() {
        return;
    }
    let server = Server::start(&["--backend", "gpu"]);
    server.get("/tile/0/0/0.png?t_max=1");
    let before = server.rss_kib();
    // 200 different tiles at once (level 5 has 1024): some wait, the rest are refused (503)
    // once the queue is full.
    let statuses: Vec<u16> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..200u64)
            .map(|k| {
                let server = &server;
                s.spawn(move || {
                    server
                        .get(&format!("/tile/5/{}/{}.png?t_max=2", k % 32, k / 32))
                        .0
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let after = server.rss_kib();
    let ok = statuses.iter().filter(|&&s| s == 200).count();
    let busy = statuses.iter().filter(|&&s| s == 503).count();
    eprintln!(
        "200 requests at once: {ok} tiles, {busy} refused; RSS {} -> {} MiB",
        before / 1024,
        after / 1024
    );
    assert_eq!(
        ok + busy,
        200,
        "every request gets a tile or 503: {statuses:?}"
    );
    assert!(
        ok >= chaoscope::serve::MAX_WAITING.min(200) / 2,
        "{ok} tiles"
    );
    let (status, _, stats) = server.get("/api/stats");
    assert_eq!(status, 200);
    let stats: serde_json::Value = serde_json::from_slice(&stats).unwrap();
    assert_eq!(stats["refused"].as_u64(), Some(busy as u64), "{stats}");
    assert_eq!(stats["waiting"].as_u64(), Some(0), "{stats}");
    let (status, _, _) = server.get("/tile/0/0/0.png?t_max=1.5");
    assert_eq!(status, 200, "the server answers after the burst");
}

#[test]
fn a_request_whose_client_leaves_is_cancelled() {
    if gpu().is_none() {
        return;
    }
    let server = Server::start(&["--backend", "gpu"]);
    server.get("/tile/0/0/0.png?t_max=1");
    // A tile that takes seconds (divergence maps have no early exit; ~8 s on lavapipe),
    // abandoned after 0.3 s.
    let impatient = ureq::Agent::new_with_config(
        ureq::Agent::config_builder()
            .timeout_global(Some(Duration::from_millis(300)))
            .build(),
    );
    let gone = impatient
        .get(&format!(
            "{}/tile/2/1/1.png?kind=ftle&t_max=100",
            server.url
        ))
        .call();
    assert!(
        gone.is_err(),
        "the slow tile should not have finished in 0.3 s"
    );
    let mut stats = serde_json::Value::Null;
    for _ in 0..100 {
        std::thread::sleep(Duration::from_millis(100));
        let (_, _, body) = server.get("/api/stats");
        stats = serde_json::from_slice(&body).unwrap();
        if stats["cancelled"].as_u64() == Some(1) && stats["waiting"].as_u64() == Some(0) {
            break;
        }
    }
    assert_eq!(stats["cancelled"].as_u64(), Some(1), "{stats}");
    assert_eq!(stats["computed"].as_u64(), Some(1), "{stats}");
    let (status, _, _) = server.get("/tile/0/0/0.png?t_max=2");
    assert_eq!(status, 200);
}

#[test]
fn a_stored_map_is_served_from_its_pixels_and_computed_below_them() {
    if gpu().is_none() {
        return;
    }
    use chaoscope::serve::world::World;
    let dir = tempfile::tempdir().unwrap();
    let store = dir.path().join("map.zarr");
    // 600 x 300 pixels: level 2 holds them one to one (3 x 2 tiles, the last ones partly
    // beyond the map's edge).
    let map = [
        "flip", "--size", "600x300", "--theta1", "-2:3", "--theta2", "-1:2", "--t-max", "6",
    ];
    chaoscope()
        .args(map)
        .args(["--backend", "gpu", "--data"])
        .arg(&store)
        .arg("--resolved")
        .arg(&store)
        .assert()
        .success();
    let whole = dir.path().join("whole.png");
    chaoscope()
        .arg("render")
        .arg(&store)
        .arg("--output")
        .arg(&whole)
        .assert()
        .success();
    let whole = read_png(&whole).unwrap();
    let server = Server::start(&["--backend", "gpu", "--store", store.to_str().unwrap()]);
    let s = chaoscope::render::store::MapStore::open(&store).unwrap();
    let mask = s.read_resolved(0, 300).unwrap().unwrap();
    let grid = chaoscope::spec::Grid::angles(
        600,
        300,
        chaoscope::spec::Range {
            min: -2.0,
            max: 3.0,
        },
        chaoscope::spec::Range {
            min: -1.0,
            max: 2.0,
        },
        0.0,
        0.0,
    );
    let world = World::of_grid(&grid);
    const OUTSIDE: [u8; 3] = [42, 42, 48];
    for (z, x, y) in [(2, 2, 1), (2, 0, 0), (0, 0, 0), (1, 1, 0)] {
        let (status, ran, body) = server.get(&format!("/tile/{z}/{x}/{y}.png"));
        assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
        assert_eq!(ran.as_deref(), Some("stored"));
        let (_, _, tile) = rgb_of_bytes(&body, dir.path(), "t.png");
        let (_, _, verdict) = rgb_of_bytes(
            &server
                .get(&format!("/tile/{z}/{x}/{y}.png?kind=resolved"))
                .2,
            dir.path(),
            "v.png",
        );
        for j in 0..256u32 {
            for i in 0..256u32 {
                let col = world.stored_pixel(z, x, i, 256);
                let row = world.stored_pixel(z, y, j, 256);
                let k = 3 * (j * 256 + i) as usize;
                let (want, want_verdict) = if col < 600 && row < 300 {
                    let w = 3 * (row * 600 + col) as usize;
                    let m = mask[(row * 600 + col) as usize];
                    (&whole.rgb[w..w + 3], [if m == 1 { 255 } else { 0 }; 3])
                } else {
                    (&OUTSIDE[..], OUTSIDE)
                };
                assert_eq!(&tile[k..k + 3], want, "tile {z}/{x}/{y} at ({i}, {j})");
                assert_eq!(
                    verdict[k..k + 3],
                    want_verdict,
                    "verdict {z}/{x}/{y} at ({i}, {j})"
                );
            }
        }
    }
    // Below the store's pixels: computed with its command's settings over the tile.
    let (status, ran, body) = server.get("/tile/4/5/3.png");
    assert_eq!((status, ran.as_deref()), (200, Some("f32")));
    let (_, _, tile) = rgb_of_bytes(&body, dir.path(), "deep.png");
    let g = world.tile_grid(4, 5, 3, 256).unwrap();
    let out = dir.path().join("deep_flip.png");
    chaoscope()
        .args("flip --size 256 --t-max 6 --backend gpu --theta1".split(' '))
        .arg(format!("{}:{}", g.x.range.min, g.x.range.max))
        .arg("--theta2")
        .arg(format!("{}:{}", g.y.range.min, g.y.range.max))
        .arg("--output")
        .arg(&out)
        .assert()
        .success();
    assert_eq!(
        first_differing_pixel(&tile, &read_png(&out).unwrap().rgb, 256),
        None
    );
    // The store fixes the physics and the kind.
    for (path, key) in [
        ("/tile/0/0/0.png?m1=2", "m1"),
        ("/tile/0/0/0.png?t_max=3", "t_max"),
        ("/tile/0/0/0.png?kind=ftle", "kind"),
        ("/tile/2/0/2.png", "y"),
    ] {
        server.refuses(path, key);
    }
}

/// The static explorer under /web/ (its files only), and in a browser without WebGPU its
/// fall back to this server's explorer with the same map, time and region.
#[test]
fn the_static_page_falls_back_to_the_servers_explorer_without_webgpu() {
    if gpu().is_none() {
        return;
    }
    let server = Server::start(&["--backend", "gpu"]);
    let (status, _, page) = server.get("/web/");
    assert_eq!(status, 200);
    assert!(String::from_utf8_lossy(&page).contains("explorer.js"));
    assert_eq!(server.get("/web/manifest.json").0, 200);
    for path in ["/web/../Cargo.toml", "/web/app.js", "/web/x/manifest.json"] {
        assert_eq!(server.get(path).0, 404, "{path}");
    }
    let Some(python) = browser_tools() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let url = format!("{}/web/#kind=ftle&t_max=5&cx=1&cy=1&w=2", server.url);
    let shot = dir.path().join("fallback.png");
    let report = browser_report(
        &python,
        "web.py",
        &["--no-webgpu".as_ref(), url.as_ref(), shot.as_ref()],
    );
    let location = report["location"].as_str().unwrap();
    let (page, hash) = location.split_once('#').unwrap();
    assert_eq!(page, format!("{}/", server.url), "the server's explorer");
    let keys: Vec<&str> = hash.split('&').collect();
    for key in [
        "kind=ftle",
        "t_max=5",
        "x=theta1",
        "x_min=0",
        "x_max=2",
        "y=theta2",
        "y_min=0",
        "y_max=2",
    ] {
        assert!(keys.contains(&key), "{key} in {location}");
    }
    // The server's explorer drew its map: many colours, not an empty page.
    let shot = read_png(&shot).unwrap();
    let colours: std::collections::HashSet<&[u8]> = shot.rgb.chunks(3).collect();
    assert!(colours.len() > 200, "{} colours", colours.len());
}

#[test]
fn the_page_shows_the_map_and_a_clicked_pendulum_in_chromium() {
    if gpu().is_none() {
        return;
    }
    let Some(python) = browser_tools() else {
        return;
    };
    let server = Server::start(&["--backend", "gpu"]);
    let dir = tempfile::tempdir().unwrap();
    let url = format!("{}/", server.url);
    let report = browser_report(&python, "explore.py", &[url.as_ref(), dir.path().as_ref()]);

    // The first screenshot shows a map: many colours inside the map's area, not a blank or
    // an error page.
    let (mx, my, mw, mh) = (
        report["map_box"][0].as_u64().unwrap() as u32,
        report["map_box"][1].as_u64().unwrap() as u32,
        report["map_box"][2].as_u64().unwrap() as u32,
        report["map_box"][3].as_u64().unwrap() as u32,
    );
    // The colours of a screenshot within the first view's map area.
    let colours_in = |name: &str| {
        let shot = read_png(&dir.path().join(name)).unwrap();
        let mut colours = std::collections::HashSet::new();
        for y in my..(my + mh).min(shot.height) {
            for x in mx..(mx + mw).min(shot.width) {
                let k = 3 * (y * shot.width + x) as usize;
                colours.insert([shot.rgb[k], shot.rgb[k + 1], shot.rgb[k + 2]]);
            }
        }
        colours.len()
    };
    let colours = colours_in("map.png");
    assert!(colours > 200, "{colours} colours in the map's area");
    // The click showed its pendulum: the command that reproduces it, drawn arms, a flip
    // time; shift-click added a second start.
    let command = report["command"].as_str().unwrap();
    assert!(
        command.starts_with("chaoscope trajectory --theta1 "),
        "{command}"
    );
    assert!(report["swing_pixels"].as_u64().unwrap() > 200, "{report}");
    assert!(report["starts"].as_array().unwrap().len() == 2, "{report}");
    assert!(
        report["starts"][0].as_str().unwrap().contains("flips at"),
        "{report}"
    );
    assert!(dir.path().join("pendulum.png").exists());
    // The axis menus: the (theta1, omega1) plane's tiles at theta2 = 0.4, omega1's input off
    // (it varies along y) and theta2's on; a click there is that pendulum.
    let tiles = report["plane_tiles"].as_str().unwrap();
    assert!(
        tiles.contains("y=omega1") && tiles.contains("theta2=0.4") && tiles.contains("y_min=-8"),
        "{tiles}"
    );
    assert_eq!(
        report["plane_inputs"],
        serde_json::json!([["omega1", true], ["theta2", false], ["m2", false]])
    );
    let status = report["plane_status"].as_str().unwrap();
    assert!(
        status.contains("rad × ") && status.contains("rad/s"),
        "{status}"
    );
    // The number after `label` in `text`.
    let after = |text: &str, label: &str| -> f64 {
        let rest = &text[text
            .find(label)
            .unwrap_or_else(|| panic!("{label} in {text}"))
            + label.len()..];
        let end = rest.find([',', ' ', ':']).unwrap_or(rest.len());
        rest[..end].parse().unwrap()
    };
    // The clicked pixel's centre: within a pixel (2 pi / 1024 rad, 16 / 1024 rad/s at the
    // first view's tile zoom 2) of the point clicked.
    let start = report["plane_starts"][0].as_str().unwrap();
    assert!(
        (after(start, "θ1 ") - 2.0).abs() < 0.01 && (after(start, "ω1 ") - 3.0).abs() < 0.02,
        "{start}"
    );
    let command = report["plane_command"].as_str().unwrap();
    assert_eq!(after(command, "--theta2 "), 0.4, "{command}");
    // The list shows 7 significant digits of the command's value.
    let omega1 = after(command, "--omega1 ");
    assert!(
        (omega1 - after(start, "ω1 ")).abs() < 1e-6 * omega1.abs(),
        "{command}"
    );
    // "Zoom film to here" on the (theta1, theta2) view at (1.2, 0.9), zoom 2: a zoom command
    // that parses, from the whole plane to the view on the screen (2 pi a 256 px tile at zoom
    // 0) kept square and inside the plane: no wider than it, its centre moved in.
    let zoom = report["zoom_command"].as_str().unwrap();
    let words = std::iter::once("chaoscope").chain(zoom.split_whitespace().skip(1));
    chaoscope::cli::Cli::parse_args(words).unwrap_or_else(|e| panic!("{zoom}: {e}"));
    let to: Vec<f64> = zoom["chaoscope zoom --to ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let [px, z] = [0, 1].map(|k| report["zoom_view"][k].as_f64().unwrap());
    let tau = 2.0 * std::f64::consts::PI;
    let w = (px / (256.0 * z.exp2()) * tau).min(tau);
    let inside = |c: f64| c.clamp(-0.5 * tau + 0.5 * w, 0.5 * tau - 0.5 * w);
    // Within a pixel of the screen's view.
    let pixel = tau / (256.0 * z.exp2());
    assert!(
        (to[2] - w).abs() < pixel
            && (to[0] - inside(1.2)).abs() < pixel
            && (to[1] - inside(0.9)).abs() < pixel,
        "{zoom}: expected about {},{},{w}",
        inside(1.2),
        inside(0.9)
    );
    assert!(
        zoom.contains(" flip --size 1080x1080 --theta1 -3.14"),
        "{zoom}"
    );
    let colours = colours_in("plane.png");
    assert!(colours > 200, "{colours} colours in the plane");
    // The page's menu of maps is the kinds' table, and the verdict.
    let mut kinds: Vec<&str> = chaoscope::spec::MapKind::all()
        .iter()
        .map(|k| k.short())
        .collect();
    kinds.push("resolved");
    assert_eq!(report["kinds"], serde_json::json!(kinds), "{report}");
    // Issue 25's audit: the first view of a 1400 x 900 window filled a third of it (zoom 1,
    // whole steps). The world's square now fills the map's shorter side to within a quarter
    // zoom step (2^-0.25 = 0.84) and stays inside it.
    let fill = &report["first_fill"];
    let [w, h, bw, bh] = [0, 1, 2, 3].map(|k| fill[k].as_f64().unwrap());
    let side = bw.min(bh);
    assert!(
        w >= 0.84 * side && w <= side + 1.0 && (w - h).abs() < 1.0,
        "first view {w} x {h} in a {bw} x {bh} map"
    );
}

#[test]
fn ctrl_c_stops_the_server_while_it_computes() {
    if gpu().is_none() {
        return;
    }
    let mut server = Server::start(&["--backend", "gpu"]);
    // A slow tile (~8 s on lavapipe) in flight when Ctrl-C comes.
    let url = format!("{}/tile/2/1/1.png?kind=ftle&t_max=100", server.url);
    std::thread::spawn(move || ureq::get(&url).call().ok());
    std::thread::sleep(Duration::from_millis(300));
    let pid = server.child.id().to_string();
    assert!(
        Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success()
    );
    let started = std::time::Instant::now();
    let status = loop {
        if let Some(status) = server.child.try_wait().unwrap() {
            break status;
        }
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "still running 20 s after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    assert!(status.success(), "{status}");
}

#[test]
fn bad_serve_flags_exit_2_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    for (args, flag) in [
        (vec!["--m1", "-1"], "--m1"),
        (vec!["--port", "99999"], "--port"),
        (vec!["--host", "localhost:80"], "--host"),
        (vec!["--store", "missing.zarr"], "missing.zarr"),
        (vec!["--store", "missing.zarr", "--m2", "2"], "--store"),
    ] {
        chaoscope()
            .current_dir(dir.path())
            .arg("serve")
            .args(&args)
            .timeout(Duration::from_secs(30))
            .assert()
            .failure()
            .stderr(predicates::str::contains(flag));
    }
}

/// A client that never finishes its request is cut off after the header-read limit, and
/// the server goes on answering others meanwhile.
#[test]
fn a_request_never_finished_is_cut_off() {
    if gpu().is_none() {
        return;
    }
    use std::io::{Read, Write};
    let server = Server::start(&["--backend", "gpu"]);
    let address = server.url.trim_start_matches("http://");
    let mut slow = std::net::TcpStream::connect(address).unwrap();
    slow.write_all(b"GET /api/info HTTP/1.1\r\nHost: x\r\n")
        .unwrap();
    let (status, _, _) = server.get("/api/info");
    assert_eq!(status, 200, "others are answered while one request hangs");
    slow.set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let started = std::time::Instant::now();
    let mut rest = Vec::new();
    // The server closes the connection (perhaps after a 408): the read ends.
    let _ = slow.read_to_end(&mut rest);
    let waited = started.elapsed();
    let limit = chaoscope::serve::HEADER_READ_LIMIT;
    assert!(
        waited < limit + Duration::from_secs(5),
        "closed after {waited:?} (limit {limit:?})"
    );
    assert!(
        rest.is_empty() || String::from_utf8_lossy(&rest).starts_with("HTTP/1.1 408"),
        "{}",
        String::from_utf8_lossy(&rest)
    );
}

/// Issue 25's audit: a request whose physics overflow (`m1=1e308`) ran nalgebra's unbounded
/// Schur decomposition for ever inside the one engine, so the next normal tile got no answer.
/// Now every such value is refused at once naming its key, on every endpoint, and the next
/// normal tile is computed (a new t-max each time, so not from the cache) within the
/// watchdog's bound: answered at all, not hung (a 16^2 tile takes milliseconds).
#[test]
fn hostile_values_are_refused_and_the_explorer_keeps_answering() {
    let server = Server::start(&["--backend", "cpu"]);
    let hostile = [
        ("/tile/0/0/0.png?size=16&m1=1e308", "m1"),
        ("/tile/0/0/0.png?size=16&l1=1e155", "l1"),
        ("/tile/0/0/0.png?size=16&m2=1e300", "m2"),
        ("/tile/0/0/0.png?size=16&g=1e308", "g"),
        ("/tile/0/0/0.png?size=16&damping=1e308", "damping"),
        ("/api/point?px=1&py=1&pixel=0.01&m1=1e308", "m1"),
        ("/api/range?m1=1e308", "m1"),
        (
            "/api/save?x_min=0&x_max=1&y_min=0&y_max=1&width=16&m1=1e308",
            "m1",
        ),
        ("/api/trajectory?px=1&py=1&m1=1e308", "m1"),
    ];
    for (k, (path, key)) in hostile.iter().enumerate() {
        let sent = Instant::now();
        server.refuses(path, key);
        let refused = sent.elapsed();
        let sent = Instant::now();
        let (status, _, _) = server.get(&format!(
            "/tile/0/0/0.png?size=16&t_max={}",
            1.0 + 0.1 * k as f64
        ));
        let answered = sent.elapsed();
        assert_eq!(status, 200, "the tile after {path}");
        // A watchdog's bound, not a speed target: a hung engine never answers.
        assert!(
            refused < Duration::from_secs(10) && answered < Duration::from_secs(10),
            "{path}: refused in {refused:?}, the next tile in {answered:?}"
        );
        eprintln!("{path}: refused in {refused:?}, the next tile in {answered:?}");
    }
}

/// Issue 25's smaller server findings: a repeated key is refused naming it (not one value
/// taken silently), a too-narrow clicked pixel names `pixel` (not `theta1`), and a request
/// head of 200 kB is answered 431 while the server goes on answering.
#[test]
fn heads_and_keys_are_bounded() {
    let server = Server::start(&["--backend", "cpu"]);
    server.refuses("/tile/0/0/0.png?size=16&size=512", "size");
    server.refuses("/api/point?px=1&py=1&pixel=1e-16", "pixel");
    // A pixel wider than the plane reaches past -pi:pi: the pixel's size is at fault, not
    // the point (issue 35).
    server.refuses("/api/point?px=1&py=1&pixel=10", "pixel");
    server.refuses("/api/point?px=1&py=1&pixel=0.01&pixel_y=10", "pixel_y");
    server.refuses("/api/point?px=4&py=1&pixel=0.01", "px");
    let address = server.url.trim_start_matches("http://").to_string();
    let mut stream = std::net::TcpStream::connect(&address).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let head = format!(
        "GET /api/info HTTP/1.1\r\nHost: {address}\r\nX-Big: {}\r\n\r\n",
        "x".repeat(200_000)
    );
    // The server may close the connection before all 200 kB are written: that is fine.
    let _ = std::io::Write::write_all(&mut stream, head.as_bytes());
    let mut answer = String::new();
    let _ = std::io::Read::read_to_string(&mut stream, &mut answer);
    assert!(
        answer.starts_with("HTTP/1.1 431"),
        "{:?}",
        &answer[..answer.len().min(80)]
    );
    let (status, _, _) = server.get("/api/info");
    assert_eq!(status, 200);
}

/// Issue 25: every query key of every endpoint with extreme values (1e+-300, 1e308, -0, a
/// subnormal, infinities, NaN, a huge whole number): each answered within 10 s (a watchdog's
/// bound, not a speed target), 200 or a 400 naming the key it was given for, never a server
/// error; then a normal tile still comes.
#[test]
fn extreme_values_of_every_query_key_are_answered_or_refused_naming_it() {
    let server = Server::start(&["--backend", "cpu"]);
    let physics = ["t_max", "dt", "m1", "m2", "l1", "l2", "g", "damping"];
    let endpoints: [(&str, &[&str]); 8] = [
        (
            "/tile/0/0/0.png?size=16&x_min=-1&x_max=2&y_min=0&y_max=1&omega1=0.5",
            &[
                "size", "x_min", "x_max", "y_min", "y_max", "omega1", "omega2",
            ],
        ),
        (
            "/tile/0/0/0.png?size=16&x=m2/m1&y=omega1&x_min=0.5&x_max=2&y_min=-3&y_max=3&theta1=1",
            &[
                "x_min", "x_max", "y_min", "y_max", "theta1", "theta2", "omega2",
            ],
        ),
        ("/tile/0/0/0.png?size=16&kind=ftle&lo=0&hi=1", &["lo", "hi"]),
        (
            "/api/point?px=1&py=1&pixel=0.01&pixel_y=0.02",
            &["px", "py", "pixel", "pixel_y"],
        ),
        ("/api/trajectory?x=l2/l1&px=1.5&py=1", &["px", "py"]),
        ("/api/range?kind=ftle&t_max=2", &[]),
        (
            "/api/save?x_min=0&x_max=1&y_min=0&y_max=1&width=16",
            &["x_min", "x_max", "y_min", "y_max", "width"],
        ),
        ("/api/legend?kind=ftle&lo=0&hi=1", &["lo", "hi"]),
    ];
    let values = [
        "1e300",
        "-1e300",
        "1e308",
        "1e-300",
        "-0",
        "5e-324",
        "inf",
        "-inf",
        "nan",
        "4294967296",
        "-1",
    ];
    let (mut answered, mut refused, mut failures) = (0, 0, Vec::new());
    let mut slowest = (Duration::ZERO, String::new());
    for (base, own) in endpoints {
        let (path, query) = base.split_once('?').unwrap();
        let keys = own.iter().chain(if path == "/api/legend" {
            &[][..]
        } else {
            &physics[..]
        });
        for key in keys {
            for value in values {
                let mut pairs: Vec<String> = query
                    .split('&')
                    .filter(|p| p.split('=').next() != Some(*key))
                    .map(String::from)
                    .collect();
                pairs.push(format!("{key}={value}"));
                let url = format!("{path}?{}", pairs.join("&"));
                let sent = Instant::now();
                let (status, _, body) = server.get(&url);
                let took = sent.elapsed();
                if took > slowest.0 {
                    slowest = (took, url.clone());
                }
                let body = String::from_utf8_lossy(&body);
                match status {
                    200 => answered += 1,
                    400 if body.starts_with(&format!("invalid value for {key}:")) => refused += 1,
                    // A region's end whose physics is refused: the message names its axis
                    // and the value (the end is not known, the plane being checked whole).
                    400 if matches!(*key, "x_min" | "x_max" | "y_min" | "y_max")
                        && body.starts_with(&format!("invalid value for {}:", &key[..1])) =>
                    {
                        refused += 1
                    }
                    // Physics the step cannot follow: the refusal names the step to change.
                    400 if physics.contains(key)
                        && body.starts_with("invalid value for dt:")
                        && body.contains("unstable") =>
                    {
                        refused += 1
                    }
                    _ => failures.push(format!("{url}: {status} {body}")),
                }
                if took > Duration::from_secs(10) {
                    failures.push(format!("{url}: answered in {took:?}"));
                }
            }
        }
    }
    eprintln!(
        "{answered} answered, {refused} refused naming their key, slowest {:?} ({})",
        slowest.0, slowest.1
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let (status, _, _) = server.get("/tile/0/0/0.png?size=16&t_max=3.3");
    assert_eq!(status, 200, "a normal tile after the extremes");
}

/// A stored map of every kind in the kinds' table is named in /api/info as the page's menu
/// names it (a flip-kind store was named "flipkind", which no menu entry matches, so the
/// page removed every entry but the verdict).
#[test]
fn every_kind_of_store_is_named_as_the_menu_names_it() {
    let dir = tempfile::tempdir().unwrap();
    for (k, (args, name)) in [
        (vec!["flip"], "flip"),
        (vec!["flip", "--colour-by", "kind"], "flip-kind"),
        (vec!["lyapunov"], "ftle"),
    ]
    .into_iter()
    .enumerate()
    {
        let store = dir.path().join(format!("m{k}.zarr"));
        chaoscope()
            .args(args)
            .args(["--size", "32", "--t-max", "1", "--backend", "cpu", "--data"])
            .arg(&store)
            .assert()
            .success();
        let server = Server::start(&["--backend", "cpu", "--store", store.to_str().unwrap()]);
        let (status, _, body) = server.get("/api/info");
        assert_eq!(status, 200);
        let info: serde_json::Value = serde_json::from_slice(&body).unwrap();
        assert_eq!(info["store"]["kind"], name);
        assert!(
            info["kinds"]
                .as_array()
                .unwrap()
                .iter()
                .any(|k| k["name"] == name),
            "{info}"
        );
    }
}

/// A divergence tile is planned as the commands plan a map: on the GPU an f32 kernel refuses
/// a DP54 tolerance below its floor (its error estimate would be round-off), naming the key
/// and the explorer's own spelling of the way out; in f64 the same tolerance runs, and on
/// the CPU (f64 whatever is asked) so does f32's. `chaoscope lyapunov` refuses it alike.
#[test]
fn a_divergence_tile_refuses_an_f32_tolerance_below_the_floor_as_the_cli_does() {
    if gpu().is_none() {
        return;
    }
    let tight = "kind=ftle&integrator=dp54&rtol=1e-9&size=16&t_max=0.5";
    let server = Server::start(&["--backend", "gpu"]);
    let (status, _, body) = server.get(&format!("/tile/0/0/0.png?{tight}&precision=f32"));
    let body = String::from_utf8_lossy(&body);
    assert_eq!(status, 400, "{body}");
    assert!(body.starts_with("invalid value for rtol:"), "{body}");
    assert!(body.contains("precision=f64"), "{body}");
    let (status, ran, body) = server.get(&format!("/tile/0/0/0.png?{tight}&precision=f64"));
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    assert_eq!(ran.as_deref(), Some("f64"));
    drop(server);
    let cpu = Server::start(&["--backend", "cpu"]);
    let (status, ran, body) = cpu.get(&format!("/tile/0/0/0.png?{tight}&precision=f32"));
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    assert_eq!(ran.as_deref(), Some("f64"));
    let dir = tempfile::tempdir().unwrap();
    let out = chaoscope()
        .args("lyapunov --size 16 --t-max 0.5 --integrator dp54".split(' '))
        .args("--rtol 1e-9 --precision f32 --backend gpu --output".split(' '))
        .arg(dir.path().join("never.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--rtol") && stderr.contains("--precision f64"),
        "{stderr}"
    );
    assert!(
        !dir.path().join("never.png").exists(),
        "a refused map writes nothing"
    );
}
