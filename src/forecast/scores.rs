//! How a forecast did against the rows after its window, the only rows it is scored on: how
//! long its median followed the lower mass, its bands' coverage by lead, and the data's
//! horizon (where the measurements leave their band for good).

use super::ensemble::Forecast;

/// The first data row (its time) after the window from which a measured coordinate lies
/// outside its measurement band at `run` rows in a row: a single exit is what a calibrated
/// 90 % band shows one time in ten. `run` is the least for which a calibrated band would
/// show such a run by chance with probability under 5 % over the forecast's rows.
pub fn data_horizon(
    forecast: &Forecast,
    t: &[f64],
    data: &[[f64; 4]],
) -> (Option<f64>, usize, Option<f64>) {
    let rows: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] > forecast.window_end + 1e-9 && forecast.index(t[i]).is_some())
        .collect();
    let chances = 4.0 * rows.len().max(1) as f64;
    let run = (1..)
        .find(|&k| chances * 0.1f64.powi(k) < 0.05)
        .unwrap_or(1) as usize;
    let out = |i: usize, c: usize| {
        let q = forecast.observed[forecast.index(t[i]).expect("a band time")][c];
        !(q[0]..=q[4]).contains(&data[i][c])
    };
    let horizon = (0..rows.len()).find_map(|r| {
        (0..4)
            .any(|c| r + run <= rows.len() && (r..r + run).all(|s| out(rows[s], c)))
            .then_some(t[rows[r]])
    });
    // How often the measurements lie inside the band before the spread's horizon.
    let until = forecast.spread_horizon.unwrap_or(f64::INFINITY);
    let (mut inside, mut all) = (0usize, 0usize);
    for &i in rows.iter().filter(|&&i| t[i] < until) {
        for c in 0..4 {
            all += 1;
            inside += !out(i, c) as usize;
        }
    }
    (horizon, run, (all > 0).then(|| inside as f64 / all as f64))
}

/// How the forecast did against the data after its window: how long the members' median
/// follows the lower mass within `within` (m, the distance), and the share of the lower
/// mass's coordinates inside their measurement's 90 % band, over all the rows scored and by
/// lead. Only rows after the window are scored; a median that is not a number never follows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Scores {
    pub within: f64,
    /// Seconds after the window's end until the median first strays past `within`; where it
    /// never strays, the last row's lead and `followed_to_data_end` (a lower bound). None
    /// where no row lies after the window.
    pub median_follows_for: Option<f64>,
    pub followed_to_data_end: bool,
    /// Rows scored, and the lead (s) of the last.
    pub rows: usize,
    pub last_lead: Option<f64>,
    pub lower_in_band: Option<f64>,
    /// The lower mass's coordinates inside their 90 % band by lead: each bin holds the rows
    /// whose lead is at most its `to` (s) and more than the bin before's.
    pub by_lead: Vec<LeadCoverage>,
}

/// One lead bin of [`Scores::by_lead`].
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct LeadCoverage {
    pub to: f64,
    pub coordinates: usize,
    pub inside: Option<f64>,
}

/// The lead bins' upper ends (s) of [`Scores::by_lead`].
pub const SCORED_LEADS: [f64; 6] = [0.05, 0.1, 0.2, 0.3, 0.5, 1.0];

pub fn scores(forecast: &Forecast, t: &[f64], data: &[[f64; 4]], within: f64) -> Scores {
    let mut follows_for = None;
    let (mut inside, mut all, mut rows, mut last_lead) = (0usize, 0usize, 0usize, None);
    let mut by_lead: Vec<(usize, usize)> = vec![(0, 0); SCORED_LEADS.len()];
    for (i, &ti) in t.iter().enumerate() {
        if ti <= forecast.window_end + 1e-9 {
            continue;
        }
        let Some(k) = forecast.index(ti) else {
            continue;
        };
        let lead = ti - forecast.window_end;
        rows += 1;
        last_lead = Some(lead);
        let (m, q) = (&forecast.model[k], &forecast.observed[k]);
        let off = (data[i][2] - m[2][2]).hypot(data[i][3] - m[3][2]);
        // A median that is not a number never follows.
        if follows_for.is_none() && (off.is_nan() || off > within) {
            follows_for = Some(lead);
        }
        let bin = SCORED_LEADS.iter().position(|&to| lead <= to + 1e-9);
        for c in 2..4 {
            let hit = (q[c][0]..=q[c][4]).contains(&data[i][c]) as usize;
            all += 1;
            inside += hit;
            if let Some(b) = bin {
                by_lead[b].0 += 1;
                by_lead[b].1 += hit;
            }
        }
    }
    Scores {
        within,
        median_follows_for: follows_for.or(last_lead),
        followed_to_data_end: follows_for.is_none() && last_lead.is_some(),
        rows,
        last_lead,
        lower_in_band: (all > 0).then(|| inside as f64 / all as f64),
        by_lead: SCORED_LEADS
            .iter()
            .zip(by_lead)
            .map(|(&to, (n, hit))| LeadCoverage {
                to,
                coordinates: n,
                inside: (n > 0).then(|| hit as f64 / n as f64),
            })
            .collect(),
    }
}
