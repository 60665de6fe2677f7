//! A store's identity: what it holds, compared with what a task would add to it (the version,
//! the verdict, and its settings as data, field by field).

use super::StoreInfo;
use crate::error::{Error, Result};
use std::path::Path;

/// `theirs` (a store's) and `ours` made by the same command and version, else an error naming
/// `field` and what differs.
pub(super) fn check_same(
    field: &'static str,
    path: &Path,
    theirs: &StoreInfo,
    ours: &StoreInfo,
) -> Result<()> {
    // Every refusal names the store first.
    let refuse = |why: String| Err(Error::invalid(field, format!("{} {why}", path.display())));
    if theirs.version != ours.version {
        return refuse(format!(
            "was made by chaoscope {}, this is {}: start a new store",
            theirs.version, ours.version
        ));
    }
    if theirs.resolved != ours.resolved {
        let (made, ask) = match theirs.resolved {
            true => ("with", "too"),
            false => ("without", "in a new store"),
        };
        return refuse(format!(
            "was made {made} the verdict ([[resolved]]): ask for it {ask}"
        ));
    }
    if theirs.identity.is_null() {
        return refuse(
            "records no settings as data (chaoscope:identity): it was made by an older chaoscope; start a new store".into(),
        );
    }
    let mut differences = Vec::new();
    differ(
        &mut Vec::new(),
        &theirs.identity,
        &ours.identity,
        &mut differences,
    );
    if !differences.is_empty() {
        return Err(Error::StoreDiffers {
            field,
            path: path.to_path_buf(),
            differences,
            command: theirs.command.clone(),
        });
    }
    Ok(())
}

/// The settings in which two identities differ: (spec field, theirs, ours), one entry a
/// field, in the order of the identity.
pub(super) fn differ(
    at: &mut Vec<String>,
    theirs: &serde_json::Value,
    ours: &serde_json::Value,
    out: &mut Vec<(&'static str, String, String)>,
) {
    use serde_json::Value;
    match (theirs, ours) {
        (Value::Object(a), Value::Object(b)) if a.keys().eq(b.keys()) => {
            for (key, value) in a {
                at.push(key.clone());
                differ(at, value, &b[key], out);
                at.pop();
            }
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                at.push(k.to_string());
                differ(at, x, y, out);
                at.pop();
            }
        }
        (a, b) if a == b => {}
        (a, b) => {
            let field = setting(at);
            if out.iter().all(|(f, _, _)| *f != field) {
                out.push((field, shown(a), shown(b)));
            }
        }
    }
}

/// A value as a command line writes it: numbers as Rust prints them (1, not 1.0; 1e-300, not
/// three hundred zeros), enum variants by name, the rest as JSON cut at 60 characters (a
/// damaged store's record can be any size).
pub(super) fn shown(v: &serde_json::Value) -> String {
    let text = match v {
        serde_json::Value::Number(n) => match n.as_f64() {
            Some(x) if x != 0.0 && !(1e-4..1e16).contains(&x.abs()) => format!("{x:e}"),
            Some(x) => x.to_string(),
            None => n.to_string(),
        },
        serde_json::Value::String(s) => s.to_lowercase(),
        serde_json::Value::Object(o) if o.len() == 1 => o.keys().next().unwrap().to_lowercase(),
        v => v.to_string(),
    };
    match text.char_indices().nth(60) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text,
    }
}

/// The spec field an identity's path names (the names the command line maps to its flags).
pub(super) fn setting(at: &[String]) -> &'static str {
    let leaf = at.last().map(String::as_str).unwrap_or("");
    let parent = at.len().checked_sub(2).map_or("", |k| at[k].as_str());
    let axis = at.len().checked_sub(3).map_or("", |k| at[k].as_str());
    match (parent, leaf) {
        ("range", _) | (_, "var") if axis == "x" || parent == "x" => "x",
        ("range", _) | (_, "var") => "y",
        ("", "map") | (_, "Flip") | (_, "Lyapunov") | ("map", _) => "data",
        (_, "width" | "height") => "size",
        ("theta1", "min" | "max") => "theta1",
        ("theta2", "min" | "max") => "theta2",
        (_, "joint1" | "joint2") => "joint_damping",
        (_, "rod1" | "rod2") => "rod_mass",
        (_, "bob_area1" | "bob_area2") => "drag_area",
        (_, "rod_area1" | "rod_area2") => "rod_drag_area",
        (_, "bearing") => "bearing_friction",
        (_, "measure") => "colour_by",
        (_, "early_exit") => "full",
        (_, "use_symmetry") => "no_symmetry",
        ("fixed", "theta1") => "theta1",
        ("fixed", "theta2") => "theta2",
        // A setting named as its flag, else the map's data.
        _ => SAME_NAME.into_iter().find(|&n| n == leaf).unwrap_or("data"),
    }
}

/// The settings whose spec field is named as its flag.
const SAME_NAME: [&str; 18] = [
    "rtol",
    "atol",
    "eps",
    "m1",
    "m2",
    "l1",
    "l2",
    "g",
    "t_max",
    "dt",
    "omega1",
    "omega2",
    "renorm",
    "precision",
    "backend",
    "rho",
    "cw",
    "bearing_radius",
];
