//! Shader assembly: which WGSL files make each kernel, in which precision. A kernel's full
//! source is the constants shared with Rust, the precision's own file (`real_f32.wgsl` or
//! `real_f64.wgsl`: `alias real = ...` and the few functions whose f32 and f64 forms differ),
//! `common.wgsl`, then the kernel's files, every one of them written over `real`.

use super::layout::{NEVER, NONFINITE, Real, WORKGROUP_SIZE, with_real};
use crate::spec::Precision;

const COMMON: &str = include_str!("../../shaders/common.wgsl");
const FLIP_TIME: &str = include_str!("../../shaders/flip_time.wgsl");
const FLIP_KIND: &str = include_str!("../../shaders/flip_kind.wgsl");
const ADAPTIVE_COMMON: &str = include_str!("../../shaders/adaptive_common.wgsl");
const DP54: &str = include_str!("../../shaders/dp54.wgsl");
const FLIP_DP54: &str = include_str!("../../shaders/flip_adaptive.wgsl");
const FLIP_DOP853: &str = include_str!("../../shaders/flip_dop853.wgsl");
const TANGENT: &str = include_str!("../../shaders/tangent.wgsl");
const ADAPTIVE_WINDOWS: &str = include_str!("../../shaders/adaptive_windows.wgsl");
const LYAPUNOV: &str = include_str!("../../shaders/lyapunov.wgsl");
const INDICATORS: &str = include_str!("../../shaders/indicators.wgsl");
const TRAJECTORY: &str = include_str!("../../shaders/trajectory.wgsl");
const POSITIONS: &str = include_str!("../../shaders/positions.wgsl");

/// The kernels, each one WGSL module.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Flip times, RK4 (`flip_init`, `flip_time`).
    FlipTime,
    /// Flip kinds: the flip-time kernel's loop and flip location, and its own entry.
    FlipKind,
    /// Flip times, DP54: the adaptive kernels' shared part, DP54's coefficients, the method.
    FlipDp54,
    /// Flip times, DOP853: the shared part and the stages written out from the tableau.
    FlipDop853,
    /// Divergence maps (tangent, twin, adaptive tangent; DP54's coefficients, the tangent
    /// arithmetic) and Jacobians.
    Lyapunov,
    /// Chaos indicators: the tangent arithmetic, the indicators' file and the measures' own.
    Indicators,
    /// Trajectories and ensembles.
    Trajectory,
    /// Ensembles' positions at given times.
    Positions,
}

impl Kernel {
    pub const ALL: [Kernel; 8] = [
        Kernel::FlipTime,
        Kernel::FlipKind,
        Kernel::FlipDp54,
        Kernel::FlipDop853,
        Kernel::Lyapunov,
        Kernel::Indicators,
        Kernel::Trajectory,
        Kernel::Positions,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Kernel::FlipTime => "flip_time",
            Kernel::FlipKind => "flip_kind",
            Kernel::FlipDp54 => "flip_adaptive",
            Kernel::FlipDop853 => "flip_dop853",
            Kernel::Lyapunov => "lyapunov",
            Kernel::Indicators => "indicators",
            Kernel::Trajectory => "trajectory",
            Kernel::Positions => "positions",
        }
    }

    /// The kernel's own files, in order, after `common.wgsl`.
    fn body(self) -> String {
        match self {
            Kernel::FlipTime => FLIP_TIME.to_string(),
            Kernel::FlipKind => format!("{FLIP_TIME}\n{FLIP_KIND}"),
            Kernel::FlipDp54 => format!(
                "{ADAPTIVE_COMMON}\n{}\n{}",
                dp54(),
                with_flip_dp54_stages(FLIP_DP54)
            ),
            Kernel::FlipDop853 => flip_dop853(),
            Kernel::Lyapunov => format!(
                "{}\n{TANGENT}\n{}",
                dp54(),
                with_dp54_stages(
                    &with_adaptive_windows(LYAPUNOV),
                    "tangent_rate",
                    "tangent_ahead",
                    "t"
                )
            ),
            Kernel::Indicators => format!(
                "{}\n{TANGENT}\n{}\n{}",
                dp54(),
                with_dp54_stages(
                    &with_adaptive_windows(INDICATORS),
                    "set_rate",
                    "set_ahead",
                    "x"
                ),
                crate::measure::wgsl()
            ),
            Kernel::Trajectory => TRAJECTORY.to_string(),
            Kernel::Positions => POSITIONS.to_string(),
        }
    }
}

/// The full source of `kernel` in `precision` (f64 needs `Features::SHADER_F64`).
pub fn source(kernel: Kernel, precision: Precision) -> String {
    assemble(&kernel.body(), precision)
}

/// The full source of WGSL `body` (written over `real`) in `precision`: the constants shared
/// with Rust, the precision's file, `common.wgsl`, then `body`.
pub fn assemble(body: &str, precision: Precision) -> String {
    let real = with_real!(precision, R => R::WGSL);
    format!(
        "const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;\nconst NEVER: real = {NEVER:?};\nconst NONFINITE: real = {NONFINITE:?};\n{real}\n{COMMON}\n{body}"
    )
}

/// Every kernel in every precision, for validation: named as the kernel, with `_f64` for
/// the f64 ones.
pub fn all_shaders() -> Vec<(String, String)> {
    Kernel::ALL
        .into_iter()
        .flat_map(|k| {
            Precision::ALL.into_iter().map(move |p| {
                let suffix = if p == Precision::F64 { "_f64" } else { "" };
                (format!("{}{suffix}", k.name()), source(k, p))
            })
        })
        .collect()
}

/// `body` with DP54's stages written in at `//{{DP54_STAGES}}` from the tableau (src/tableau.rs
/// `DP54`, nonzero weights only) for a state kind whose rate is `rate(c, y)` and whose step
/// along a rate is `ahead(y, w, k)` (y + w k): `k2`..`k6`, `next` (the fifth-order solution)
/// and `k7` (its rate, the next step's first), from the state `y` and its rate `k1` at step
/// `step`, each sum nested in the tableau's order.
fn with_dp54_stages(body: &str, rate: &str, ahead: &str, y: &str) -> String {
    let t = &crate::tableau::DP54;
    let along = |weights: &[f64], name: &dyn Fn(usize) -> String| {
        let mut sum = y.to_string();
        for (j, &w) in weights.iter().enumerate() {
            if w != 0.0 {
                sum = format!("{ahead}({sum}, {} * step, k{})", name(j), j + 1);
            }
        }
        sum
    };
    let mut lines: Vec<String> = (1..6)
        .map(|s| {
            let stage = along(&t.a[s][..s], &|j| format!("A{}{}", s + 1, j + 1));
            format!("let k{} = {rate}(c, {stage});", s + 1)
        })
        .collect();
    lines.push(format!(
        "let next = {};",
        along(&t.b, &|j| format!("B{}", j + 1))
    ));
    lines.push(format!("let k7 = {rate}(c, next);"));
    let out = body.replace("//{{DP54_STAGES}}", &lines.join("\n            "));
    assert!(!out.contains("{{"), "a placeholder left in a DP54 kernel");
    out
}

/// `body` with the adaptive windows' loop (shaders/adaptive_windows.wgsl) where it marks
/// `//{{ADAPTIVE_WINDOWS}}`, filled from the sections that follow the mark up to `//{{END}}`
/// (`//{{RATE}}`, `//{{ERROR}}`, `//{{ACCEPT}}`, `//{{STALLED}}`, `//{{WINDOW_END}}`, each a
/// line of its own): the loop written once for every state kind.
fn with_adaptive_windows(body: &str) -> String {
    let start = body
        .find("    //{{ADAPTIVE_WINDOWS}}")
        .expect("the kernel marks where its adaptive windows go");
    let end_mark = "    //{{END}}\n";
    let end = body[start..].find(end_mark).expect("its fills end") + start;
    let block = &body[start..end];
    // The block's first line is the mark; then each section's mark and its lines.
    let mut fills: Vec<(&str, String)> = Vec::new();
    for part in block.split("    //{{").skip(2) {
        let (name, text) = part
            .split_once("}}\n")
            .expect("a section's mark on its own line");
        fills.push((name, text.trim_end_matches('\n').to_string()));
    }
    // The template without its header of comments.
    let template: String = ADAPTIVE_WINDOWS
        .lines()
        .skip_while(|l| l.starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect();
    let mut filled = template;
    for (name, text) in fills {
        let text = match name {
            "RATE" => text.trim().to_string(),
            _ => text,
        };
        filled = filled.replace(&format!("{{{{{name}}}}}"), &text);
    }
    let out = format!(
        "{}{filled}{}",
        &body[..start],
        &body[end + end_mark.len()..]
    );
    assert!(
        !out.replace("//{{DP54_STAGES}}", "").contains("{{"),
        "a section of the adaptive windows left unfilled"
    );
    out
}

/// The flip kernel's `body` with DP54's stages written in at `//{{DP54_STAGES}}` from the
/// tableau, over a `Pendulum` `p` and its `Rate`s: each stage's state is `p` plus the step
/// times one sum of the weighted rates (`advanced` for one weight, `alongN` of
/// flip_adaptive.wgsl for N), the nonzero weights only.
fn with_flip_dp54_stages(body: &str) -> String {
    let t = &crate::tableau::DP54;
    let along = |weights: &[f64], name: &dyn Fn(usize) -> String| {
        let terms: Vec<(String, usize)> = weights
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != 0.0)
            .map(|(j, _)| (name(j), j + 1))
            .collect();
        match &terms[..] {
            [(w, k)] => format!("advanced(p, {w} * step, k{k})"),
            _ => {
                let weighted: Vec<String> =
                    terms.iter().map(|(w, k)| format!("{w}, k{k}")).collect();
                format!("along{}(p, step, {})", terms.len(), weighted.join(", "))
            }
        }
    };
    let mut lines: Vec<String> = (1..6)
        .map(|s| {
            let stage = along(&t.a[s][..s], &|j| format!("A{}{}", s + 1, j + 1));
            format!("let k{} = rate(c, {stage});", s + 1)
        })
        .collect();
    lines.push(format!(
        "let next = {};",
        along(&t.b, &|j| format!("B{}", j + 1))
    ));
    lines.push("let k7 = rate(c, next);".into());
    let out = body.replace("//{{DP54_STAGES}}", &lines.join("\n        "));
    assert!(
        !out.contains("{{"),
        "a placeholder left in the flip's DP54 kernel"
    );
    out
}

/// DP54's coefficients and controller (dp54.wgsl) with the coefficients written from the
/// tableau (src/tableau.rs `DP54`): `const Aij`, `Bj`, `Ej`, `Dj` (1-based, as in Hairer's
/// tables) for the nonzero weights, as literals WGSL takes at full precision in either float.
fn dp54() -> String {
    let t = &crate::tableau::DP54;
    let mut lines = Vec::new();
    let mut named = |name: String, w: f64| {
        if w != 0.0 {
            lines.push(format!("const {name} = {w:e};"));
        }
    };
    // Rows 2..6: the last row is b (FSAL), named B.
    for (s, row) in t.a.iter().enumerate().take(6).skip(1) {
        for (j, &w) in row[..s].iter().enumerate() {
            named(format!("A{}{}", s + 1, j + 1), w);
        }
    }
    for (letter, weights) in [("B", &t.b), ("E", &t.e[0]), ("D", &t.d[0])] {
        for (j, &w) in weights.iter().enumerate() {
            named(format!("{letter}{}", j + 1), w);
        }
    }
    lines.push(format!(
        "const ATTEMPTS_PER_DISPATCH: u32 = {}u;",
        super::tiled::ATTEMPTS_PER_DISPATCH
    ));
    let body = DP54.replace("//{{COEFFICIENTS}}", &lines.join("\n"));
    assert!(!body.contains("{{"), "a placeholder left in dp54.wgsl");
    body
}

/// The DOP853 flip kernel: its template with the stages written out from the tableau
/// (src/tableau.rs, which the CPU twin loops over), only the nonzero weights, as literals
/// that WGSL takes at full precision in either float type.
fn flip_dop853() -> String {
    let t = &crate::tableau::DOP853;
    // "w1 * k1.dy + w2 * k2.dy ..." over the nonzero weights (stage j is k{j + 1}).
    let sum = |weights: &[f64], part: &str| -> String {
        let terms: Vec<String> = weights
            .iter()
            .enumerate()
            .filter(|(_, w)| **w != 0.0)
            .map(|(j, w)| format!("{w:e} * k{}.{part}", j + 1))
            .collect();
        terms.join(" + ")
    };
    let stage = |s: usize| {
        let a = &t.a[s][..s];
        format!(
            "let k{} = rate(c, Pendulum(p.y + step * ({}), p.u + step * ({})));",
            s + 1,
            sum(a, "dy"),
            sum(a, "du")
        )
    };
    let indent = "\n        ";
    let mut stages: Vec<String> = (1..12).map(stage).collect();
    stages.push(format!(
        "let next = Pendulum(p.y + step * ({}), p.u + step * ({}));",
        sum(&t.b, "dy"),
        sum(&t.b, "du")
    ));
    stages.push(format!("let e5 = {};", sum(&t.e[0], "dy")));
    stages.push(format!("let e3 = {};", sum(&t.e[1], "dy")));
    let mut dense: Vec<String> = (13..16).map(stage).collect();
    for (m, d) in t.d.iter().enumerate() {
        dense.push(format!("let hd{m} = step * ({});", sum(d, "dy")));
    }
    let body = FLIP_DOP853
        .replace("//{{STAGES}}", &stages.join(indent))
        .replace("//{{DENSE_STAGES}}", &dense.join("\n                "));
    assert!(
        !body.contains("{{"),
        "a placeholder left in flip_dop853.wgsl"
    );
    format!("{ADAPTIVE_COMMON}\n{body}")
}
