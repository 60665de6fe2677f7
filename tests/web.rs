//! `chaoscope web`: the static explorer's files are the engine's own (its kernel, the layout
//! of its params, each pendulum's uploaded bytes, the colours), and in headless Chromium, on
//! its software WebGPU adapter, the page's maps equal the command line's f32 maps.

mod common;

use std::io::{BufRead, BufReader};
use std::mem::size_of;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use chaoscope::gpu::layout::{GpuIndicatorSlot, GpuLyapunovSlot, GpuParams};
use chaoscope::gpu::shaders::{Kernel, source};
use chaoscope::model::Params;
use chaoscope::params::Preset;
use chaoscope::render::{Colormap, flip_table};
use chaoscope::spec::{Axis, Grid, MapKind, Precision, Var};
use common::{browser_report, browser_tools, chaoscope, gpu, read_npy};

/// The site made by `chaoscope web` in `dir`, and its manifest.
fn site(dir: &Path) -> serde_json::Value {
    chaoscope()
        .args(["web", "--output"])
        .arg(dir)
        .assert()
        .success();
    serde_json::from_slice(&std::fs::read(dir.join("manifest.json")).unwrap()).unwrap()
}

#[test]
fn the_site_is_the_engines_own_and_small() {
    let dir = tempfile::tempdir().unwrap();
    let m = site(dir.path());
    // The bound: a folder any static host takes.
    let bytes: u64 = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    assert!(bytes < 2_000_000, "{bytes} bytes");
    // The page's kernels are the engine's, as assembled, and each pixel's slot is the size
    // of the engine's mirror.
    for (name, kernel, slot) in [
        ("flip_time", Kernel::FlipTime, 16),
        ("lyapunov", Kernel::Lyapunov, size_of::<GpuLyapunovSlot>()),
        (
            "indicators",
            Kernel::Indicators,
            size_of::<GpuIndicatorSlot>(),
        ),
    ] {
        let k = &m["kernels"][name];
        assert_eq!(
            std::fs::read_to_string(dir.path().join(k["file"].as_str().unwrap())).unwrap(),
            source(kernel, Precision::F32),
            "{name}"
        );
        assert_eq!(
            k["bindings"][1]["stride"].as_u64(),
            Some(slot as u64),
            "{name}"
        );
    }
    let k = &m["kernels"]["flip_time"];
    // Every field the page writes sits where the engine's mirror has it.
    let fields = &k["params"]["fields"];
    macro_rules! offsets {
        ($($f:ident),*) => {$(
            assert_eq!(
                fields[stringify!($f)]["offset"].as_u64(),
                Some(std::mem::offset_of!(GpuParams, $f) as u64),
                stringify!($f)
            );
        )*};
    }
    offsets!(
        dt,
        x_mid,
        x_half_step,
        y_mid,
        y_half_step,
        theta1,
        omega1,
        theta2,
        omega2,
        width,
        height,
        row0,
        rows,
        step0,
        steps,
        count,
        x_var,
        y_var,
        t_max
    );
    assert!(k["params"]["size"].as_u64().unwrap() >= std::mem::size_of::<GpuParams>() as u64);
    // Each pendulum's params are the bytes the engine uploads.
    let words = |p: &Params| -> Vec<u64> {
        bytemuck::cast_slice::<u8, u32>(bytemuck::bytes_of(&GpuParams::new(p, 0.01)))
            .iter()
            .map(|&w| w as u64)
            .collect()
    };
    for (i, p) in [Params::default(), Preset::Lab.params()].iter().enumerate() {
        let given: Vec<u64> = m["pendulums"][i]["params"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_u64().unwrap())
            .collect();
        assert_eq!(given, words(p), "pendulum {i}");
    }
    // The page's bounds on a run are the library's, and its longest run is one the engine
    // takes (within MAX_STEPS).
    assert_eq!(
        m["bounds"]["t_max"],
        serde_json::json!(chaoscope::web::PAGE_T_MAX)
    );
    assert_eq!(
        m["bounds"]["dt"],
        serde_json::json!(chaoscope::web::PAGE_DT)
    );
    let longest = chaoscope::spec::Stepping {
        t_max: chaoscope::web::PAGE_T_MAX[1],
        dt: chaoscope::web::PAGE_DT[0],
    };
    chaoscope::spec::validate_stepping(&longest).unwrap();
    let hex: String = flip_table(Colormap::Inferno)
        .iter()
        .map(|[r, g, b]| format!("{r:02x}{g:02x}{b:02x}"))
        .collect();
    assert_eq!(m["colours"]["inferno"].as_str(), Some(hex.as_str()));
}

/// A site written by `chaoscope web` into a new folder (kept while the test holds it), and
/// served: the folder, the site's root in it, its manifest, its server.
fn served() -> (tempfile::TempDir, PathBuf, serde_json::Value, StaticServer) {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("site");
    let manifest = site(&root);
    let server = StaticServer::start(&root);
    (dir, root, manifest, server)
}

/// `python3 -m http.server` on a free port over `dir`, stopped when dropped.
struct StaticServer {
    child: Child,
    url: String,
}

impl StaticServer {
    fn start(dir: &Path) -> Self {
        let mut child = Command::new("python3")
            .args(["-u", "-m", "http.server", "--bind", "127.0.0.1", "0", "-d"])
            .arg(dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // "Serving HTTP on 127.0.0.1 port 40123 (http://127.0.0.1:40123/) ..."
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let port = line
            .split_whitespace()
            .skip_while(|w| *w != "port")
            .nth(1)
            .unwrap_or_else(|| panic!("no port in {line:?}"));
        StaticServer {
            child,
            url: format!("http://127.0.0.1:{port}/"),
        }
    }
}

impl Drop for StaticServer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The share of pixels on which two maps agree: both finite within `tol` of each other (flip
/// times in s, exponents in 1/s), or both never flipped, or both NaN.
fn agreement(a: &[f32], b: &[f32], tol: f32) -> f64 {
    let same = a
        .iter()
        .zip(b)
        .filter(|&(&x, &y)| match (x.is_finite(), y.is_finite()) {
            (true, true) => (x - y).abs() <= tol,
            _ => x.is_nan() == y.is_nan() && x.is_finite() == y.is_finite(),
        })
        .count();
    same as f64 / a.len() as f64
}

/// Runs a command line the page gave (its words after `chaoscope`) on the command line's f32
/// GPU path, writing its picture to `png` and, with `npy`, its map.
fn run_on_the_command_line(words: &[&str], png: &Path, npy: Option<&Path>) {
    let mut cli = chaoscope();
    cli.args(words)
        .args(["--backend", "gpu", "--precision", "f32", "--output"])
        .arg(png);
    if let Some(npy) = npy {
        cli.arg("--data").arg(npy);
    }
    cli.assert().success();
}

fn read_f32(path: &Path) -> Vec<f32> {
    bytemuck::pod_collect_to_vec(&std::fs::read(path).unwrap())
}

#[test]
fn the_page_computes_the_command_lines_f32_maps_in_chromium() {
    if gpu().is_none() {
        return;
    }
    let Some(python) = browser_tools() else {
        return;
    };
    let (dir, _, _, server) = served();
    let turn = std::f64::consts::TAU;
    // The whole plane over 20 s (chaos grows any difference in the arithmetic), a deep view
    // into the boundary, the lab's pendulum (its losses compiled in), the (theta1, omega1)
    // plane, parameter planes (the mass ratio; m1, in the engine's mass scale, of the lab's
    // pendulum), the FTLE (of the lab's pendulum too: the tangent's losses), MEGNO and the FLI.
    let mut views = serde_json::json!([
        {"name": "whole", "width": 128, "height": 128,
         "view": {"cx": 0, "cy": 0, "w": turn, "t_max": 20, "dt": 0.01}},
        {"name": "deep", "width": 96, "height": 64,
         "view": {"cx": 1.9, "cy": 2.6, "w": 0.004, "t_max": 10, "dt": 0.01}},
        {"name": "lab", "width": 64, "height": 64,
         "view": {"cx": 0, "cy": 0, "w": turn, "t_max": 10, "dt": 0.005, "pendulum": 1}},
        {"name": "omega", "width": 64, "height": 64,
         "view": {"x": "theta1", "y": "omega1", "cx": 0.5, "cy": 0, "w": 5, "t_max": 10,
                  "dt": 0.01}},
        {"name": "ratio", "width": 64, "height": 48,
         "view": {"x": "theta1", "y": "m2/m1", "cx": 0, "cy": 1.55, "w": turn, "h": 2.9,
                  "t_max": 10, "dt": 0.01}},
        {"name": "mass", "width": 48, "height": 64,
         "view": {"x": "m1", "y": "theta2", "cx": 1.05, "cy": 0, "w": 1.9, "h": turn,
                  "t_max": 10, "dt": 0.01, "pendulum": 1}},
        {"name": "ftle", "width": 64, "height": 64,
         "view": {"kind": "ftle", "cx": 0, "cy": 0, "w": turn, "t_max": 10, "dt": 0.01}},
        {"name": "megno", "width": 64, "height": 48,
         "view": {"kind": "megno", "cx": 1, "cy": 1, "w": 2, "t_max": 10, "dt": 0.01}},
        {"name": "lab_ftle", "width": 48, "height": 48,
         "view": {"kind": "ftle", "cx": 0, "cy": 0, "w": turn, "t_max": 10, "dt": 0.005,
                  "pendulum": 1}},
        {"name": "fli", "width": 48, "height": 48,
         "view": {"kind": "fli", "cx": 0, "cy": 0, "w": turn, "t_max": 5, "dt": 0.01}},
    ]);
    // Every other indicator of the kinds' table, each on a small grid.
    for kind in [
        "sali",
        "gali",
        "alignment-time",
        "exponent",
        "exponent-sum",
        "descriptor",
        "ofli",
        "rli",
    ] {
        views.as_array_mut().unwrap().push(serde_json::json!({
            "name": kind, "width": 32, "height": 32,
            "view": {"kind": kind, "cx": 0.5, "cy": 0.5, "w": 3, "t_max": 5, "dt": 0.01}}));
    }
    // Indicators at settings other than their defaults, as the page's menu offers them
    // (src/web.rs `variants`, whose order the manifest keeps).
    for (kind, options) in [
        ("exponent", "exponent 3"),
        ("gali", "gali 2, threshold 1e-4"),
        ("descriptor", "ld-p 2"),
    ] {
        let kind = MapKind::from_short(kind).unwrap();
        let setting = setting_of(kind, options);
        views.as_array_mut().unwrap().push(serde_json::json!({
            "name": format!("{}-{setting}", kind.short()), "width": 32, "height": 32,
            "view": {"kind": kind.short(), "setting": setting, "cx": 0.5, "cy": 0.5, "w": 3,
                     "t_max": 5, "dt": 0.01}}));
    }
    // The verdict in f32: the same map at half and a quarter of the step.
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "judged", "width": 64, "height": 64, "times": false, "verdict": true,
        "view": {"cx": 0, "cy": 0, "w": turn, "t_max": 20, "dt": 0.01}}));
    // A click's swing: the engine's trajectory kernel, every second step kept at dt 0.01
    // (about 60 a second).
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "swing", "width": 64, "height": 64, "times": false,
        "swing": {"theta1": 1.0, "theta2": 2.0}, "view": {"t_max": 2, "dt": 0.01}}));
    // A plane of two parameters from a start the view fixes (both arms at 2 rad).
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "ratios", "width": 48, "height": 48,
        "view": {"x": "m2/m1", "y": "l2/l1", "cx": 1.5, "cy": 1.5, "w": 2, "h": 2,
                 "theta1": 2, "theta2": 2, "t_max": 5, "dt": 0.01}}));
    // A click on a plane of two parameters (both ratios: each multiplies a value the other
    // does not set): the pixel's own pendulum swings, and the page's command runs it.
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "swing_plane", "width": 64, "height": 64, "times": false,
        "swing": {"theta1": 0.5, "theta2": 0.5}, "at": {"x": 2.5, "y": 0.7},
        "view": {"x": "m2/m1", "y": "l2/l1", "cx": 2, "cy": 1, "w": 2, "h": 1,
                 "t_max": 2, "dt": 0.01}}));
    // The page's rule for a view too deep for f32 is the engine's (`Grid::needs_f64`): the
    // widths around the switch on a 512-pixel grid at a point of the boundary.
    let widths = [1e-2, 3e-3, 2e-3, 1.9e-3, 1.5e-3, 1e-3, 1e-4];
    for w in widths {
        views.as_array_mut().unwrap().push(serde_json::json!({
            "name": format!("w{w:e}"), "width": 512, "height": 512, "times": false,
            "view": {"cx": 1.9, "cy": 2.6, "w": w}}));
    }
    // A lost device (here Chromium's GPU process killed, as a GPU reset would end it): the
    // page computes its view again on a new device, and the maps it makes after are the
    // command line's still.
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "after_loss", "width": 64, "height": 64, "lose_device": true,
        "view": {"cx": 1, "cy": 0.5, "w": 2, "t_max": 10, "dt": 0.01}}));
    // A view panned past the turn: the page keeps the angles within -pi:pi, as the command
    // line does (the generic check below runs its command); a parameter plane reaching below
    // its range (Var::limits) is refused in words.
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "panned", "width": 48, "height": 48,
        "view": {"cx": 3, "cy": -2.5, "w": 4, "t_max": 5, "dt": 0.01}}));
    views.as_array_mut().unwrap().push(serde_json::json!({
        "name": "negative", "width": 16, "height": 16, "refused": true, "times": false,
        "view": {"x": "theta1", "y": "m2/m1", "cx": 0, "cy": 0, "w": 2, "h": 2, "t_max": 1}}));
    let shot = dir.path().join("page.png");
    let views_json = views.to_string();
    // The first view in viridis: the saved PNG's command must draw it so.
    let first = format!("{}#t_max=10&colours=viridis", server.url);
    let report = browser_report(
        &python,
        "web.py",
        &[
            first.as_ref(),
            shot.as_ref(),
            dir.path().as_ref(),
            views_json.as_ref(),
        ],
    );
    assert!(report["error"].is_null(), "{report}");
    assert!(
        report["adapter"].as_str().unwrap().contains("swiftshader"),
        "{report}"
    );
    assert_eq!(report["gpu_processes_killed"], 1, "{report}");
    assert_eq!(report["lost"], 1, "{report}");
    let refusal = report["views"]["negative"]["refused"]
        .as_str()
        .unwrap_or_default();
    assert!(
        refusal.contains("m2/m1 from -1.0000 to 1.0000 leaves its range (1e-30 to 1e+30)"),
        "{report}"
    );

    // The screenshot shows a map: many colours, not a blank page or an error.
    let shot = chaoscope::render::read_png(&shot).unwrap();
    let colours: std::collections::HashSet<&[u8]> = shot.rgb.chunks(3).collect();
    assert!(colours.len() > 200, "{} colours", colours.len());

    // "Save PNG": the map shown, carrying the command line's provenance chunks; its command
    // run on the command line draws the same picture.
    let file = std::fs::File::open(dir.path().join("shown.png")).unwrap();
    let saved = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let text: std::collections::HashMap<String, String> = saved
        .info()
        .uncompressed_latin1_text
        .iter()
        .map(|c| (c.keyword.clone(), c.text.clone()))
        .collect();
    let (w, h) = (saved.info().width, saved.info().height);
    assert_eq!(text["chaoscope:backend"], "gpu", "{text:?}");
    assert!(
        text["chaoscope:adapter"].contains("swiftshader"),
        "{text:?}"
    );
    let shown = &text["chaoscope:command"];
    assert!(
        shown.starts_with(&format!("chaoscope flip --size {w}x{h} "))
            && shown.contains("--colormap viridis"),
        "{shown}"
    );
    let cli_png = dir.path().join("shown_cli.png");
    let words: Vec<&str> = shown.split_whitespace().skip(1).collect();
    run_on_the_command_line(&words, &cli_png, None);
    let cli = chaoscope::render::read_png(&cli_png).unwrap();
    let mut reader = saved;
    let mut rgba = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut rgba).unwrap();
    let same = rgba
        .chunks(4)
        .zip(cli.rgb.chunks(3))
        .filter(|(a, b)| a[..3] == b[..])
        .count() as f64
        / (w * h) as f64;
    eprintln!("saved PNG: {same:.5} of its pixels the command line's");
    // The same flip times (all within 1e-3 s above) through the same colour table: a pixel
    // differs only where an ulp of a time crosses a colour's edge.
    assert!(same >= 0.999, "{same}");

    for w in widths {
        let grid = Grid {
            x: Axis::new(Var::Theta1, 1.9 - w / 2.0, 1.9 + w / 2.0),
            y: Axis::new(Var::Theta2, 2.6 - w / 2.0, 2.6 + w / 2.0),
            ..Grid::square(512)
        };
        let page = &report["views"][format!("w{w:e}")]["resolves"];
        assert_eq!(page.as_bool(), Some(!grid.needs_f64()), "width {w}");
    }
    // The page's verdict is the engine's rule on a GPU without f64 (src/plan.rs): the command
    // line's f32 maps at dt, dt/2 and dt/4, each agreeing with the next within the flip
    // time's vouching tolerance.
    let command = report["views"]["judged"]["command"].as_str().unwrap();
    let at = |dt: &str| -> Vec<f32> {
        let npy = dir.path().join(format!("judged_{dt}.npy"));
        let mut words: Vec<&str> = command.split_whitespace().skip(1).collect();
        let k = words.iter().position(|w| *w == "--dt").unwrap();
        words[k + 1] = dt;
        run_on_the_command_line(&words, &dir.path().join("judged.png"), Some(&npy));
        read_npy(&npy).1
    };
    let (map, half, quarter) = (at("0.01"), at("0.005"), at("0.0025"));
    let vouch = chaoscope::quantity::FLIP_TIME.vouch;
    let page = std::fs::read(dir.path().join("judged.mask")).unwrap();
    let same = (0..map.len())
        .filter(|&i| {
            let resolved = vouch.agrees(map[i], half[i]) && vouch.agrees(half[i], quarter[i]);
            resolved == (page[i] == 1)
        })
        .count() as f64
        / map.len() as f64;
    let resolved = page.iter().filter(|&&m| m == 1).count() as f64 / page.len() as f64;
    eprintln!("verdict: {resolved:.4} resolved, {same:.5} as the command line's f32 maps judge");
    // The maps differ by ulps of a flip time at most: a pixel's verdict turns only where the
    // runs part by the tolerance to within those ulps.
    assert!(same >= 0.999, "{same}");
    let swing = &report["views"]["swing"]["swing"];
    assert_eq!(swing["seconds"].as_f64(), Some(0.02), "{swing}");
    let rows = cli_trajectory("trajectory --theta1 1 --theta2 2 --t-max 2 --dt 0.01");
    // The same f32 kernel from the same start: equal but for the start's cos and sin, which
    // the page's JavaScript and the engine's Rust may round an ulp apart.
    let worst = departure(&numbers(&swing["states"]), &rows);
    assert!(worst <= 1e-4, "the page's swing departs by {worst}");
    // The parameter plane's pixel: its arms drawn at its own lengths, and its run the one its
    // command line computes. The page's kernel forms the pixel's coefficients in f32 from its
    // parameters where the engine rounds them once from f64: a few ulps (1e-7 relative), grown
    // over 100 steps of a regular swing (0.5 rad) by far less than the 1e-4 asked.
    let plane = &report["views"]["swing_plane"]["swing"];
    assert_eq!(numbers(&plane["arms"]), [1.0, 0.7], "{}", plane["command"]);
    let command = plane["command"].as_str().unwrap();
    assert!(
        command.contains("--at m2/m1=2.5 --at l2/l1=0.7"),
        "{command}"
    );
    let rows = cli_trajectory(command.strip_prefix("chaoscope ").unwrap());
    let worst = departure(&numbers(&plane["states"]), &rows);
    assert!(worst <= 1e-4, "the page's run departs by {worst}");
    for v in views
        .as_array()
        .unwrap()
        .iter()
        .filter(|v| v["times"].is_null())
    {
        let name = v["name"].as_str().unwrap();
        let command = report["views"][name]["command"].as_str().unwrap();
        // The view's own command line, run on the command line's f32 GPU path.
        let npy: PathBuf = dir.path().join(format!("{name}.npy"));
        let words: Vec<&str> = command.split_whitespace().skip(1).collect();
        let png = dir.path().join(format!("{name}.png"));
        run_on_the_command_line(&words, &png, Some(&npy));
        let (shape, cli) = read_npy(&npy);
        let page = read_f32(&dir.path().join(format!("{name}.f32")));
        let (w, h) = (v["width"].as_u64().unwrap(), v["height"].as_u64().unwrap());
        assert_eq!(shape, [h, w], "{name}");
        // The RLI is the difference of two orbits' exponents 1e-4 apart: each carries the f32
        // round-off of its 500 steps (about 1e-6 /s), some percent of an RLI near 1e-4, so
        // its log10 may part by a few hundredths where the maps' rounding differs.
        let tol = if name == "rli" { 0.05 } else { 1e-3 };
        let agree = agreement(&cli, &page, tol);
        let exact = agreement(&cli, &page, 0.0);
        eprintln!("{name}: {agree:.5} within {tol} (s, 1/s) or the same class, {exact:.5} exactly");
        // Both run the same WGSL over the same f32 params. The two software GPUs round
        // every step of the motion alike (RK4's 6 is data: Params `six`; the bearing
        // friction's sums are explicit fmas) and differ at most in an ulp or two of where a
        // flip falls in its step: the 1e-3 s (and 1e-3 /s for the FTLE) holds
        // everywhere, the lab's pendulum with its losses included.
        assert!(agree >= 0.999, "{name}: {agree}");
        // The colours' range the page drew is the measure's rule on the command line's map.
        let kind = v["view"]["kind"].as_str().unwrap_or("flip");
        let setting = v["view"]["setting"].as_u64().unwrap_or(0) as usize;
        if let Some(i) = MapKind::from_short(kind)
            .and_then(|k| chaoscope::web::variants(k).get(setting).copied())
        {
            let t_max = v["view"]["t_max"].as_f64().unwrap();
            let field = chaoscope::field::Field {
                width: w as u32,
                height: h as u32,
                data: cli,
            };
            let (lo, hi) = i.measure().default_range(i, t_max, &field);
            let page = &report["views"][name]["range"];
            for (p, r) in [(&page[0], lo), (&page[1], hi)] {
                let p = p.as_f64().unwrap();
                // Quantiles of maps equal within 1e-3 at 99.9 % of their pixels.
                assert!(
                    (p - r as f64).abs() <= 2e-3 * (1.0 + r.abs() as f64),
                    "{name}: {page} against ({lo}, {hi})"
                );
            }
        }
        assert!(
            report["views"][name]["resolves"].as_bool().unwrap(),
            "{name}"
        );
    }
}

/// A JSON array of numbers.
fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// `chaoscope WORDS` (a trajectory) on the GPU in f32, a row kept every 0.02 s: its rows
/// (t, then the state).
fn cli_trajectory(words: &str) -> Vec<Vec<f64>> {
    let out = chaoscope()
        .args(words.split_whitespace())
        .args("--every 0.02 --backend gpu --precision f32".split(' '))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{words}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('t'))
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

/// The largest difference between a page's kept states (four a row, flat) and `rows`' (t,
/// then the state), one kept state for each row.
fn departure(states: &[f64], rows: &[Vec<f64>]) -> f64 {
    assert_eq!(states.len(), 4 * rows.len(), "states kept");
    rows.iter()
        .enumerate()
        .flat_map(|(k, row)| (0..4).map(move |j| (states[4 * k + j] - row[1 + j]).abs()))
        .fold(0.0, f64::max)
}

/// The index of `kind`'s setting whose options read `options` in the page's menu.
fn setting_of(kind: MapKind, options: &str) -> usize {
    chaoscope::web::variants(kind)
        .iter()
        .position(|&i| chaoscope::web::options_label(i) == options)
        .unwrap_or_else(|| panic!("{options}: no such setting of {}", kind.short()))
}

/// `web --params FILE --name NAME`: a class's own pendulum under its own name, offered first;
/// a name out of bounds, or with no pendulum to name, is refused naming `--name`.
#[test]
fn a_pendulum_of_ones_own_goes_by_its_name() {
    use predicates::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let lab = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/lab.toml");
    chaoscope()
        .args(["web", "--params"])
        .arg(&lab)
        .args(["--name", "our pendulum", "--output"])
        .arg(dir.path().join("ours"))
        .assert()
        .success();
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("ours/manifest.json")).unwrap())
            .unwrap();
    assert_eq!(m["pendulums"][0]["name"], "our pendulum");
    assert_eq!(m["pendulums"].as_array().unwrap().len(), 3);
    for bad in [
        &["--params", lab.to_str().unwrap(), "--name", ""][..],
        &["--name", "ours"],
    ] {
        chaoscope()
            .arg("web")
            .args(bad)
            .arg("--output")
            .arg(dir.path().join("refused"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains("--name"));
        assert!(!dir.path().join("refused").exists());
    }
}

/// `web --output` writes into a new or empty folder, or over a site it wrote before; a folder
/// of the user's files is refused naming them, with nothing written (its index.html was
/// replaced before), and a link to nothing is named as such.
#[test]
fn the_site_goes_only_where_it_replaces_nothing_of_the_users() {
    use predicates::prelude::*;
    let dir = tempfile::tempdir().unwrap();
    let again = dir.path().join("site");
    site(&again);
    site(&again);
    let notes = dir.path().join("notes");
    std::fs::create_dir(&notes).unwrap();
    std::fs::write(notes.join("index.html"), "my page").unwrap();
    std::fs::write(notes.join("todo.txt"), "").unwrap();
    chaoscope()
        .args(["web", "--output"])
        .arg(&notes)
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("--output")
                .and(predicate::str::contains("index.html, todo.txt")),
        );
    assert_eq!(
        std::fs::read_to_string(notes.join("index.html")).unwrap(),
        "my page"
    );
    assert!(!notes.join("manifest.json").exists());
    let link = dir.path().join("gone");
    std::os::unix::fs::symlink(dir.path().join("nowhere"), &link).unwrap();
    chaoscope()
        .args(["web", "--output"])
        .arg(&link)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("dangling"));
}

/// A setting of a link and the rule the page's controls hold it to (`chaoscope::web`'s
/// bounds, the manifest's names): written here apart from the page's script, so the two
/// agreeing means something.
fn link_value_ok(manifest: &serde_json::Value, key: &str, text: &str, number: Option<f64>) -> bool {
    let names = |list: &str, field: Option<&str>| -> Vec<String> {
        match field {
            Some(f) => manifest[list]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v[f].as_str().unwrap().to_string())
                .collect(),
            None => manifest[list]
                .as_object()
                .unwrap()
                .keys()
                .cloned()
                .collect(),
        }
    };
    let within = |[lo, hi]: [f64; 2]| number.is_some_and(|x| (lo..=hi).contains(&x));
    let pendulums = manifest["pendulums"].as_array().unwrap().len() as f64;
    match key {
        "t_max" => within(chaoscope::web::PAGE_T_MAX),
        "dt" => within(chaoscope::web::PAGE_DT),
        "cx" | "cy" => number.is_some_and(f64::is_finite),
        "w" | "h" => number.is_some_and(|x| x.is_finite() && x > 0.0),
        "pendulum" => number.is_some_and(|x| x.fract() == 0.0 && (0.0..pendulums).contains(&x)),
        "x" | "y" => names("vars", Some("name")).iter().any(|n| n == text),
        "kind" => names("kinds", Some("name")).iter().any(|n| n == text),
        "colours" => names("colours", None).iter().any(|n| n == text),
        "verdict" => text == "0" || text == "1",
        // The start's fixed angles: within the turn, as an angle axis.
        "theta1" | "theta2" => within([-std::f64::consts::PI, std::f64::consts::PI]),
        _ => false,
    }
}

/// Percent-encodes every byte of `s` but letters, digits and `-._~` (so the page's
/// URLSearchParams reads back exactly `s`).
fn percent(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'a'..=b'z' | b'A'..=b'Z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

#[test]
fn a_link_is_held_to_the_controls_rules_in_chromium() {
    let Some(python) = browser_tools() else {
        return;
    };
    let (_dir, root, manifest, server) = served();
    // Values with the number JavaScript's Number() makes of them (None: NaN; the page takes
    // blank text as no number), and names: the manifest's, an Object's own members, junk.
    let numbers: &[(&str, Option<f64>)] = &[
        ("0", Some(0.0)),
        ("-5", Some(-5.0)),
        ("2", Some(2.0)),
        ("0.01", Some(0.01)),
        ("1e-300", Some(1e-300)),
        ("1e9", Some(1e9)),
        ("1e308", Some(1e308)),
        ("-1", Some(-1.0)),
        ("0.5", Some(0.5)),
        ("1", Some(1.0)),
        ("1000", Some(1000.0)),
        ("0.1", Some(0.1)),
        ("0.0001", Some(1e-4)),
        ("0.00009999", Some(9.999e-5)),
        ("1000.0001", Some(1000.0001)),
        ("NaN", None),
        ("Infinity", Some(f64::INFINITY)),
        ("-Infinity", Some(f64::NEG_INFINITY)),
        ("", None),
        (" ", None),
        ("abc", None),
        ("0x10", Some(16.0)),
        ("1e3", Some(1000.0)),
        (" 3 ", Some(3.0)),
        ("1,5", None),
        ("2.5e-3", Some(0.0025)),
        ("1.2", Some(1.2)),
    ];
    let words = [
        "theta1",
        "theta2",
        "omega1",
        "m2/m1",
        "flip",
        "ftle",
        "megno",
        "inferno",
        "viridis",
        "constructor",
        "__proto__",
        "toString",
        "hasOwnProperty",
        "1",
        "0",
        "yes",
        "<b>x</b>",
        "théta",
        "",
    ];
    let keys = [
        "t_max", "dt", "cx", "cy", "w", "h", "pendulum", "x", "y", "kind", "colours", "verdict",
        "theta1", "theta2",
    ];
    let odd_keys = [
        "constructor",
        "__proto__",
        "toString",
        "foo",
        "T_MAX",
        "t_max ",
    ];
    let numeric = |k: &str| {
        [
            "t_max", "dt", "cx", "cy", "w", "h", "pendulum", "theta1", "theta2",
        ]
        .contains(&k)
    };
    let number_of = |t: &str| {
        numbers
            .iter()
            .find(|(w, _)| *w == t)
            .map_or(t.parse().ok(), |n| n.1)
    };
    // The audit's crafted links, then seeded random ones.
    let mut links: Vec<Vec<(String, String, Option<f64>)>> = [
        "dt=0&t_max=2",
        "dt=1e-300",
        "t_max=1e9",
        "t_max=-5",
        "w=-1&h=-1",
        "colours=constructor",
        "colours=__proto__",
        "kind=toString",
        "pendulum=1e9",
        "pendulum=0.5",
        "x=constructor",
        "verdict=yes",
        "t_max=2",
        "kind=ftle&t_max=1",
        "",
        "colours=viridis&t_max=1",
        "x=theta1&y=m2/m1&t_max=1",
        "x=theta1&y=theta1&t_max=1",
        // A setting is one of its kind's, whichever the link names first.
        "kind=gali&setting=2&t_max=1",
        "setting=3&kind=exponent&t_max=1",
        "kind=gali&setting=99",
        "setting=1",
        "kind=sali&setting=0.5",
        // The start's angles where no axis sets them.
        "x=m2/m1&y=l2/l1&theta1=2&theta2=2&t_max=1",
        "theta1=4",
        "theta2=-1e9",
    ]
    .iter()
    .map(|l| {
        l.split('&')
            .filter(|p| !p.is_empty())
            .map(|p| {
                let (k, v) = p.split_once('=').unwrap();
                let n = numbers
                    .iter()
                    .find(|(t, _)| *t == v)
                    .map_or(v.parse().ok(), |n| n.1);
                (k.to_string(), v.to_string(), n)
            })
            .collect()
    })
    .collect();
    // Half the values drawn among those a control could set, so that about half the links
    // hold to the rules.
    let good = |k: &str| -> &[&str] {
        match k {
            "t_max" => &["0.5", "1", "2"],
            "dt" => &["0.005", "0.01", "0.02"],
            "cx" | "cy" => &["0", "1", "-1", "0.5"],
            "w" | "h" => &["0.5", "1", "2", "6.283185307179586"],
            "pendulum" | "verdict" => &["0", "1"],
            "x" | "y" => &["theta1", "theta2", "omega1", "m2/m1"],
            "kind" => &["flip", "ftle", "megno", "fli"],
            "colours" => &["inferno", "viridis"],
            _ => &["1"],
        }
    };
    let mut rng = fastrand::Rng::with_seed(66);
    for _ in 0..100 {
        let pairs = (0..rng.usize(1..=3))
            .map(|_| {
                let key = if rng.f64() < 0.9 {
                    keys[rng.usize(..keys.len())]
                } else {
                    odd_keys[rng.usize(..odd_keys.len())]
                };
                let text = if rng.f64() < 0.75 {
                    let pool = good(key);
                    pool[rng.usize(..pool.len())]
                } else if numeric(key) == (rng.f64() < 0.75) {
                    numbers[rng.usize(..numbers.len())].0
                } else {
                    words[rng.usize(..words.len())]
                };
                (key.to_string(), text.to_string(), number_of(text))
            })
            .collect();
        links.push(pairs);
    }
    let hashes: Vec<String> = links
        .iter()
        .map(|pairs| {
            pairs
                .iter()
                .map(|(k, v, _)| format!("{}={}", percent(k), percent(v)))
                .collect::<Vec<_>>()
                .join("&")
        })
        .collect();
    let report = browser_report(
        &python,
        "links.py",
        &[
            server.url.as_ref(),
            serde_json::to_string(&hashes).unwrap().as_ref(),
            format!("file://{}", root.join("index.html").display()).as_ref(),
        ],
    );
    // Opened from disk (the browser lets it read none of its files), the page says to serve
    // the folder instead of waiting for ever.
    let disk = report["from_disk"].as_str().unwrap();
    assert!(
        disk.contains("must be served") && disk.contains("http.server"),
        "{disk}"
    );
    let cases = report["cases"].as_array().unwrap();
    assert_eq!(cases.len(), links.len());
    let mut refused = 0;
    for (pairs, case) in links.iter().zip(cases) {
        let status = case["status"].as_str().unwrap();
        // Nothing thrown past the script, and every link settled in words within the wait.
        assert_eq!(case["errors"], serde_json::json!([]), "{case}");
        assert!(case["error"].is_null(), "{case}");
        assert!(!status.starts_with("starting"), "{case}");
        // A setting is judged against the link's kind (the last one it names that the page
        // has, else the flip time's single setting).
        let kind = pairs
            .iter()
            .rev()
            .find(|(k, v, n)| k == "kind" && link_value_ok(&manifest, k, v, *n))
            .map_or("flip", |(_, v, _)| v.as_str());
        let settings = manifest["kinds"]
            .as_array()
            .unwrap()
            .iter()
            .find(|k| k["name"] == kind)
            .and_then(|k| k["settings"].as_array())
            .map_or(1, Vec::len) as f64;
        let bad: Vec<&String> = pairs
            .iter()
            .filter(|(k, v, n)| match k.as_str() {
                "setting" => !n.is_some_and(|x| x.fract() == 0.0 && (0.0..settings).contains(&x)),
                _ => !link_value_ok(&manifest, k, v, *n),
            })
            .map(|(k, _, _)| k)
            .collect();
        let said = case["refused"].as_array().unwrap();
        if bad.is_empty() {
            assert!(said.is_empty(), "a link within the rules refused: {case}");
        } else {
            refused += 1;
            // Refused, each bad setting named, and nothing computed.
            assert!(status.contains("was not computed"), "{case}");
            assert_eq!(case["views"], 0, "{case}");
            let text = said
                .iter()
                .map(|s| s.as_str().unwrap())
                .collect::<Vec<_>>()
                .join("; ");
            for k in bad {
                assert!(text.contains(k.as_str()), "{k} not named: {case}");
            }
        }
    }
    eprintln!("{} links, {refused} refused", links.len());
    // The seeded draw holds both kinds (so each branch above was tried).
    assert!(
        refused > 30 && refused + 30 < links.len(),
        "{refused} of {}",
        links.len()
    );
}

#[test]
fn the_page_serves_a_class_on_a_phone_and_a_projector() {
    let Some(python) = browser_tools() else {
        return;
    };
    let (dir, _, _, server) = served();
    let report = browser_report(
        &python,
        "class.py",
        &[server.url.as_ref(), dir.path().as_ref()],
    );
    for (name, r) in report.as_object().unwrap() {
        let first = &r["first"];
        for step in ["first", "tapped", "changed", "copied"] {
            assert_eq!(
                r[step]["errors"],
                serde_json::json!([]),
                "{name} {step}: {r}"
            );
        }
        let width = first["inner"][0].as_f64().unwrap();
        let map = first["map"]["width"].as_f64().unwrap();
        if name == "phone" {
            // On a phone the map comes first, across (nearly) the whole width.
            assert!(map >= 0.9 * width, "{name}: map {map} px of {width}");
        }
        // The new view showed coarse before it was whole.
        let (preview, whole) = (
            first["preview"].as_f64().unwrap(),
            first["seconds"].as_f64().unwrap(),
        );
        assert!(
            preview < whole,
            "{name}: preview {preview} s, map {whole} s"
        );
        // The tapped start: marked on the map, in words, its swing in sight.
        let tapped = &r["tapped"];
        let text = tapped["clicked"].as_str().unwrap();
        assert!(
            text.contains("theta1 = ") && text.contains("flips"),
            "{name}: {text}"
        );
        let marker = &tapped["marker"];
        assert!(!marker.is_null(), "{name}: no marker");
        let inside = |outer: &serde_json::Value, inner: &serde_json::Value| {
            ["left", "top"]
                .iter()
                .all(|k| inner[k].as_f64() >= outer[k].as_f64())
                && ["right", "bottom"]
                    .iter()
                    .all(|k| inner[k].as_f64() <= outer[k].as_f64())
        };
        assert!(inside(&tapped["map"], marker), "{name}: {tapped}");
        let swing = &tapped["swing"];
        let height = first["inner"][1].as_f64().unwrap();
        assert!(
            swing["top"].as_f64().unwrap() >= 0.0 && swing["bottom"].as_f64().unwrap() <= height,
            "{name}: the swing is out of sight: {swing}"
        );
        // Its words follow the map shown.
        let changed = r["changed"]["clicked"].as_str().unwrap();
        assert!(
            changed.contains("FTLE") && !changed.contains("flips"),
            "{name}: {changed}"
        );
        // "Copy link" copies the view's address.
        let copied = &r["copied"];
        assert_eq!(copied["copied"], copied["href"], "{name}");
        assert!(
            copied["href"].as_str().unwrap().contains("kind=ftle"),
            "{name}"
        );
    }
}
