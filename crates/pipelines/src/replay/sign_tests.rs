//! Sign tests of the surfaces and the accelerometers from the record's own kinematics and
//! responses: independent of the model file, the estimator and its priors, so a reversed
//! channel is named where it is, not where a derivative happens to come out with the wrong sign.
//!
//! **Surfaces.** The angular accelerations (central differences of the rates) are regressed by
//! least squares on the states and the surfaces, the dimensional equation-error model
//! (Klein & Morelli, *Aircraft System Identification*, 2006, §5.2):
//!
//! ```text
//! q̇ = M₀ + M_α α + M_q q + M_δe δe
//! ṗ = L₀ + L_β β + L_p p + L_r r + L_δa δa + L_δr δr
//! ṙ = N₀ + N_β β + N_p p + N_r r + N_δa δa + N_δr δr
//! ```
//!
//! with β from the kinematics where the record maps none (module `sideslip`: `a_y` standing in for it
//! moves the rudder's coefficient by the rudder's own side force), and the terms of channels
//! not mapped left out. Without β or the kinematics to give it, the aileron's test takes `a_y`
//! (an aileron's side force is small) and the rudder's cannot be decided. Under the mapping's conventions (docs/mapping.md:
//! δe > 0 trailing edge down, δa > 0 a negative rolling moment, δr > 0 trailing edge left) a
//! conventional aircraft has `M_δe`, `L_δa`, `N_δr` < 0 (Stevens & Lewis, *Aircraft Control
//! and Simulation*, 2nd ed., §2.3; a canard reverses `M_δe`).
//!
//! **Accelerometers.** The flat-earth body-axis force equations (Stevens & Lewis, 2nd ed.,
//! Table 2.5-1) give the specific force the accelerometers measure at the CG:
//!
//! ```text
//! a_x = u̇ − r v + q w + g sinθ
//! a_y = v̇ + r u − p w − g cosθ sinφ
//! a_z = ẇ − q u + p v − g cosθ cosφ
//! ```
//!
//! with `(u, v, w) = V (cosα cosβ, sinβ, sinα cosβ)` (a steady wind moves them by a constant,
//! which the regression's bias takes). The right side, from the air data, attitude and rates, is
//! regressed on the channel with a bias: its gain is 1 when the channel is consistent and −1
//! when it is reversed. `a_y` needs β (the side velocity), `a_x` and `a_z` need θ; without them
//! the test says so instead of guessing.
//!
//! An accelerometer whose gain is decided beyond [`DECIDE_SIGMAS`] σ from +1 and −1 (a gain
//! near 0 with a small σ is a channel that does not carry the motion's force) and lies outside [1/[`SCALE_BOUND`], [`SCALE_BOUND`]] does not read the specific force as
//! mapped: it is `not_a_specific_force`, with the likely form (`likely_form`): gravity
//! removed (the force equations' gravity term, added as a second regressor, takes a gain near
//! −1), a reading in g or ft/s², or a load factor.
//!
//! **Decision.** The sign is decided when the gain is more than [`DECIDE_SIGMAS`] σ from 0, σ
//! the least-squares one widened by `√((1 + ρ)/(1 − ρ))` for the residuals' lag-1
//! autocorrelation ρ > 0 (an AR(1) account of the fewer independent samples; Bartlett 1946).
//! Otherwise the channel "cannot be decided from this record", with the numbers.
//!
//! **Differences.** Each derivative is a central difference across ±0.05 s (at least
//! one sample each side), the mean of the derivative over that span, so every other term is
//! averaged over the same span (trapezoidal). Differences stay within one manoeuvre and within
//! contiguous samples (each interval at most 2.5 × the shortest: none across a gap).

use crate::kinematics::sideslip;
use aeroident_estimators::AirDataSample;
use aeroident_io::replay_output::{SignTest, SignVerdict};
use aeroident_io::warning::{Warning, WarningKind};
use aeroident_io::{Channel, Mapping};
use aeroident_physics::rigid_body::{SinCos, body_acceleration, body_velocity, gravity_body};
use aeroident_physics::units::G0_MPS2;
use nalgebra::{DMatrix, DVector};

/// The gain must be this many (widened) σ from 0 for its sign to be decided.
pub const DECIDE_SIGMAS: f64 = 4.0;

/// An accelerometer's gain within [1/`SCALE_BOUND`, `SCALE_BOUND`] of ±1 is read as a specific
/// force's with calibration and timing errors (an α vane 0.2 s late moved a normal
/// accelerometer's kinematic gain to 2.7), beyond it as another quantity.
pub const SCALE_BOUND: f64 = 3.0;

/// Half the span of the central differences, s: wide enough that sensor noise at 50–100 Hz
/// does not swamp the derivative, narrow against a short period or Dutch roll (a difference
/// over ±0.05 s passes 2 Hz with 3 % loss, and the regressors are averaged the same way).
const HALF_SPAN_S: f64 = 0.05;

/// Fewest differenced samples before a sign is decided.
const MIN_ROWS: usize = 50;

/// One sample's field, read from an [`AirDataSample`].
type Field = fn(&AirDataSample) -> Option<f64>;

/// The fields a test may use, by name (as `AirDataSample` and the mapping's keys name them).
const FIELDS: [(&str, Field); 12] = [
    ("p", |s| s.p_rad_s),
    ("q", |s| s.q_rad_s),
    ("r", |s| s.r_rad_s),
    ("beta", |s| s.beta_rad),
    ("phi", |s| s.phi_rad),
    ("theta", |s| s.theta_rad),
    ("ax", |s| s.ax_mps2),
    ("ay", |s| s.ay_mps2),
    ("az", |s| s.az_mps2),
    ("de", |s| s.de_rad),
    ("da", |s| s.da_rad),
    ("dr", |s| s.dr_rad),
];

/// The samples `i − m … i + m` around one sample, contiguous in time.
struct Stencil<'a> {
    window: &'a [AirDataSample],
    span_s: f64,
}

impl Stencil<'_> {
    /// The central difference of `f` across the stencil (unit per s): the derivative of `f`
    /// averaged over the stencil.
    fn rate(&self, f: impl Fn(&AirDataSample) -> Option<f64>) -> Option<f64> {
        let (first, last) = (self.window.first()?, self.window.last()?);
        Some((f(last)? - f(first)?) / self.span_s)
    }

    /// `f` averaged over the stencil (trapezoidal), to match the difference's averaging.
    fn mean(&self, f: impl Fn(&AirDataSample) -> Option<f64>) -> Option<f64> {
        let mut sum = 0.0;
        for w in self.window.windows(2) {
            sum += 0.5 * (f(&w[0])? + f(&w[1])?) * (w[1].t_s - w[0].t_s);
        }
        Some(sum / self.span_s)
    }
}

/// The mapped fields of the record: those more than half of its samples carry.
#[derive(Debug, Clone, Default)]
struct Present(Vec<&'static str>);

impl Present {
    fn has(&self, name: &str) -> bool {
        self.0.contains(&name)
    }
}

/// One test: the channel, the sign a consistent one gives, the fields it needs beyond the
/// channel, its regression and what that is in words.
#[derive(Clone, Copy)]
struct Test {
    channel: &'static str,
    expected: f64,
    needs: &'static [&'static str],
    /// What is regressed on what.
    regression: Regression,
    what: &'static str,
    unit: &'static str,
}

const TESTS: [Test; 6] = [
    Test {
        channel: "de",
        expected: -1.0,
        needs: &["q"],
        regression: Regression::Pitch,
        what: "q̇ per δe (least squares on δe, α, q)",
        unit: " rad/s² per rad",
    },
    Test {
        channel: "da",
        expected: -1.0,
        needs: &["p"],
        regression: Regression::Roll,
        what: "ṗ per δa (least squares on δa, β (else a_y), p, r, δr where mapped)",
        unit: " rad/s² per rad",
    },
    Test {
        channel: "dr",
        expected: -1.0,
        needs: &["r"],
        regression: Regression::Yaw,
        what: "ṙ per δr (least squares on δr, β, p, r, δa where mapped)",
        unit: " rad/s² per rad",
    },
    Test {
        channel: "ax",
        expected: 1.0,
        needs: &["theta", "q"],
        regression: Regression::SpecificForce(0),
        what: "a_x's gain against u̇ − r v + q w + g sinθ",
        unit: "",
    },
    Test {
        channel: "ay",
        expected: 1.0,
        needs: &["beta", "phi", "theta", "p", "r"],
        regression: Regression::SpecificForce(1),
        what: "a_y's gain against v̇ + r u − p w − g cosθ sinφ",
        unit: "",
    },
    Test {
        channel: "az",
        expected: 1.0,
        needs: &["theta", "q"],
        regression: Regression::SpecificForce(2),
        what: "a_z's gain against ẇ − q u + p v − g cosθ cosφ",
        unit: "",
    },
];

/// What a test regresses: an angular acceleration on the states and surfaces, or the
/// kinematics' specific force along body axis 0, 1, 2 on that accelerometer.
#[derive(Debug, Clone, Copy)]
enum Regression {
    Pitch,
    Roll,
    Yaw,
    SpecificForce(usize),
    /// The kinematics' specific force on the body-axis gravity term and the accelerometer.
    Gravity(usize),
}

impl Test {
    /// The regressand and the regressors (the tested one first; the bias is added) at one
    /// stencil, or `None` where a field is missing.
    fn row(&self, s: &Stencil, on: &Present) -> Option<(f64, Vec<f64>)> {
        match self.regression {
            Regression::Pitch => pitch(s),
            Regression::Roll => roll(s, on),
            Regression::Yaw => yaw(s, on),
            Regression::SpecificForce(axis) => specific_force(s, axis, self.needs),
            Regression::Gravity(axis) => {
                let (y, reading) = specific_force(s, axis, self.needs)?;
                let g = s.mean(|c| {
                    let (phi, theta) = (c.phi_rad.unwrap_or(0.0), c.theta_rad.unwrap_or(0.0));
                    Some(gravity_body(G0_MPS2, SinCos::of(phi), SinCos::of(theta))[axis])
                })?;
                Some((y, vec![g, reading[0]]))
            }
        }
    }
}

/// The specific force along body axis `axis` that the force equations give from the air data,
/// attitude and rates ([`body_acceleration`] with no specific force, taken from the body
/// velocity's rate), and the accelerometer's reading, both over the stencil. Each sample must
/// carry the `needs` fields; β, φ and the rates not among them count as 0 where missing.
fn specific_force(s: &Stencil, axis: usize, needs: &[&str]) -> Option<(f64, Vec<f64>)> {
    let field = |c: &AirDataSample, name: &str| FIELDS.iter().find(|f| f.0 == name)?.1(c);
    let or_zero = |v: Option<f64>| v.unwrap_or(0.0);
    let v_body = |c: &AirDataSample| {
        body_velocity(c.vt_mps, SinCos::of(c.alpha_rad), SinCos::of(or_zero(c.beta_rad)))
    };
    let v_dot = s.rate(|c| Some(v_body(c)[axis]))?;
    let kinematic = s.mean(|c| {
        if !needs.iter().all(|n| field(c, n).is_some()) {
            return None;
        }
        let omega = [or_zero(c.p_rad_s), or_zero(c.q_rad_s), or_zero(c.r_rad_s)];
        let (phi, theta) = (SinCos::of(or_zero(c.phi_rad)), SinCos::of(or_zero(c.theta_rad)));
        let g = gravity_body(G0_MPS2, phi, theta);
        Some(body_acceleration(v_body(c), omega, g, [0.0; 3])[axis])
    })?;
    let reading = s.mean(|c| [c.ax_mps2, c.ay_mps2, c.az_mps2][axis])?;
    Some((v_dot - kinematic, vec![reading]))
}

fn pitch(s: &Stencil) -> Option<(f64, Vec<f64>)> {
    let x = vec![s.mean(|c| c.de_rad)?, s.mean(|c| Some(c.alpha_rad))?, s.mean(|c| c.q_rad_s)?];
    Some((s.rate(|x| x.q_rad_s)?, x))
}

/// The lateral regressors after the tested surface: β (or `a_y` without it), p, r and the
/// other surface, each where the record maps it, averaged over the stencil.
fn lateral(s: &Stencil, on: &Present, other: &str) -> Option<Vec<f64>> {
    let side = if on.has("beta") { "beta" } else { "ay" };
    let mut x = Vec::with_capacity(5);
    for (name, f) in FIELDS {
        if on.has(name) && [side, "p", "r", other].contains(&name) {
            x.push(s.mean(f)?);
        }
    }
    Some(x)
}

fn roll(s: &Stencil, on: &Present) -> Option<(f64, Vec<f64>)> {
    let mut x = vec![s.mean(|c| c.da_rad)?];
    x.extend(lateral(s, on, "dr")?);
    Some((s.rate(|x| x.p_rad_s)?, x))
}

fn yaw(s: &Stencil, on: &Present) -> Option<(f64, Vec<f64>)> {
    let mut x = vec![s.mean(|c| c.dr_rad)?];
    x.extend(lateral(s, on, "da")?);
    Some((s.rate(|x| x.r_rad_s)?, x))
}

/// The sign tests of every surface and accelerometer the record maps, over the samples of each
/// manoeuvre (no difference across two), in the order `de, da, dr, ax, ay, az`, each decided
/// surface's timing searched.
pub fn sign_tests<M: AsRef<[AirDataSample]>>(manoeuvres: &[M]) -> Vec<SignTest> {
    sign_tests_timed(manoeuvres, None)
}

/// [`sign_tests`], with the timing search left out for the reason `no_timing` when given (it
/// is added to each decided surface's evidence).
fn sign_tests_timed<M: AsRef<[AirDataSample]>>(
    manoeuvres: &[M],
    no_timing: Option<&str>,
) -> Vec<SignTest> {
    let present = present_fields(manoeuvres);
    let kinematic = (!present.has("beta")).then(|| sideslip::filled(manoeuvres)).flatten();
    TESTS
        .iter()
        .filter(|t| present.has(t.channel))
        .map(|t| match t.needs.iter().find(|n| !present.has(n)) {
            Some(missing) => undecided(t, format!("`{missing}` is not mapped")),
            None if !matches!(t.regression, Regression::Roll | Regression::Yaw) => {
                run(t, manoeuvres, &present, no_timing)
            }
            None => lateral_test(t, manoeuvres, kinematic.as_deref(), &present, no_timing),
        })
        .collect()
}

/// A lateral moment test: on β as mapped, else on the kinematics' β (said in the evidence),
/// else the aileron's on `a_y` and the rudder's undecided (module doc).
fn lateral_test<M: AsRef<[AirDataSample]>>(
    t: &Test,
    manoeuvres: &[M],
    kinematic: Option<&[Vec<AirDataSample>]>,
    present: &Present,
    no_timing: Option<&str>,
) -> SignTest {
    if present.has("beta") {
        return run(t, manoeuvres, present, no_timing);
    }
    match kinematic {
        Some(k) => {
            let mut test = run(t, k, &present_fields(k), no_timing);
            test.evidence.push_str(&format!("; β not mapped: {}", sideslip::HOW));
            test
        }
        None if matches!(t.regression, Regression::Yaw) => undecided(
            t,
            "β is not mapped and the kinematics cannot give it (a_y, r and φ are needed); a_y cannot stand in for it here, since the rudder's own side force would move the rudder's coefficient".into(),
        ),
        None => run(t, manoeuvres, present, no_timing),
    }
}

/// The record's mapped fields: those more than half of its samples carry.
fn present_fields<M: AsRef<[AirDataSample]>>(manoeuvres: &[M]) -> Present {
    let all = || manoeuvres.iter().flat_map(|m| m.as_ref().iter());
    let n = all().count();
    let carried = |f: Field| n > 0 && 2 * all().filter(|s| f(s).is_some()).count() > n;
    Present(FIELDS.iter().filter(|(_, f)| carried(*f)).map(|(k, _)| *k).collect())
}

/// A test that could not be run, with why.
fn undecided(t: &Test, why: String) -> SignTest {
    SignTest {
        channel: t.channel.into(),
        verdict: SignVerdict::Undecided,
        gain: None,
        sigma: None,
        lead_s: None,
        lead_interval_s: None,
        evidence: format!("{}: {why}", t.what),
    }
}

/// One row of a test: regressand, regressors (the tested one first, the bias last), and where
/// it is: (manoeuvre, index of the stencil's centre sample).
type Row = (f64, Vec<f64>, (usize, usize));

/// The rows of `t` over the manoeuvres.
fn rows<M: AsRef<[AirDataSample]>>(t: &Test, manoeuvres: &[M], on: &Present) -> Vec<Row> {
    let dt_min = shortest_interval(manoeuvres);
    // Half-width m: about HALF_SPAN_S each side, at least one sample.
    let m = ((HALF_SPAN_S / dt_min).round() as usize).max(1);
    let mut out = Vec::new();
    for (k, man) in manoeuvres.iter().enumerate() {
        for (i, w) in man.as_ref().windows(2 * m + 1).enumerate() {
            let contiguous = w.windows(2).all(|p| {
                let d = p[1].t_s - p[0].t_s;
                d > 0.0 && d <= 2.5 * dt_min
            });
            if !contiguous {
                continue;
            }
            let st = Stencil { window: w, span_s: w[2 * m].t_s - w[0].t_s };
            if let Some((y, mut x)) = t.row(&st, on)
                && y.is_finite()
                && x.iter().all(|v| v.is_finite())
            {
                x.push(1.0);
                out.push((y, x, (k, i + m)));
            }
        }
    }
    out
}

/// The shortest positive sample interval of the manoeuvres, s.
fn shortest_interval<M: AsRef<[AirDataSample]>>(manoeuvres: &[M]) -> f64 {
    manoeuvres
        .iter()
        .flat_map(|m| m.as_ref().windows(2).map(|w| w[1].t_s - w[0].t_s))
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min)
}

/// Runs `t`: the gain of its channel, its widened σ and the verdict; for a surface whose sign
/// is decided, its lead over the response ([`timing`]).
fn run<M: AsRef<[AirDataSample]>>(
    t: &Test,
    manoeuvres: &[M],
    on: &Present,
    no_timing: Option<&str>,
) -> SignTest {
    let rows = rows(t, manoeuvres, on);
    if rows.len() < MIN_ROWS {
        return undecided(t, format!("{} differenced samples, fewer than {MIN_ROWS}", rows.len()));
    }
    let Some(LsFit { gain, sigma, .. }) = regress(&rows) else {
        return undecided(t, "the regressors are not independent (is the channel excited?)".into());
    };
    let verdict = decide(t, gain, sigma);
    let expected = if t.expected > 0.0 {
        "+1 when consistent, −1 reversed"
    } else {
        "< 0 for a conventional aircraft under the mapping's convention"
    };
    let mut evidence =
        format!("{} {gain:+.4} ± {sigma:.2e}{} (expected {expected})", t.what, t.unit);
    if verdict == SignVerdict::Undecided {
        evidence.push_str(&format!("; within {DECIDE_SIGMAS} σ of 0"));
    }
    if verdict == SignVerdict::NotASpecificForce {
        evidence.push_str(&format!(
            "; more than {DECIDE_SIGMAS} σ from ±1 and outside 1/{SCALE_BOUND}–{SCALE_BOUND}, so not the specific force as mapped: {}",
            likely_form(t, manoeuvres, on, gain)
        ));
    }
    let surface_decided = t.expected < 0.0 && verdict != SignVerdict::Undecided;
    if let (true, Some(why)) = (surface_decided, no_timing) {
        evidence.push_str(&format!("; its timing is not searched: {why}"));
    }
    let lead = (surface_decided && no_timing.is_none())
        .then(|| timing::lead(&rows, shortest_interval(manoeuvres)))
        .flatten();
    if let Some(l) = lead {
        evidence.push_str(&format!(
            "; leads the response by {:+.3} s (95 % {:+.3} … {:+.3} s; the same regression with δ shifted in time)",
            l.lead_s, l.lo_s, l.hi_s
        ));
    }
    SignTest {
        channel: t.channel.into(),
        verdict,
        gain: Some(gain),
        sigma: Some(sigma),
        evidence,
        lead_s: lead.map(|l| l.lead_s),
        lead_interval_s: lead.map(|l| (l.lo_s, l.hi_s)),
    }
}

/// The verdict on a gain and its σ (module doc, "Decision").
fn decide(t: &Test, gain: f64, sigma: f64) -> SignVerdict {
    let beyond = |target: f64| (gain - target).abs() > DECIDE_SIGMAS * sigma;
    let off_scale = !(1.0 / SCALE_BOUND..=SCALE_BOUND).contains(&gain.abs());
    if t.expected > 0.0 && off_scale && beyond(1.0) && beyond(-1.0) {
        SignVerdict::NotASpecificForce
    } else if !beyond(0.0) {
        SignVerdict::Undecided
    } else if gain * t.expected > 0.0 {
        SignVerdict::Consistent
    } else {
        SignVerdict::Reversed
    }
}

/// The gains of the accelerometer forms a mapping mix-up gives, with the form in words: the
/// specific force `f` regressed on a reading `k f` has gain `1/k`.
const ACCELEROMETER_FORMS: [(f64, &str); 5] = [
    (G0_MPS2, "likely a reading in g mapped as m/s² (`unit = \"g\"`)"),
    (1.0 / G0_MPS2, "likely m/s² data mapped in g (`unit = \"m/s2\"`)"),
    (0.3048, "likely ft/s² data mapped as m/s² (`unit = \"ft/s2\"`)"),
    (
        -G0_MPS2,
        "likely a load factor (n = −a/g, or n − 1) mapped as the specific force (`unit = \"g\"`, `scale = -1`)",
    ),
    (
        -1.0,
        "likely a load factor in m/s² or a reversed channel (`scale = -1`) with a gain off by more than 3",
    ),
];

/// The likely form of an accelerometer whose gain is `gain` ([`decide`]): gravity removed when
/// the force equations' gravity term takes a gain within 0.2 of −1 beside the reading, else the
/// form of [`ACCELEROMETER_FORMS`] within a factor 1.5 of the gain.
fn likely_form<M: AsRef<[AirDataSample]>>(
    t: &Test,
    manoeuvres: &[M],
    on: &Present,
    gain: f64,
) -> String {
    let Regression::SpecificForce(axis) = t.regression else {
        return "check its unit, sign and what it measures".into();
    };
    let with_gravity = Test { regression: Regression::Gravity(axis), ..*t };
    let fit = regress(&rows(&with_gravity, manoeuvres, on));
    if let Some(LsFit { gain: g, sigma, .. }) = fit
        && (g + 1.0).abs() < 0.2
        && sigma < 0.1
    {
        let term = ["g sinθ", "g cosθ sinφ", "g cosθ cosφ"][axis];
        return format!(
            "likely gravity removed (the gravity term beside it takes {g:+.3} ± {sigma:.1e}, −1 when the channel reads the specific force less gravity, {term}): map the raw accelerometer, or leave the channel out"
        );
    }
    let near = |f: f64| gain / f > 0.0 && (gain / f).ln().abs() < 1.5f64.ln();
    ACCELEROMETER_FORMS
        .iter()
        .find(|(f, _)| near(*f))
        .map_or_else(|| "check its unit, sign and what it measures".into(), |f| f.1.to_string())
}

/// A least-squares fit of one test's rows.
#[derive(Debug, Clone, Copy)]
struct LsFit {
    /// The first regressor's coefficient and its widened σ.
    gain: f64,
    sigma: f64,
    /// Residual sum of squares and its degrees of freedom.
    rss: f64,
    dof: usize,
    /// The σ widening for the residuals' colour, `√((1 + ρ)/(1 − ρ))`.
    widen: f64,
}

/// Least squares of the rows: the first regressor's coefficient and its σ, widened for the
/// residuals' lag-1 autocorrelation within each manoeuvre (module doc); `None` when the
/// normal equations are singular.
fn regress(rows: &[Row]) -> Option<LsFit> {
    let view = RowView {
        len: rows.len(),
        width: rows[0].1.len(),
        y: |i: usize| rows[i].0,
        x: |i: usize, j: usize| rows[i].1[j],
        manoeuvre: |i: usize| rows[i].2.0,
    };
    regress_view(&view)
}

/// Rows seen through accessors: `len` rows of `width` regressors, row `i`'s response `y(i)`,
/// its regressor `j` `x(i, j)` and its manoeuvre `manoeuvre(i)`. The timing search reads its
/// shifted rows so, without copying them for every shift.
struct RowView<Y, X, M> {
    len: usize,
    width: usize,
    y: Y,
    x: X,
    manoeuvre: M,
}

/// [`regress`] over a [`RowView`].
fn regress_view<Y, X, M>(rows: &RowView<Y, X, M>) -> Option<LsFit>
where
    Y: Fn(usize) -> f64,
    X: Fn(usize, usize) -> f64,
    M: Fn(usize) -> usize,
{
    let (m, k, x_at) = (rows.len, rows.width, &rows.x);
    // Columns scaled to unit RMS so the normal equations are well conditioned.
    let scale: Vec<f64> = (0..k)
        .map(|j| ((0..m).map(|i| x_at(i, j) * x_at(i, j)).sum::<f64>() / m as f64).sqrt())
        .collect();
    if scale.iter().any(|s| s.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)) {
        return None;
    }
    let x = DMatrix::from_fn(m, k, |i, j| x_at(i, j) / scale[j]);
    let y = DVector::from_fn(m, |i, _| (rows.y)(i));
    let xtx = x.tr_mul(&x);
    let inv = xtx.clone().cholesky()?.inverse();
    let beta = &inv * x.tr_mul(&y);
    let e = &y - &x * &beta;
    let dof = m.checked_sub(k).filter(|d| *d > 0)?;
    let rss = e.norm_squared();
    let same = |i: usize| (rows.manoeuvre)(i) == (rows.manoeuvre)(i - 1);
    let lagged: f64 = (1..m).filter(|&i| same(i)).map(|i| e[i] * e[i - 1]).sum();
    let rho = (lagged / rss).clamp(0.0, 0.98);
    let widen = ((1.0 + rho) / (1.0 - rho)).sqrt();
    let sigma = (rss / dof as f64 * inv[(0, 0)]).sqrt() * widen / scale[0];
    let gain = beta[0] / scale[0];
    (gain.is_finite() && sigma.is_finite() && inv[(0, 0)] < 1e12).then_some(LsFit {
        gain,
        sigma,
        rss,
        dof,
        widen,
    })
}

/// The tests over `manoeuvres` and the warnings of the reversed channels (labels from `mapping`).
pub fn checked<M: AsRef<[AirDataSample]>>(
    manoeuvres: &[M],
    mapping: &Mapping,
) -> (Vec<SignTest>, Vec<Warning>) {
    checked_timed(manoeuvres, mapping, None)
}

fn checked_timed<M: AsRef<[AirDataSample]>>(
    manoeuvres: &[M],
    mapping: &Mapping,
    no_timing: Option<&str>,
) -> (Vec<SignTest>, Vec<Warning>) {
    let tests = sign_tests_timed(manoeuvres, no_timing);
    let w = warnings(&tests, mapping, shortest_interval(manoeuvres));
    (tests, w)
}

/// [`checked`] over a sample log's segments (a replay's fed samples: a gap or a decimation
/// starts a segment, and no difference is taken across one). A log that dropped blocks of a
/// long record has lost whichever manoeuvres fell in them, and a surface's timing from what is
/// left can be far off (a doublet cut at a block's edge): the timing is not searched then.
pub fn checked_log(
    log: &crate::sample_log::SampleLog<AirDataSample>,
    mapping: &Mapping,
) -> (Vec<SignTest>, Vec<Warning>) {
    let (items, segs) = (log.items(), log.segments());
    let mut parts: Vec<&[AirDataSample]> = Vec::new();
    let mut start = 0;
    for i in 1..=items.len() {
        if i == items.len() || segs[i] != segs[i - 1] {
            parts.push(&items[start..i]);
            start = i;
        }
    }
    let why = format!(
        "the replay kept one block of samples in {} of this long record; replay its manoeuvres with --window",
        log.stride()
    );
    checked_timed(&parts, mapping, (log.dropped() > 0).then_some(why.as_str()))
}

/// The control derivative whose sign surface `key` fixes ([`super::diagnostics::CONTROL_SIGNS`]).
pub(crate) fn derivative_of(key: &str) -> Option<&'static str> {
    super::diagnostics::CONTROL_SIGNS.iter().find(|c| c.2 == key).map(|c| c.0)
}

/// A tested channel as the mapping gives it (``channel `dr` (column `rudder_deg`)``).
pub(crate) fn label(mapping: &Mapping, key: &str) -> String {
    let channel = Channel::ALL.iter().find(|c| c.key() == key);
    channel.map_or_else(|| format!("`{key}`"), |c| mapping.channel_label(*c))
}

/// A warning per reversed channel, naming its mapping source and the fix, and per surface
/// whose lead over its response is determined and at least a sample and 0.02 s ([`timing`]).
pub fn warnings(tests: &[SignTest], mapping: &Mapping, dt_s: f64) -> Vec<Warning> {
    let mut out = reversed_warnings(tests, mapping);
    out.extend(tests.iter().flat_map(|t| timing::warnings(t, mapping, dt_s)));
    out
}

fn reversed_warnings(tests: &[SignTest], mapping: &Mapping) -> Vec<Warning> {
    tests
        .iter()
        .filter(|t| matches!(t.verdict, SignVerdict::Reversed | SignVerdict::NotASpecificForce))
        .map(|t| {
            let label = label(mapping, &t.channel);
            let layout = if t.channel == "de" { " (or the aircraft has a canard)" } else { "" };
            let text = if t.verdict == SignVerdict::Reversed {
                format!(
                    "sign test: {label} looks reversed{layout}: {}; check its sign (`scale = -1`) in the mapping (docs/mapping.md, Channels)",
                    t.evidence
                )
            } else {
                format!("sign test: {label} is not a specific force as mapped: {}", t.evidence)
            };
            let w = Warning::new(WarningKind::Sign, text);
            match derivative_of(&t.channel) {
                Some(d) => w.about(d),
                None => w,
            }
        })
        .collect()
}

pub mod refit;
pub mod timing;

#[cfg(test)]
mod tests;
