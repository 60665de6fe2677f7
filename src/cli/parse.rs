//! Value parsers for the flags: numbers with pi, ranges, sizes, pairs, spreads, points, and
//! the library's named choices.

use clap::builder::{PossibleValuesParser, TypedValueParser};

use crate::app::sweep::{Param, Vary};
use crate::spec::{Range, Spread};

/// A value that is really the next flag: its own value was left out (`--l1 --cw 2`).
pub fn not_a_flag(s: &str) -> Result<(), String> {
    if s.trim_start().starts_with("--") {
        Err(format!(
            "the value is missing (found the flag `{s}` instead)"
        ))
    } else {
        Ok(())
    }
}

/// A number, or a multiple or fraction of pi: `1.5`, `-pi`, `pi/2`, `2pi`, `-0.5*pi`, `3pi/4`.
pub fn parse_number(s: &str) -> Result<f64, String> {
    not_a_flag(s)?;
    let t = s.trim().to_ascii_lowercase();
    if let Some(i) = t.find("pi") {
        let (head, tail) = (&t[..i], &t[i + 2..]);
        let head = head.trim_end_matches('*');
        let factor = match head {
            "" | "+" => 1.0,
            "-" => -1.0,
            h => h
                .parse::<f64>()
                .map_err(|_| format!("`{s}` is not a number"))?,
        };
        let divisor = match tail {
            "" => 1.0,
            d => d
                .strip_prefix('/')
                .and_then(|d| d.parse::<f64>().ok())
                .ok_or_else(|| format!("`{s}` is not a number"))?,
        };
        Ok(factor * std::f64::consts::PI / divisor)
    } else {
        t.parse::<f64>()
            .map_err(|_| format!("`{s}` is not a number"))
    }
}

/// `MIN:MAX`.
pub fn parse_range(s: &str) -> Result<Range, String> {
    not_a_flag(s)?;
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("`{s}` must be MIN:MAX, e.g. -pi:pi"))?;
    Ok(Range {
        min: parse_number(a)?,
        max: parse_number(b)?,
    })
}

/// `N` (square) or `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    not_a_flag(s)?;
    let side = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("`{s}` must be N or WxH with whole numbers"))
    };
    match s.split_once(['x', 'X']) {
        Some((w, h)) => Ok((side(w)?, side(h)?)),
        None => side(s).map(|n| (n, n)),
    }
}

/// `A` or `A,B` (one value for both).
pub fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    not_a_flag(s)?;
    match s.split_once(',') {
        Some((a, b)) => Ok((parse_number(a)?, parse_number(b)?)),
        None => parse_number(s).map(|v| (v, v)),
    }
}

/// An angle (rad, `pi` understood) or a position error with a unit: `5mm`, `0.5cm`, `0.005m`.
pub fn parse_spread(s: &str) -> Result<Spread, String> {
    not_a_flag(s)?;
    let t = s.trim();
    for (suffix, factor) in [("mm", 1e-3), ("cm", 1e-2), ("m", 1.0)] {
        if let Some(v) = t.strip_suffix(suffix) {
            return v
                .trim()
                .parse::<f64>()
                .map(|v| Spread::Metres(v * factor))
                .map_err(|_| format!("`{s}` is not a length"));
        }
    }
    parse_number(t.strip_suffix("rad").unwrap_or(t)).map(Spread::Radians)
}

/// `PARAM=FROM:TO`.
pub fn parse_vary(s: &str) -> Result<Vary, String> {
    not_a_flag(s)?;
    let (name, range) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}` must be PARAM=FROM:TO, e.g. m2/m1=0.5:2"))?;
    let names: Vec<&str> = Param::NAMES.iter().map(|(_, n)| *n).collect();
    let param = Param::NAMES
        .iter()
        .find(|(_, n)| *n == name.trim())
        .map(|(p, _)| *p)
        .ok_or_else(|| format!("`{}` is not one of {}", name.trim(), names.join(", ")))?;
    let (a, b) = range
        .split_once(':')
        .ok_or_else(|| format!("`{range}` must be FROM:TO"))?;
    Ok(Vary {
        param,
        from: parse_number(a)?,
        to: parse_number(b)?,
    })
}

/// `THETA1,THETA2`.
pub fn parse_point(s: &str) -> Result<(f64, f64), String> {
    not_a_flag(s)?;
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("`{s}` must be THETA1,THETA2"))?;
    Ok((parse_number(a)?, parse_number(b)?))
}

/// An angle flag: a range of the map, or a single start.
pub use crate::spec::Angles;
/// `--x`/`--y`: what an axis varies, `NAME` or `NAME=MIN:MAX`.
pub use crate::spec::AxisAsked as AxisArg;

pub fn parse_axis(s: &str) -> Result<AxisArg, String> {
    not_a_flag(s)?;
    let (name, range) = match s.split_once('=') {
        Some((name, range)) => (name, Some(parse_range(range)?)),
        None => (s, None),
    };
    let var = crate::spec::Var::parse(name).ok_or_else(|| {
        let names: Vec<_> = crate::spec::Var::ALL.iter().map(|v| v.name()).collect();
        format!("`{name}` is none of {}", names.join(" "))
    })?;
    Ok(AxisArg { var, range })
}

/// `--at`: `NAME=VALUE`, a map axis's variable at one value.
pub fn parse_at(s: &str) -> Result<(crate::spec::Var, f64), String> {
    not_a_flag(s)?;
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}` must be NAME=VALUE, e.g. m2/m1=2.5"))?;
    let AxisArg { var, .. } = parse_axis(name)?;
    Ok((var, parse_number(value)?))
}

pub fn parse_angles(s: &str) -> Result<Angles, String> {
    if s.contains(':') {
        parse_range(s).map(Angles::Range)
    } else {
        parse_number(s).map(Angles::Point)
    }
}

/// A whole number >= 0 that fits `T`: negative ones are read and refused here, by clap with
/// the flag's name, rather than taken for flags.
fn parse_whole<T: TryFrom<i128>>(s: &str) -> Result<T, String> {
    not_a_flag(s)?;
    let n = s
        .trim()
        .parse::<i128>()
        .map_err(|_| format!("`{s}` is not a whole number"))?;
    if n < 0 {
        return Err(format!("{n} is negative; it must be 0 or more"));
    }
    T::try_from(n).map_err(|_| format!("{n} is too large"))
}

/// `INDEX/COUNT` of a tile: 0 <= INDEX < COUNT (Slurm's SLURM_ARRAY_TASK_ID and
/// SLURM_ARRAY_TASK_COUNT, Kubernetes' JOB_COMPLETION_INDEX and the job's completions).
pub fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    not_a_flag(s)?;
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("{s}: must be INDEX/COUNT, e.g. 0/4"))?;
    let (i, n): (u32, u32) = (parse_whole(i)?, parse_whole(n)?);
    if n == 0 || i >= n {
        return Err(format!(
            "{s}: INDEX/COUNT needs COUNT >= 1 and 0 <= INDEX < COUNT"
        ));
    }
    Ok((i, n))
}

pub fn parse_u32(s: &str) -> Result<u32, String> {
    parse_whole(s)
}

pub fn parse_usize(s: &str) -> Result<usize, String> {
    parse_whole(s)
}

/// One of the library's named choices (`values`, named by `name`), listed in the help.
pub fn one_of<T: Copy + Send + Sync + 'static>(
    values: &'static [T],
    name: fn(T) -> &'static str,
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(values.iter().map(|&v| name(v))).map(move |s| {
        *values
            .iter()
            .find(|&&v| name(v) == s)
            .expect("clap accepts only the possible values")
    })
}

pub fn parse_u64(s: &str) -> Result<u64, String> {
    parse_whole(s)
}

/// A length in metres, or with a unit: `3cm`, `2mm`, `0.03m`, `0.03`.
pub fn parse_length(s: &str) -> Result<f64, String> {
    match parse_spread(s)? {
        Spread::Metres(m) => Ok(m),
        Spread::Radians(v) => Ok(v),
    }
}

/// `START:END` (s).
pub fn parse_window(s: &str) -> Result<(f64, f64), String> {
    let r =
        parse_range(s).map_err(|_| format!("`{s}` must be START:END in seconds, e.g. 0.8:2.3"))?;
    Ok((r.min, r.max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn numbers_with_pi() {
        assert_eq!(parse_number("-pi").unwrap(), -PI);
        assert_eq!(parse_number("pi/2").unwrap(), PI / 2.0);
        assert_eq!(parse_number("3pi/4").unwrap(), 3.0 * PI / 4.0);
        assert_eq!(parse_number("-0.5*pi").unwrap(), -0.5 * PI);
        assert_eq!(parse_number("-3").unwrap(), -3.0);
        assert!(parse_number("pie").is_err());
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("64").unwrap(), (64, 64));
        assert_eq!(parse_size("640x480").unwrap(), (640, 480));
        assert!(parse_size("64x").is_err());
    }
}
