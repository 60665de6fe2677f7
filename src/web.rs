//! The explorer as a folder of static files (`chaoscope web`): a page that computes maps with
//! WebGPU on the viewer's own GPU. Nothing of the physics is written again for it: its WGSL
//! is the kernels as [`gpu::shaders::source`] assembles them for the engine (f32: WebGPU has
//! no f64), the buffers' layouts are read from that WGSL by naga (the `Params` struct's
//! members, each binding's kind), each pendulum's `Params` are the bytes the engine uploads,
//! and the colours are the render's own tables. The page's script only drives the kernels as
//! `src/gpu/flip_time.rs` does: set a tile's fields, dispatch, follow the active list, read
//! the times back.

use serde_json::{Value, json};
use wgpu::naga;

use crate::gpu::layout::{
    GpuParams, GpuPendulum, MAX_WORKGROUPS, NEVER, NONFINITE, WORKGROUP_SIZE, mass_scale,
};
use crate::gpu::shaders::{Kernel, source};
use crate::gpu::{
    LEFT_BELOW, MIN_STEPS, STALLED_BELOW, STEPS_PER_DISPATCH, STEPS_PER_INVOCATION,
    TANGENT_STEP_COST,
};
use crate::measure::{End, Indicator, IndicatorAsked, Runs};
use crate::model::Params;
use crate::quantity::Quantity;
use crate::render::{Colormap, flip_table, ftle_table, legend};
use crate::spec::{LyapunovSpec, MapKind, Precision, Var};

/// The page, its script and its style.
const PAGE: &str = include_str!("../assets/web/index.html");
const SCRIPT: &str = include_str!("../assets/web/explorer.js");
/// The engine's rules the page applies per view, shared with the served page.
const RULES: &str = include_str!("../assets/rules.js");
const STYLE: &str = include_str!("../assets/web/style.css");

/// A pendulum the page offers: its name, its parameters, and their flags in a command line
/// beside each set of parameter axes the page may show: keyed by the axes' names, sorted and
/// joined by commas ("" for a plane of the start, "g", "m1,m2/m1"), what they set left out.
#[derive(Clone, Debug, PartialEq)]
pub struct Pendulum {
    pub name: String,
    pub params: Params,
    pub flags: Vec<(String, String)>,
}

/// The sets of parameter axes a plane may have (none, one, or two that set different
/// values), each as its names sorted: the keys of [`Pendulum::flags`].
pub fn parameter_axes() -> Vec<Vec<Var>> {
    let params: Vec<Var> = Var::ALL.into_iter().filter(|v| !v.is_state()).collect();
    let mut sets = vec![vec![]];
    for (i, &a) in params.iter().enumerate() {
        sets.push(vec![a]);
        for &b in &params[i + 1..] {
            if !a.overlaps(b) {
                sets.push(vec![a, b]);
            }
        }
    }
    for set in &mut sets {
        set.sort_by_key(|v| v.name());
    }
    sets
}

/// What the site holds.
#[derive(Clone, Debug, PartialEq)]
pub struct SiteSpec {
    pub pendulums: Vec<Pendulum>,
    /// The flip map's command line with `{width}`, `{height}`, `{x_min}`, `{x_max}`,
    /// `{y_min}`, `{y_max}`, `{t_max}`, `{dt}`, `{start}` (the fixed start's angles as
    /// flags, or nothing), `{pendulum}`, `{colours}` and `{verdict}`
    /// to fill in: the page shows it for its view, the map the command line computes for the
    /// same pixels.
    pub command: String,
    /// The divergence-family maps the page offers (the kinds' table's, in its order), each
    /// with the settings of its indicator the page offers ([`variants`]: its f32 default
    /// first), each with its command line, as the flip map's.
    pub indicator_commands: Vec<(MapKind, Vec<(Indicator, String)>)>,
    /// A clicked pixel's run as a command line, with `{theta1}`, `{omega1}`, `{theta2}`,
    /// `{omega2}`, `{t_max}`, `{dt}` and `{pendulum}` to fill in.
    pub swing_command: String,
}

/// The kernels the page runs, by the name its script knows them by.
const KERNELS: [(&str, Kernel); 4] = [
    ("flip_time", Kernel::FlipTime),
    ("lyapunov", Kernel::Lyapunov),
    ("indicators", Kernel::Indicators),
    ("trajectory", Kernel::Trajectory),
];

/// What a site's manifest.json says wrote it: `web --output` writes again only into a folder
/// that is new, empty or such a site.
pub const GENERATOR: &str = "chaoscope web";

/// The site's files: (path inside the folder, contents).
pub fn files(spec: &SiteSpec) -> Vec<(String, Vec<u8>)> {
    let mut files = vec![
        ("index.html".to_string(), PAGE.as_bytes().to_vec()),
        ("rules.js".to_string(), RULES.as_bytes().to_vec()),
        ("explorer.js".to_string(), SCRIPT.as_bytes().to_vec()),
        ("style.css".to_string(), STYLE.as_bytes().to_vec()),
    ];
    let mut kernels = serde_json::Map::new();
    for (name, kernel) in KERNELS {
        let wgsl = source(kernel, Precision::F32);
        let path = format!("{name}.wgsl");
        kernels.insert(name.into(), reflect(&wgsl, &path));
        files.push((path, wgsl.into_bytes()));
    }
    let manifest = manifest(spec, Value::Object(kernels));
    files.push((
        "manifest.json".to_string(),
        serde_json::to_vec_pretty(&manifest).expect("JSON of plain values"),
    ));
    files
}

/// The simulated time a view of the page may ask for (s), in its controls and its links
/// alike (a link outside is refused in words): with [`PAGE_DT`], at most 1000 / 1e-4 = 10^7
/// steps a run, within the engine's `MAX_STEPS` (2^24).
pub const PAGE_T_MAX: [f64; 2] = [0.1, 1000.0];
/// The time step a view of the page may ask for (s).
pub const PAGE_DT: [f64; 2] = [1e-4, 0.1];

/// `indicator` as the page computes it, in f32: a setting f32 cannot hold (the RLI's
/// neighbour 1e-8 away) takes the measure's own f32 default, as the command line's f32 maps do.
pub fn in_f32(indicator: Indicator) -> Indicator {
    let measure = indicator.measure();
    match measure.validate(indicator, Precision::F32) {
        Ok(()) => indicator,
        Err(_) => {
            let name = indicator.spelled().0;
            measure.asked(
                name,
                &IndicatorAsked {
                    gpu_f32: true,
                    ..IndicatorAsked::named(name)
                },
            )
        }
    }
}

/// The settings of `kind`'s indicator the page offers, in f32: its default there first
/// ([`in_f32`]), then each combination of its options' values (a whole option's range, the
/// others' offered values) that f32 allows, each once. None for the flip time.
pub fn variants(kind: MapKind) -> Vec<Indicator> {
    let Some(default) = kind.entry().indicator else {
        return Vec::new();
    };
    let first = in_f32(default);
    let name = first.spelled().0;
    let mut combos: Vec<Vec<(&'static str, f64)>> = vec![Vec::new()];
    for opt in first.measure().options(name) {
        let values: Vec<f64> = match opt.whole {
            Some((lo, hi)) => (lo..=hi).map(f64::from).collect(),
            None => opt.offered.to_vec(),
        };
        combos = combos
            .iter()
            .flat_map(|c| {
                values
                    .iter()
                    .map(move |&v| [&c[..], &[(opt.field, v)]].concat())
            })
            .collect();
    }
    let mut out = vec![first];
    for options in combos {
        let asked = IndicatorAsked {
            name,
            options: &options,
            accurate: false,
            gpu_f32: true,
        };
        if let Ok(i) = asked.indicator()
            && i.validate(Precision::F32).is_ok()
            && !out.contains(&i)
        {
            out.push(i);
        }
    }
    out
}

/// An indicator's options in words for the page's menu: "gali 3, threshold 1e-4".
pub fn options_label(indicator: Indicator) -> String {
    let (_, options) = indicator.spelled();
    match options.is_empty() {
        true => "its settings".into(),
        false => options
            .iter()
            .map(|(opt, v)| format!("{} {v}", opt.field.replace('_', "-")))
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// The page's settings: the kernels' layouts, the engine's constants, the pendulums, the
/// planes' variables, the colours.
fn manifest(spec: &SiteSpec, kernels: Value) -> Value {
    let pendulums: Vec<Value> = spec
        .pendulums
        .iter()
        .map(|p| {
            // dt is the page's to set (the `dt` field); the rest is the engine's upload.
            let params = GpuParams::new(&p.params, 0.01);
            let words: Vec<u32> = bytemuck::cast_slice(bytemuck::bytes_of(&params)).to_vec();
            let flags: serde_json::Map<String, Value> = p
                .flags
                .iter()
                .map(|(k, v)| (k.clone(), Value::String(v.clone())))
                .collect();
            json!({
                "name": p.name,
                "flags": flags,
                // The scale of everything measured in mass on the GPU (src/gpu/layout.rs).
                "mass_scale": mass_scale(&p.params),
                "params": words,
                "losses": p.params.losses.kinds(),
                // The flip colours' earliest time.
                "t_lo": crate::render::FlipColors::t_lo(&p.params),
                // The arms' lengths, to draw a swinging pendulum.
                "l1": p.params.l1,
                "l2": p.params.l2,
            })
        })
        .collect();
    let vars: Vec<Value> = Var::ALL
        .iter()
        .map(|v| {
            let (r, l) = (v.default_range(), v.limits());
            // An unbounded side is null (JSON has no infinity).
            let side = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
            json!({"name": v.name(), "symbol": v.symbol(), "code": v.code(), "unit": v.unit(), "angle": v.is_angle(),
                "state": v.is_state(), "mass": v.is_mass(), "writes": v.writes(),
                "range": [r.min, r.max], "limits": [side(l.min), side(l.max)]})
        })
        .collect();
    // The flip time's colour maps (each divergence kind carries its own table).
    let colours: Vec<(String, Value)> = [Colormap::Inferno, Colormap::Viridis]
        .iter()
        .map(|&c| (c.name().to_string(), Value::String(hex(&flip_table(c)))))
        .collect();
    let flip = MapKind::FLIP_TIME.entry();
    let mut kinds = vec![json!({
        "name": flip.short, "label": flip.label, "unit": "s", "kernel": "flip_time",
        "about": legend(MapKind::FLIP_TIME),
        "command": spec.command,
        "vouch": vouch(&crate::quantity::FLIP_TIME),
    })];
    // Each kind as its default setting, with every setting the page offers (the default
    // first) for its menu of options.
    kinds.extend(spec.indicator_commands.iter().map(|(kind, offered)| {
        let default = options_label(offered[0].0);
        let settings: Vec<Value> = offered
            .iter()
            .enumerate()
            .map(|(k, (i, command))| {
                let mut v = divergence_kind(*kind, *i, command);
                let options = options_label(*i);
                // The kinds' table's words are its default setting's: another says so.
                if k > 0 {
                    v["label"] = json!(format!("{} ({options})", v["bar_label"].as_str().unwrap()));
                    v["about"] = json!(format!(
                        "Colour: {}, at {options}. At its default setting ({default}): {}",
                        v["bar_label"].as_str().unwrap(),
                        v["about"].as_str().unwrap()
                    ));
                }
                v["options"] = json!(options);
                v
            })
            .collect();
        let mut first = settings[0].clone();
        first["settings"] = json!(settings);
        first
    }));
    let colours: serde_json::Map<String, Value> = colours.into_iter().collect();
    json!({
        "generator": GENERATOR,
        "version": env!("CARGO_PKG_VERSION"),
        "kernels": kernels,
        "kinds": kinds,
        "constants": {
            "workgroup_size": WORKGROUP_SIZE,
            "never": NEVER,
            "nonfinite": NONFINITE,
            "steps_per_dispatch": STEPS_PER_DISPATCH,
            "steps_per_invocation": STEPS_PER_INVOCATION,
            "min_steps": MIN_STEPS,
            "pendulum_bytes": std::mem::size_of::<GpuPendulum>(),
            "f32_epsilon": f32::EPSILON,
            "max_workgroups": MAX_WORKGROUPS,
            // The coarsest step the verdict vouches at (src/verdict.rs).
            "verdict_dt_max": crate::verdict::LARGEST_VOUCHED_DT,
            // The most steps a run may take (src/spec/map.rs): the page computes no more.
            "max_steps": crate::spec::MAX_STEPS,
        },
        // The page's own bounds on a view's run, its controls' and its links' alike.
        "bounds": {"t_max": PAGE_T_MAX, "dt": PAGE_DT},
        "pendulums": pendulums,
        "vars": vars,
        "colours": colours,
        "swing_command": spec.swing_command,
    })
}

/// The verdict's rule of `quantity`: the tolerance two runs at different steps must keep, and
/// its words.
fn vouch(quantity: &Quantity) -> Value {
    let t = quantity.vouch;
    json!({"relative": t.relative, "absolute": t.absolute, "time": t.never.is_some(),
        "words": quantity.vouching()})
}

/// A colour table as one string of RRGGBB hex.
fn hex(table: &[[u8; 3]]) -> String {
    table
        .iter()
        .map(|[r, g, b]| format!("{r:02x}{g:02x}{b:02x}"))
        .collect()
}

/// What the page needs to map `indicator`, from the measure that computes it and its line in
/// the kinds' table: the kernel and entries the engine runs, the run's setting and measure,
/// a step's cost, how a raw value is finished and what marks a start that left the numbers,
/// its colours' range rule, its names and its legend.
fn divergence_kind(kind: MapKind, indicator: Indicator, command: &str) -> Value {
    let measure = indicator.measure();
    let (kernel, init, advance, code, setting, cost, left_below) = match measure.runs(indicator) {
        Runs::Divergence => (
            "lyapunov",
            "tangent_init",
            "tangent_advance",
            0,
            0.0,
            TANGENT_STEP_COST,
            STALLED_BELOW,
        ),
        Runs::Indicators(g) => (
            "indicators",
            "indicator_init",
            g.entry,
            g.measure,
            g.setting,
            g.cost,
            LEFT_BELOW,
        ),
    };
    let lyapunov = LyapunovSpec::new(
        Params::default(),
        crate::spec::Grid::square(1),
        crate::spec::Stepping {
            dt: crate::spec::Stepping::DT,
            t_max: crate::spec::Stepping::DIVERGENCE_T_MAX,
        },
    );
    // The divergence kernel's log sum is over the run's time (gpu::lyapunov); an indicator's
    // finish is the raw value or the raw value over the run's time (its `finish`).
    let per_time = match measure.runs(indicator) {
        Runs::Divergence => true,
        Runs::Indicators(_) => measure.finish(indicator, 1.0, 2.0) == 0.5,
    };
    let quantity = indicator.quantity();
    // How the command line draws it: its colour bar's label, and whether its colours run
    // from bright (low values) to dark.
    let look = measure.look(indicator, lyapunov.stepping.t_max);
    json!({
        "name": kind.short(),
        "label": kind.entry().label,
        "about": legend(kind),
        "bar_label": look.label,
        "reversed": look.reversed,
        "unit": quantity.unit,
        "kernel": kernel,
        "entries": [init, advance],
        "measure": code,
        "setting": setting,
        "cost": cost,
        "renorm": lyapunov.renorm,
        "per_time": per_time,
        "left_below": left_below,
        // The colours' range: the measure's rule (src/measure/range.rs), t-max's where it
        // counts in place of "{t_max}".
        "range": range_rule(indicator),
        // A start the measure marks as never (an alignment not within t-max) finishes as +inf.
        "never_inf": measure.finish(indicator, NEVER as f64, 1.0) == f32::INFINITY,
        "vouch": vouch(quantity),
        "table": hex(&ftle_table(Colormap::Magma)),
        "command": command,
    })
}

/// `indicator`'s colour range rule as the page applies it: ends fixed or quantiles, with
/// their bounds; a fixed end that is t-max as the string "t_max" (the page's t-max varies).
fn range_rule(indicator: Indicator) -> Value {
    // Two t-maxes tell an end that follows t-max from one that is fixed.
    let (a, b) = (
        indicator.measure().range_rule(indicator, 1.0),
        indicator.measure().range_rule(indicator, 2.0),
    );
    let end = |x: End, y: End| match (x, y) {
        (End::Fixed(p), End::Fixed(q)) if p == 1.0 && q == 2.0 => json!("t_max"),
        (End::Fixed(p), _) => json!({"fixed": p}),
        (End::Quantile { bound }, _) => json!({"bound": bound}),
    };
    json!({"quantiles": [a.quantiles.0, a.quantiles.1], "widen": a.widen,
        "low": end(a.low, b.low), "high": end(a.high, b.high)})
}

/// What the page needs to know of a kernel's WGSL, read from it by naga: its file, its entry
/// points and overrides, each binding (uniform, or storage and whether read-only, and its
/// array's element size), and the `Params` struct's members (offset and scalar).
fn reflect(wgsl: &str, path: &str) -> Value {
    let module = naga::front::wgsl::parse_str(wgsl).expect("the engine's kernels parse");
    let scalar = |ty: naga::Handle<naga::Type>| match module.types[ty].inner {
        naga::TypeInner::Scalar(s) => match s.kind {
            naga::ScalarKind::Float => Some("f32"),
            naga::ScalarKind::Uint => Some("u32"),
            naga::ScalarKind::Sint => Some("i32"),
            _ => None,
        },
        _ => None,
    };
    let (members, size) = module
        .types
        .iter()
        .find_map(|(_, t)| match (&t.name, &t.inner) {
            (Some(name), naga::TypeInner::Struct { members, span }) if name == "Params" => {
                Some((members, *span))
            }
            _ => None,
        })
        .expect("every kernel has its Params");
    let fields: serde_json::Map<String, Value> = members
        .iter()
        .filter_map(|m| {
            let kind = scalar(m.ty)?;
            Some((m.name.clone()?, json!({"offset": m.offset, "type": kind})))
        })
        .collect();
    let bindings: Vec<Value> = module
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            let kind = match g.space {
                naga::AddressSpace::Uniform => "uniform",
                naga::AddressSpace::Storage { access }
                    if !access.contains(naga::StorageAccess::STORE) =>
                {
                    "read-only-storage"
                }
                naga::AddressSpace::Storage { .. } => "storage",
                _ => return None,
            };
            // An array's element size: a storage binding's bytes per element.
            let stride = match module.types[g.ty].inner {
                naga::TypeInner::Array { stride, .. } => Some(stride),
                _ => None,
            };
            Some(
                json!({"group": b.group, "binding": b.binding, "name": g.name, "type": kind,
                "stride": stride}),
            )
        })
        .collect();
    let entries: Vec<&str> = module
        .entry_points
        .iter()
        .map(|e| e.name.as_str())
        .collect();
    let overrides: Vec<&str> = module
        .overrides
        .iter()
        .filter_map(|(_, o)| o.name.as_deref())
        .collect();
    json!({
        "file": path,
        "entries": entries,
        "overrides": overrides,
        "bindings": bindings,
        "params": {"size": size.next_multiple_of(16), "fields": fields},
    })
}
