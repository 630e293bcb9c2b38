//! The timing of a surface against the response it drives: the same regression as its sign
//! test, with the surface shifted in time sample by sample over ±[`MAX_LEAD_S`]; the shift of
//! least residual is the time the recorded surface leads the response (equation-error time-delay
//! estimation; Klein & Morelli 2006, §5.2 and §10.2, the delay as a regression parameter found by
//! a one-dimensional search). The minimum is refined by a parabola through its neighbours; the
//! 95 % interval is where the residual sum of squares stays below
//! `RSS_min (1 + 3.84 w² / dof)`, the F (likelihood-ratio) bound of one parameter, `w` the
//! widening for coloured residuals (fewer independent samples): on that parabola when the bound
//! falls within one sample of the vertex, else where the sampled curve crosses it.
//!
//! A recorded surface that *leads* the response is the signature of a commanded surface (the
//! actuator's lag lies between the command and the surface: a first-order lag τ reads as a lead
//! ≈ τ at the manoeuvre's frequencies) or of a channel recorded early; one that lags it, of a
//! channel recorded late. Every shift uses the same rows: those whose surface exists at every
//! shift (the first and last 0.3 s of each stretch are left out for all of them).

use super::{LsFit, Row, RowView, regress_view};
use aeroident_io::Mapping;
use aeroident_io::replay_output::SignTest;
use aeroident_io::warning::{Warning, WarningKind};

/// A lead is worth a warning from this many seconds (and at least one sample interval): below
/// it, the central differences' own resolution.
pub const WARN_LEAD_S: f64 = 0.02;

/// The largest lead searched each way, s.
pub const MAX_LEAD_S: f64 = 0.3;

/// 95 % point of χ²(1): the F bound of one parameter.
const CHI2_1_95: f64 = 3.84;

/// The lead of a surface over the response, s, with its 95 % interval (`lo`, `hi`; at the
/// search's edge when the bound is not crossed there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lead {
    /// The lead, s (> 0: the recorded surface moves before the response it drives).
    pub lead_s: f64,
    /// Lower end of the 95 % interval, s.
    pub lo_s: f64,
    /// Upper end, s.
    pub hi_s: f64,
}

/// The lead of a surface over its response from its sign test's rows `all` (the surface the
/// first regressor), `dt_s` the sample interval; `None` when a shift cannot be fitted. A shift
/// `j` takes each row's surface from the row `j` samples earlier, over the rows whose every
/// shift exists (the same rows for all).
pub(super) fn lead(all: &[Row], dt_s: f64) -> Option<Lead> {
    let k = ((MAX_LEAD_S / dt_s).round() as usize).max(1) as isize;
    let at_sample = SampleIndex::of(all);
    let source = |row: &Row, j: isize| {
        let (m, i) = row.2;
        at_sample.row(m, usize::try_from(i as isize - j).ok()?)
    };
    let kept: Vec<&Row> =
        all.iter().filter(|row| (-k..=k).all(|j| source(row, j).is_some())).collect();
    if kept.len() < super::MIN_ROWS {
        return None;
    }
    let mut fits: Vec<LsFit> = Vec::with_capacity(2 * k as usize + 1);
    for j in -k..=k {
        // Row i's surface from its source row j samples earlier; its other regressors its own.
        let surface: Vec<f64> =
            kept.iter().map(|row| source(row, j).map_or(f64::NAN, |r| all[r].1[0])).collect();
        let shifted = RowView {
            len: kept.len(),
            width: kept[0].1.len(),
            y: |i: usize| kept[i].0,
            x: |i: usize, c: usize| if c == 0 { surface[i] } else { kept[i].1[c] },
            manoeuvre: |i: usize| kept[i].2.0,
        };
        fits.push(regress_view(&shifted)?);
    }
    let rss: Vec<f64> = fits.iter().map(|f| f.rss).collect();
    let best = (0..rss.len()).min_by(|&a, &b| rss[a].total_cmp(&rss[b]))?;
    let f = fits[best];
    let at = |i: f64| (i - k as f64) * dt_s;
    let excess = CHI2_1_95 * f.widen * f.widen / f.dof as f64;
    // Near the minimum the residual is a parabola in the shift: its vertex and the shifts where
    // it reaches the bound, when those lie within the neighbours; else the grid's crossings.
    if best > 0 && best + 1 < rss.len() {
        let (a, b, c) = (rss[best - 1], rss[best], rss[best + 1]);
        let curv = a - 2.0 * b + c;
        if curv > 0.0 {
            let vertex = (0.5 * (a - c) / curv).clamp(-0.5, 0.5);
            let r_v = b - (c - a) * (c - a) / (8.0 * curv);
            let half = (2.0 * r_v * excess / curv).sqrt();
            let centre = best as f64 + vertex;
            if half <= 1.0 {
                return Some(Lead {
                    lead_s: at(centre),
                    lo_s: at(centre - half),
                    hi_s: at(centre + half),
                });
            }
        }
    }
    let bound = f.rss * (1.0 + excess);
    let crossing = |step: isize| {
        let mut i = best as isize;
        loop {
            let next = i + step;
            if next < 0 || next as usize >= rss.len() {
                return at(i as f64);
            }
            let (r0, r1) = (rss[i as usize], rss[next as usize]);
            if r1 > bound {
                let frac = ((bound - r0) / (r1 - r0)).clamp(0.0, 1.0);
                return at(i as f64 + step as f64 * frac);
            }
            i = next;
        }
    };
    Some(Lead { lead_s: at(best as f64), lo_s: crossing(-1), hi_s: crossing(1) })
}

/// Where each sample's row is: per manoeuvre, the row of each sample index (`None`: that
/// sample has no row). A manoeuvre's sample indices are dense, so a table answers what a hash
/// of `(manoeuvre, sample)` did, without hashing each of the search's lookups.
struct SampleIndex(Vec<Vec<Option<usize>>>);

impl SampleIndex {
    /// The table of `rows`.
    fn of(rows: &[Row]) -> Self {
        let mut table: Vec<Vec<Option<usize>>> = Vec::new();
        for (r, row) in rows.iter().enumerate() {
            let (m, i) = row.2;
            if table.len() <= m {
                table.resize_with(m + 1, Vec::new);
            }
            if table[m].len() <= i {
                table[m].resize(i + 1, None);
            }
            table[m][i] = Some(r);
        }
        Self(table)
    }

    /// The row of sample `i` of manoeuvre `m`.
    fn row(&self, m: usize, i: usize) -> Option<usize> {
        self.0.get(m)?.get(i).copied().flatten()
    }
}

/// The damping derivative of the axis a surface drives (`Cm_q` for `de`, `Cl_p` for `da`,
/// `Cn_r` for `dr`): a time shift of the surface trades against it, since the response to a
/// lagged input looks like a more damped response to a prompt one.
fn damping_of(surface: &str) -> Option<&'static str> {
    match surface {
        "de" => Some("Cm_q"),
        "da" => Some("Cl_p"),
        "dr" => Some("Cn_r"),
        _ => None,
    }
}

/// The warnings of a surface test whose lead is determined (its 95 % interval excludes 0) and
/// at least [`WARN_LEAD_S`] and one sample interval `dt_s`, in words: a lead is a commanded
/// surface or one recorded early, a lag one recorded late; both bias the control and damping
/// derivatives of every method, so one warning is about the control derivative and a second,
/// pointing to it, about the damping derivative (empty without a determined lead).
pub fn warnings(t: &SignTest, mapping: &Mapping, dt_s: f64) -> Vec<Warning> {
    let Some(w) = warning(t, mapping, dt_s) else { return Vec::new() };
    let damping = damping_of(&t.channel).zip(w.parameter.clone()).map(|(d, control)| {
        let text = format!(
            "input timing: the {} shift of `{}` named on {control} biases its damping derivative {d} too (a lagged input reads as extra damping)",
            if t.lead_s.is_some_and(|l| l > 0.0) { "lead" } else { "lag" },
            t.channel
        );
        Warning::new(WarningKind::InputTiming, text).about(d)
    });
    std::iter::once(w).chain(damping).collect()
}

/// The warning of a surface test whose lead is determined ([`warnings`]), about its control
/// derivative.
pub fn warning(t: &SignTest, mapping: &Mapping, dt_s: f64) -> Option<Warning> {
    let (lead, (lo, hi)) = (t.lead_s?, t.lead_interval_s?);
    if lead.abs() < WARN_LEAD_S.max(dt_s) || (lo <= 0.0 && hi >= 0.0) {
        return None;
    }
    let label = super::label(mapping, &t.channel);
    let interval = format!("95 % {lo:.3} … {hi:.3} s");
    let text = if lead > 0.0 {
        format!(
            "input timing: {label} leads the response by {lead:.3} s ({interval}; its sign test's regression with the surface shifted in time): the surface is probably commanded, not measured (an actuator lag between command and surface), or recorded early; every method's control and damping derivatives are biased by it (low, for a lag)"
        )
    } else {
        format!(
            "input timing: {label} lags the response by {:.3} s ({interval}; its sign test's regression with the surface shifted in time): the channel is probably recorded late (a filter or transport delay on it); every method's control and damping derivatives are biased by it",
            -lead
        )
    };
    let w = Warning::new(WarningKind::InputTiming, text);
    Some(match super::derivative_of(&t.channel) {
        Some(d) => w.about(d),
        None => w,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// The interval against its closed form: a response `y = β sin(ω(t − L))` plus white noise
    /// σ, regressed on the surface `sin(ωt)`, determines the lead with the Cramér–Rao σ
    /// `σ_L = σ / (β ω √(N/2))` (β and L are orthogonal for a sinusoid), so the 95 % interval's
    /// half-width is `1.96 σ_L`. Measured within 25 % of it on 2,000 samples (the sample σ and
    /// the widening scatter by a few %), the lead within 4 σ_L of its truth: an interval √10
    /// wider (the audit's mutant) or narrower fails.
    #[test]
    fn the_interval_is_the_cramer_rao_bound_of_the_lead() {
        let (dt, n, omega, beta, sigma, lead_true) = (0.02, 2000, 3.0, 1.0, 0.05, 0.1);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let noise = Normal::new(0.0, sigma).unwrap();
        let rows: Vec<Row> = (0..n)
            .map(|i| {
                let t = i as f64 * dt;
                let y = beta * (omega * (t - lead_true)).sin() + noise.sample(&mut rng);
                (y, vec![(omega * t).sin()], (0, i))
            })
            .collect();
        let l = lead(&rows, dt).unwrap();
        let kept = n - 2 * (MAX_LEAD_S / dt).round() as usize;
        let sigma_l = sigma / (beta * omega * (kept as f64 / 2.0).sqrt());
        let half = 0.5 * (l.hi_s - l.lo_s);
        let ratio = half / (1.96 * sigma_l);
        assert!((0.8..1.25).contains(&ratio), "half-width {half} s, {ratio} × the bound");
        assert!((l.lead_s - lead_true).abs() < 4.0 * sigma_l, "{l:?}");
        assert!(l.lo_s < l.lead_s && l.lead_s < l.hi_s, "{l:?}");
    }
}
