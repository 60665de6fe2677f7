//! Specification field -> flag, per command: the library's errors name fields (`t_max`), the
//! user reads flags (`--t-max`, or `--exposure` in `traces`).

/// The flag (or argument) of `field` in `command`.
pub fn flag(command: &str, field: &str) -> String {
    match (command, field) {
        ("traces", "t_max") => "--exposure".into(),
        ("fit", "t_max") => "--window".into(),
        ("fit" | "forecast", "file") => "FILE".into(),
        ("track", "video") => "VIDEO".into(),
        (_, field) => format!("--{}", field.replace('_', "-")),
    }
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::flag;
    use crate::cli::Cli;

    /// Every field the library names maps to a flag that the command really has.
    #[test]
    fn fields_map_to_existing_flags() {
        let cli = Cli::command();
        let fields: &[(&str, &[&str])] = &[
            (
                "flip",
                &[
                    "size",
                    "theta1",
                    "theta2",
                    "omega1",
                    "omega2",
                    "t_max",
                    "dt",
                    "m1",
                    "joint_damping",
                    "rod_drag_area",
                    "air_drag",
                    "params",
                    "output",
                    "data",
                    "integrator",
                    "colormap",
                    // The settings a store's identity names (render::store `setting`).
                    "g",
                    "rod_mass",
                    "drag_area",
                    "bearing_friction",
                    "bearing_radius",
                    "rho",
                    "cw",
                    "colour_by",
                    "full",
                    "no_symmetry",
                    "precision",
                    "rtol",
                    "atol",
                    "backend",
                ],
            ),
            (
                "lyapunov",
                &[
                    "size",
                    "theta1",
                    "t_max",
                    "dt",
                    "renorm",
                    "integrator",
                    "rtol",
                    "atol",
                    "eps",
                    "output",
                    "data",
                    "colour_range",
                    "method",
                    "no_symmetry",
                    "precision",
                    "backend",
                ],
            ),
            ("trajectory", &["theta1", "t_max", "dt", "every", "output"]),
            (
                "track",
                &[
                    "video",
                    "output",
                    "l1",
                    "pixels_per_metre",
                    "markers",
                    "region",
                ],
            ),
            (
                "traces",
                &[
                    "t_max", "dt", "runs", "spread", "size", "output", "film", "fps", "crf", "data",
                ],
            ),
            (
                "phase",
                &["t_max", "dt", "runs", "spread", "size", "output"],
            ),
            (
                "sweep",
                &[
                    "frames", "fps", "vary", "zoom", "zoom_to", "ftle_max", "size", "t_max",
                    "output", "film", "crf",
                ],
            ),
            (
                "fit",
                &[
                    "file",
                    "t_max",
                    "window",
                    "tolerance",
                    "velocity_error",
                    "candidates",
                    "start",
                    "joint_damping",
                    "params",
                    "output",
                    "y_up",
                    "pixels_per_metre",
                    "mass",
                ],
            ),
            (
                "forecast",
                &[
                    "file",
                    "window",
                    "members",
                    "seed",
                    "tolerance",
                    "tracking_error",
                    "candidates",
                    "joint_damping",
                    "params",
                    "output",
                    "y_up",
                ],
            ),
            (
                "twin",
                &[
                    "sigma",
                    "rate",
                    "replicates",
                    "duration",
                    "theta1",
                    "omega2",
                    "members",
                    "tolerance",
                    "output",
                ],
            ),
        ];
        for (command, fields) in fields {
            let sub = cli.find_subcommand(command).expect("subcommand");
            for field in *fields {
                let name = flag(command, field);
                let found = sub.get_arguments().any(|a| {
                    a.get_long().map(|l| format!("--{l}")) == Some(name.clone())
                        || a.get_value_names()
                            .is_some_and(|v| v.iter().any(|v| *v == *name))
                });
                assert!(
                    found,
                    "{command}: field {field} -> {name}, which it does not have"
                );
            }
        }
    }
}
