//! Frequency responses from input/output time histories by spectral estimation with composite
//! windowing (Tischler & Remple, *Aircraft and Rotorcraft System Identification*, 2nd ed.,
//! 2012, ch. 7–9; the CIFER method).
//!
//! **Spectra.** For each window length `T_w` the data are cut into windows of `N = T_w/Δt`
//! samples overlapping by `overlap` (default 0.8, CIFER's). Each window is detrended (its
//! least-squares line removed), tapered by a periodic Hann window `w` and Fourier transformed;
//! the one-sided cross-spectral density of channels `a`, `b` is the average over the `K`
//! windows, `G_ab(f) = 2Δt/(K Σw²) Σ conj(X_a(f)) X_b(f)` (Bendat & Piersol, *Random Data*,
//! 4th ed., eq. 11.101), so spectra of every window length estimate the same density.
//!
//! **Frequency grid.** Results are given on a log-spaced grid (`points_per_decade`); each grid
//! point owns a cell between the geometric midpoints to its neighbours. A cell's spectrum for a
//! window length is the average of the FFT bins inside the cell (frequency smoothing); a cell
//! with no bin (narrow cells at low frequency) takes the windowed Fourier transform evaluated
//! at the grid frequency itself (as CIFER's chirp-z transform does). A window length
//! contributes only at frequencies with at least two of its periods in the window,
//! `f ≥ 2/T_w` (Tischler & Remple §7.7).
//!
//! **Response and coherence.** With inputs `x` (m of them) and an output `y`:
//! `H = Gxx⁻¹ Gxy` (the conditioned multi-input solution; `H = Gxy/Gxx` with one input),
//! multiple coherence `γ²_{y:x} = Gxyᴴ Gxx⁻¹ Gxy / Gyy`, and the partial coherence of input `i`
//! with the output, the others removed, `γ²_{iy·} = |D_iy|²/(D_ii D_yy)` with `D` the inverse
//! of the spectral matrix of `[x, y]` (Bendat & Piersol §7.3). With one input both equal the
//! ordinary coherence `|Gxy|²/(Gxx Gyy)`.
//!
//! **Random error.** The normalised random error of `|H_i|` (and the phase error in rad) is
//! `ε_i² = G_nn [Gxx⁻¹]_ii / (2 n_d |H_i|²)` with `G_nn = (1 − γ²_{y:x}) Gyy` the part of the
//! output no input explains; with one input this is Bendat & Piersol's eq. 9.52,
//! `ε = √(1 − γ²) / (|γ| √(2 n_d))` (Tischler & Remple eq. 7.37). `n_d` is the number of
//! independent averages: the windows, counted with Welch's (1967) correction for their overlap,
//! times the FFT bins of the cell, counted with the same correction for the correlation of
//! adjacent Hann-windowed bins. Magnitude error in dB: `20 log₁₀(1 + ε)`; phase error:
//! `ε` rad in degrees.
//!
//! **Composite.** At each grid frequency the window lengths' spectral matrices are averaged
//! with weights `1/ε_w²` (`ε_w` from the window's multiple coherence and `n_d`): the
//! least-squares combination of estimates of one density with those variances (CIFER's
//! composite optimisation, Tischler & Remple §8.6, here in closed form). The composite
//! response, coherences and errors follow from the composite spectra, with `n_d` the
//! weight-averaged `n_d` of the windows (windows of different lengths share the data, so their
//! averages are not added).

use rustfft::FftPlanner;
pub use rustfft::num_complex::Complex64;
use std::f64::consts::PI;

/// Options of the spectral estimation (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralOptions {
    /// Window lengths, s; empty: [`default_window_lengths`] of the record.
    pub window_lengths_s: Vec<f64>,
    /// Fraction by which consecutive windows overlap, `[0, 0.95]`.
    pub overlap: f64,
    /// Lowest grid frequency, Hz; `None`: `2/T_max` (two periods in the longest window).
    pub f_min_hz: Option<f64>,
    /// Highest grid frequency, Hz; `None`: a fifth of the sample rate (Tischler & Remple §7.5).
    pub f_max_hz: Option<f64>,
    /// Grid points per decade of frequency.
    pub points_per_decade: usize,
}

/// The most grid points per decade [`SpectralOptions::check`] accepts: far finer than the FFT
/// bins of any window a record holds (a decade of a 10⁶-sample window has about 10⁶ bins only at
/// its top), while the cells' spectral matrices stay a few megabytes; a larger value would size
/// the grid, and the memory, by the option alone.
pub const MAX_POINTS_PER_DECADE: usize = 1_000;

impl SpectralOptions {
    /// Checks what the options alone decide, before any data is read: the overlap in
    /// `[0, 0.95]`, the points per decade in `1..=`[`MAX_POINTS_PER_DECADE`], the window
    /// lengths and the frequency bounds finite and positive, `f_min_hz < f_max_hz`.
    ///
    /// # Errors
    /// [`SpectralError::Option`] naming the field.
    pub fn check(&self) -> Result<(), SpectralError> {
        let opt = |option: &'static str, reason: String| SpectralError::Option { option, reason };
        if !(0.0..=0.95).contains(&self.overlap) {
            return Err(opt("overlap", format!("{} is outside [0, 0.95]", short(self.overlap))));
        }
        if !(1..=MAX_POINTS_PER_DECADE).contains(&self.points_per_decade) {
            return Err(opt(
                "points_per_decade",
                format!(
                    "{} is outside [1, {MAX_POINTS_PER_DECADE}]",
                    short(self.points_per_decade as f64)
                ),
            ));
        }
        if let Some(t) = self.window_lengths_s.iter().find(|t| !(t.is_finite() && **t > 0.0)) {
            return Err(opt(
                "window_lengths_s",
                format!("{} s is not a positive length", short(*t)),
            ));
        }
        for (option, f) in [("f_min_hz", self.f_min_hz), ("f_max_hz", self.f_max_hz)] {
            if let Some(f) = f.filter(|f| !(f.is_finite() && *f > 0.0)) {
                return Err(opt(option, format!("{} Hz is not a positive frequency", short(f))));
            }
        }
        if let (Some(lo), Some(hi)) = (self.f_min_hz, self.f_max_hz)
            && lo >= hi
        {
            return Err(opt(
                "f_max_hz",
                format!(
                    "{} Hz is not above the lowest frequency asked for, {} Hz",
                    short(hi),
                    short(lo)
                ),
            ));
        }
        Ok(())
    }
}

/// `v` in a short form for messages ([`aeroident_physics::text::Short`]).
fn short(v: f64) -> String {
    aeroident_physics::text::Short(v).to_string()
}

impl Default for SpectralOptions {
    fn default() -> Self {
        Self {
            window_lengths_s: Vec::new(),
            overlap: 0.8,
            f_min_hz: None,
            f_max_hz: None,
            points_per_decade: 40,
        }
    }
}

/// Why a frequency response could not be estimated; each names the option or channel.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectralError {
    /// An option is out of range.
    #[error("option `{option}`: {reason}")]
    Option {
        /// The option's name.
        option: &'static str,
        /// Why.
        reason: String,
    },
    /// The data cannot give a response (too short, wrong shape, not finite).
    #[error("{0}")]
    Data(String),
    /// An input carries no usable excitation: it is constant, or it moves only with the other
    /// inputs (its spectra are singular at every grid frequency). (Low coherence is not judged
    /// here: at the lowest frequencies few averages bias it up to about 0.6 for unrelated
    /// signals; the user reads it.)
    #[error("input `{input}` is not excited: {why} over the grid ({f_lo_hz:.4}–{f_hi_hz:.4} Hz)")]
    NotExcited {
        /// The input's name.
        input: String,
        /// What shows it.
        why: String,
        /// Grid, Hz.
        f_lo_hz: f64,
        /// Grid, Hz.
        f_hi_hz: f64,
    },
}

/// One contiguous, uniformly sampled stretch of data: `channels[c][k]` is channel `c` at sample
/// `k`, the inputs first, then the outputs (all the same length).
pub type Stretch = Vec<Vec<f64>>;

/// The response of one output to one input on the grid. Arrays have one entry per grid
/// frequency; `NaN` where the spectra are singular (not identified).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairResponse {
    /// Input name.
    pub input: String,
    /// Output name.
    pub output: String,
    /// Grid frequencies, Hz.
    pub frequency_hz: Vec<f64>,
    /// `20 log₁₀|H|`, dB (of the output's units per input unit).
    pub magnitude_db: Vec<f64>,
    /// Phase of `H`, deg, unwrapped from low to high frequency.
    pub phase_deg: Vec<f64>,
    /// Coherence: ordinary with one input, partial (the other inputs removed) with several.
    pub coherence: Vec<f64>,
    /// Multiple coherence of the output with all inputs (equals `coherence` with one input).
    pub multiple_coherence: Vec<f64>,
    /// Normalised random error `ε` of `|H|` (module doc), –.
    pub random_error: Vec<f64>,
    /// Magnitude random error `20 log₁₀(1 + ε)`, dB.
    pub magnitude_error_db: Vec<f64>,
    /// Phase random error `ε` rad, in deg.
    pub phase_error_deg: Vec<f64>,
    /// Real part of `H`.
    #[serde(skip)]
    pub re: Vec<f64>,
    /// Imaginary part of `H`.
    #[serde(skip)]
    pub im: Vec<f64>,
}

/// All responses of one estimation and how they were formed.
#[derive(Debug, Clone, PartialEq)]
pub struct FrequencyResponses {
    /// Each (output, input) pair, outputs outer.
    pub pairs: Vec<PairResponse>,
    /// Window lengths used, s.
    pub window_lengths_s: Vec<f64>,
    /// Overlap used.
    pub overlap: f64,
    /// Sample interval, s.
    pub dt_s: f64,
}

/// Five window lengths log-spaced from `T_max = T/2` down to `T_max/8`, `T` the longest
/// stretch, s (Tischler & Remple §8.6: the longest window at most half the record, the
/// shortest resolving the high frequencies with many averages).
pub fn default_window_lengths(longest_stretch_s: f64) -> Vec<f64> {
    let t_max = 0.5 * longest_stretch_s;
    (0..5).map(|k| t_max * 8f64.powf(-(k as f64) / 4.0)).collect()
}

/// The log-spaced grid from `f_min_hz` to `f_max_hz` with `ppd` points per decade, Hz.
///
/// Empty when the bounds are not finite, positive and ordered, or `ppd` is 0; the points are
/// counted without overflow (the callers bound `ppd`, [`SpectralOptions::check`]).
pub fn log_grid(f_min_hz: f64, f_max_hz: f64, ppd: usize) -> Vec<f64> {
    let decades = (f_max_hz / f_min_hz).log10();
    if !(decades.is_finite() && decades >= 0.0 && f_min_hz > 0.0) || ppd == 0 {
        return Vec::new();
    }
    let n = ((decades * ppd as f64).floor() as usize).saturating_add(1);
    (0..n).map(|k| f_min_hz * 10f64.powf(k as f64 / ppd as f64)).collect()
}

/// Estimates the frequency responses of every output to every input (module doc).
///
/// `stretches`: contiguous stretches sampled every `dt_s` seconds, each with the channels
/// `inputs` then `outputs` (names). Every window lies inside one stretch.
///
/// # Errors
/// [`SpectralError::Option`] for a bad overlap, window length (longer than the longest
/// stretch, or shorter than 4 samples) or frequency range; [`SpectralError::Data`] for
/// stretches of the wrong shape or non-finite values; [`SpectralError::NotExcited`] for an
/// input whose spectra are singular at every grid frequency.
pub fn frequency_responses(
    stretches: &[Stretch],
    inputs: &[String],
    outputs: &[String],
    dt_s: f64,
    opts: &SpectralOptions,
) -> Result<FrequencyResponses, SpectralError> {
    let plan = Plan::new(stretches, inputs.len() + outputs.len(), dt_s, opts)?;
    let cells: Vec<Vec<Cell>> =
        plan.windows.iter().map(|&n| plan.window_cells(stretches, n)).collect();
    let m = inputs.len();
    let mut pairs = Vec::new();
    for (o, name) in outputs.iter().enumerate() {
        let chans: Vec<usize> = (0..m).chain(std::iter::once(m + o)).collect();
        let per_freq: Vec<Option<Solved>> = (0..plan.grid.len())
            .map(|k| composite(cells.iter().filter_map(|c| c[k].pick(&chans)), m))
            .collect();
        for (i, input) in inputs.iter().enumerate() {
            pairs.push(pair(input, name, &plan.grid, &per_freq, i));
        }
    }
    for (i, input) in inputs.iter().enumerate() {
        let mine = || pairs.iter().filter(|p| p.input == *input);
        let why = if is_constant(stretches, i) {
            Some("constant (no variation beyond round-off)".to_string())
        } else if !mine().any(|p| p.re.iter().any(|v| v.is_finite())) {
            Some("it moves only with the other inputs".to_string())
        } else {
            None
        };
        if let Some(why) = why {
            return Err(SpectralError::NotExcited {
                input: input.clone(),
                why,
                f_lo_hz: plan.grid.first().copied().unwrap_or(f64::NAN),
                f_hi_hz: plan.grid.last().copied().unwrap_or(f64::NAN),
            });
        }
    }
    Ok(FrequencyResponses {
        pairs,
        window_lengths_s: plan.windows.iter().map(|&n| n as f64 * dt_s).collect(),
        overlap: opts.overlap,
        dt_s,
    })
}

/// The checked options: window lengths in samples and the grid.
struct Plan {
    windows: Vec<usize>,
    grid: Vec<f64>,
    dt_s: f64,
    overlap: f64,
    channels: usize,
    ppd: usize,
}

impl Plan {
    fn new(
        stretches: &[Stretch],
        channels: usize,
        dt_s: f64,
        opts: &SpectralOptions,
    ) -> Result<Self, SpectralError> {
        let opt = |option: &'static str, reason: String| SpectralError::Option { option, reason };
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(SpectralError::Data(format!("sample interval {dt_s} s is not positive")));
        }
        opts.check()?;
        check_stretches(stretches, channels)?;
        let longest = stretches.iter().map(|s| s[0].len()).max().unwrap_or(0);
        let longest_s = longest as f64 * dt_s;
        let lengths = if opts.window_lengths_s.is_empty() {
            default_window_lengths(longest_s)
        } else {
            opts.window_lengths_s.clone()
        };
        let mut windows = Vec::new();
        if opts.window_lengths_s.is_empty() && longest < 64 {
            // The shortest default window is T/16; below 64 samples it would hold fewer than 4,
            // and an error naming the window lengths would name an option nobody gave.
            return Err(SpectralError::Data(format!(
                "the longest contiguous stretch of data holds {longest} samples ({} s): the default spectral windows (half of it down to a sixteenth) need at least 64; give longer time windows or a longer record",
                short(longest_s)
            )));
        }
        for &t in &lengths {
            let n = (t / dt_s).round();
            if !(n.is_finite() && n >= 4.0) {
                return Err(opt(
                    "window_lengths_s",
                    format!("{} s is shorter than 4 samples of {} s", short(t), short(dt_s)),
                ));
            }
            if n as usize > longest {
                return Err(opt(
                    "window_lengths_s",
                    format!(
                        "{t} s is longer than the longest contiguous stretch of data ({longest_s:.3} s)"
                    ),
                ));
            }
            windows.push(n as usize);
        }
        windows.sort_unstable_by(|a, b| b.cmp(a));
        windows.dedup();
        let t_max = windows[0] as f64 * dt_s;
        let f_nyq = 0.5 / dt_s;
        let f_min = opts.f_min_hz.unwrap_or(2.0 / t_max);
        let f_max = opts.f_max_hz.unwrap_or(0.2 / dt_s);
        if !(f_min > 0.0 && f_min.is_finite()) {
            return Err(opt("f_min_hz", format!("{} Hz is not positive", short(f_min))));
        }
        if f_min < 2.0 / t_max * (1.0 - 1e-9) {
            return Err(opt(
                "f_min_hz",
                format!(
                    "{} Hz is below 2/T of the longest window ({} Hz for {} s): a window must hold two periods of the lowest frequency",
                    short(f_min),
                    short(2.0 / t_max),
                    short(t_max)
                ),
            ));
        }
        if !(f_max > f_min && f_max < f_nyq) {
            return Err(opt(
                "f_max_hz",
                format!(
                    "{} Hz must lie above the lowest frequency {} Hz and below the Nyquist frequency {} Hz",
                    short(f_max),
                    short(f_min),
                    short(f_nyq)
                ),
            ));
        }
        let grid = log_grid(f_min, f_max, opts.points_per_decade);
        if grid.is_empty() {
            return Err(opt(
                "points_per_decade",
                format!("no grid frequency from {} to {} Hz", short(f_min), short(f_max)),
            ));
        }
        Ok(Self {
            windows,
            grid,
            dt_s,
            overlap: opts.overlap,
            channels,
            ppd: opts.points_per_decade,
        })
    }

    /// Cell edges (Hz) of grid point `k`: the geometric midpoints to its neighbours.
    fn edges(&self, k: usize) -> (f64, f64) {
        let half = 10f64.powf(0.5 / self.ppd as f64);
        (self.grid[k] / half, self.grid[k] * half)
    }

    /// The averaged spectral matrix of every grid cell for windows of `n` samples.
    fn window_cells(&self, stretches: &[Stretch], n: usize) -> Vec<Cell> {
        let c = self.channels;
        let df = 1.0 / (n as f64 * self.dt_s);
        let t_w = n as f64 * self.dt_s;
        let hop = ((n as f64 * (1.0 - self.overlap)).round() as usize).max(1);
        let w: Vec<f64> =
            (0..n).map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / n as f64).cos()).collect();
        let sum_w2: f64 = w.iter().map(|v| v * v).sum();
        // Per cell: the FFT bins inside it, or none (then the transform at the grid frequency).
        let bins: Vec<Option<(usize, usize)>> = (0..self.grid.len())
            .map(|k| {
                if self.grid[k] < 2.0 / t_w * (1.0 - 1e-9) {
                    return None;
                }
                let (lo, hi) = self.edges(k);
                let (a, b) = ((lo / df).ceil() as usize, (hi / df).ceil() as usize);
                Some((a, b.max(a)))
            })
            .collect();
        let top = bins.iter().flatten().map(|&(_, b)| b).max().unwrap_or(0).min(n / 2 + 1);
        let mut acc = vec![vec![Complex64::new(0.0, 0.0); c * c]; self.grid.len()];
        let mut windows = 0usize;
        let mut n_eff = 0.0;
        let fft = FftPlanner::new().plan_fft_forward(n);
        let mut spectra = vec![vec![Complex64::new(0.0, 0.0); n]; c];
        let mut direct = vec![vec![Complex64::new(0.0, 0.0); self.grid.len()]; c];
        for s in stretches {
            let len = s[0].len();
            if len < n {
                continue;
            }
            let k_here = (len - n) / hop + 1;
            n_eff += effective_windows(&w, hop, k_here);
            for start in (0..k_here).map(|j| j * hop) {
                windows += 1;
                for ch in 0..c {
                    let x = tapered(&s[ch][start..start + n], &w);
                    for (k, cell) in bins.iter().enumerate() {
                        if matches!(cell, Some((a, b)) if a == b) {
                            direct[ch][k] = dft_at(&x, self.grid[k] * self.dt_s);
                        }
                    }
                    let buf = &mut spectra[ch];
                    buf.iter_mut().zip(&x).for_each(|(z, &v)| *z = Complex64::new(v, 0.0));
                    fft.process(buf);
                }
                for (k, cell) in bins.iter().enumerate() {
                    match *cell {
                        None => {}
                        Some((a, b)) if a == b => add_outer(&mut acc[k], &direct, k, c),
                        Some((a, b)) => {
                            for bin in a..b.min(top) {
                                add_outer_bin(&mut acc[k], &spectra, bin, c);
                            }
                        }
                    }
                }
            }
        }
        let scale = 2.0 * self.dt_s / (windows.max(1) as f64 * sum_w2);
        bins.iter()
            .zip(acc)
            .map(|(cell, mut g)| match *cell {
                None => Cell::default(),
                Some((a, b)) => {
                    let nbins = if a == b { 1 } else { b.min(top).saturating_sub(a) };
                    if nbins == 0 || windows == 0 {
                        return Cell::default();
                    }
                    g.iter_mut().for_each(|z| *z *= scale / nbins as f64);
                    Cell { g, c, n_d: n_eff * effective_bins(&w, nbins) }
                }
            })
            .collect()
    }
}

/// Whether channel `c` varies by no more than round-off (`1e-9` of its magnitude) in every
/// stretch.
fn is_constant(stretches: &[Stretch], c: usize) -> bool {
    stretches.iter().all(|s| {
        let (lo, hi) = s[c]
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        hi - lo <= 1e-9 * lo.abs().max(hi.abs())
    })
}

fn check_stretches(stretches: &[Stretch], channels: usize) -> Result<(), SpectralError> {
    if stretches.is_empty() {
        return Err(SpectralError::Data("no data".into()));
    }
    for (j, s) in stretches.iter().enumerate() {
        if s.len() != channels {
            return Err(SpectralError::Data(format!(
                "stretch {j} has {} channels, expected {channels}",
                s.len()
            )));
        }
        let len = s[0].len();
        for (ch, v) in s.iter().enumerate() {
            if v.len() != len {
                return Err(SpectralError::Data(format!(
                    "stretch {j}: channel {ch} has {} samples, channel 0 {len}",
                    v.len()
                )));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(SpectralError::Data(format!(
                    "stretch {j}: channel {ch} sample {k} is not finite"
                )));
            }
        }
    }
    Ok(())
}

/// `x` with its least-squares line removed, times `w`.
fn tapered(x: &[f64], w: &[f64]) -> Vec<f64> {
    let n = x.len() as f64;
    let tm = 0.5 * (n - 1.0);
    let mean = x.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (k, v) in x.iter().enumerate() {
        let d = k as f64 - tm;
        sxy += d * (v - mean);
        sxx += d * d;
    }
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    x.iter()
        .zip(w)
        .enumerate()
        .map(|(k, (v, wk))| (v - mean - slope * (k as f64 - tm)) * wk)
        .collect()
}

/// `Σ x[k] e^{−i2π ν k}` at the normalised frequency `ν = f Δt`, by a rotating phasor.
fn dft_at(x: &[f64], nu: f64) -> Complex64 {
    let step = Complex64::from_polar(1.0, -2.0 * PI * nu);
    let mut z = Complex64::new(1.0, 0.0);
    let mut sum = Complex64::new(0.0, 0.0);
    for (k, &v) in x.iter().enumerate() {
        sum += z * v;
        z *= step;
        if k % 1024 == 1023 {
            z = Complex64::from_polar(1.0, -2.0 * PI * nu * (k + 1) as f64);
        }
    }
    sum
}

fn add_outer(acc: &mut [Complex64], x: &[Vec<Complex64>], k: usize, c: usize) {
    for a in 0..c {
        let xa = x[a][k].conj();
        for b in 0..c {
            acc[a * c + b] += xa * x[b][k];
        }
    }
}

fn add_outer_bin(acc: &mut [Complex64], x: &[Vec<Complex64>], bin: usize, c: usize) {
    for a in 0..c {
        let xa = x[a][bin].conj();
        for b in 0..c {
            acc[a * c + b] += xa * x[b][bin];
        }
    }
}

/// Welch's equivalent number of independent windows among `k` windows of taper `w` stepped by
/// `hop`: `k / (1 + 2 Σ_j (1 − j/k) ρ_j²)`, `ρ_j = Σ w[i] w[i + j·hop] / Σ w²`.
fn effective_windows(w: &[f64], hop: usize, k: usize) -> f64 {
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let mut sum = 0.0;
    for j in 1..k {
        let shift = j * hop;
        if shift >= w.len() {
            break;
        }
        let rho: f64 = w.iter().zip(&w[shift..]).map(|(a, b)| a * b).sum::<f64>() / s2;
        sum += (1.0 - j as f64 / k as f64) * rho * rho;
    }
    k as f64 / (1.0 + 2.0 * sum)
}

/// Equivalent number of independent bins among `b` adjacent FFT bins of a `w`-tapered window:
/// `b / (1 + 2 Σ_j (1 − j/b) |r_j|²)`, `r_j = Σ w[i]² e^{−i2π j i/N} / Σ w²` the correlation of
/// bins `j` apart for white data.
fn effective_bins(w: &[f64], b: usize) -> f64 {
    let n = w.len();
    let w2: Vec<f64> = w.iter().map(|v| v * v).collect();
    let s2: f64 = w2.iter().sum();
    let mut sum = 0.0;
    for j in 1..b.min(8) {
        let r = dft_at(&w2, j as f64 / n as f64).norm() / s2;
        sum += (1.0 - j as f64 / b as f64) * r * r;
    }
    b as f64 / (1.0 + 2.0 * sum)
}

/// One window length's averaged spectral matrix at one grid cell (`c × c`, row-major,
/// `g[a·c + b] = G_ab`) and its number of independent averages.
#[derive(Debug, Clone, Default)]
struct Cell {
    g: Vec<Complex64>,
    c: usize,
    n_d: f64,
}

impl Cell {
    /// The sub-matrix of channels `chans` (inputs then one output), with `n_d`.
    fn pick(&self, chans: &[usize]) -> Option<(Vec<Complex64>, f64)> {
        if self.g.is_empty() {
            return None;
        }
        let k = chans.len();
        let mut s = vec![Complex64::new(0.0, 0.0); k * k];
        for (i, &a) in chans.iter().enumerate() {
            for (j, &b) in chans.iter().enumerate() {
                s[i * k + j] = self.g[a * self.c + b];
            }
        }
        Some((s, self.n_d))
    }
}

/// The solution at one frequency from a spectral matrix of `m` inputs and one output.
#[derive(Debug, Clone)]
struct Solved {
    h: Vec<Complex64>,
    partial: Vec<f64>,
    multiple: f64,
    eps: Vec<f64>,
}

/// Solves `S` (`(m+1)²`, inputs then the output) with `n_d` averages (module doc).
fn solve(s: &[Complex64], m: usize, n_d: f64) -> Option<Solved> {
    let k = m + 1;
    let gxx: Vec<Complex64> = (0..m).flat_map(|a| (0..m).map(move |b| s[a * k + b])).collect();
    let gxy: Vec<Complex64> = (0..m).map(|a| s[a * k + m]).collect();
    let gyy = s[m * k + m].re;
    let inv = invert(&gxx, m)?;
    let h: Vec<Complex64> = (0..m).map(|a| (0..m).map(|b| inv[a * m + b] * gxy[b]).sum()).collect();
    let explained: f64 = (0..m).map(|a| (gxy[a].conj() * h[a]).re).sum();
    if gyy.is_nan() || gyy <= 0.0 {
        return None;
    }
    let multiple = (explained / gyy).clamp(0.0, 1.0);
    let d = invert(s, k);
    let partial = (0..m)
        .map(|i| match (&d, m) {
            (_, 1) => multiple,
            (Some(d), _) => {
                (d[i * k + m].norm_sqr() / (d[i * k + i].re * d[m * k + m].re)).clamp(0.0, 1.0)
            }
            (None, _) => 1.0,
        })
        .collect();
    let gnn = (1.0 - multiple) * gyy;
    let eps =
        (0..m).map(|i| (gnn * inv[i * m + i].re / (2.0 * n_d * h[i].norm_sqr())).sqrt()).collect();
    Some(Solved { h, partial, multiple, eps })
}

/// The composite of the window lengths' matrices at one frequency, weighted by `1/ε²` of each
/// window's multiple coherence (module doc), solved.
fn composite(cells: impl Iterator<Item = (Vec<Complex64>, f64)>, m: usize) -> Option<Solved> {
    let cells: Vec<(Vec<Complex64>, f64)> = cells.collect();
    let mut sum: Option<Vec<Complex64>> = None;
    let (mut wsum, mut nd_sum) = (0.0, 0.0);
    for (s, n_d) in &cells {
        let Some(one) = solve(s, m, *n_d) else { continue };
        let g = one.multiple.max(1e-12);
        let eps2 = (1.0 - g) / (g * 2.0 * n_d);
        let w = 1.0 / eps2.max(1e-12);
        let acc = sum.get_or_insert_with(|| vec![Complex64::new(0.0, 0.0); s.len()]);
        acc.iter_mut().zip(s).for_each(|(a, v)| *a += v * w);
        wsum += w;
        nd_sum += w * n_d;
    }
    let mut s = sum?;
    s.iter_mut().for_each(|v| *v /= wsum);
    solve(&s, m, nd_sum / wsum)
}

/// Inverse of the `n × n` complex matrix `a` (row-major) by Gauss–Jordan elimination with
/// partial pivoting; `None` when a pivot falls below `1e-10` of the largest diagonal element.
fn invert(a: &[Complex64], n: usize) -> Option<Vec<Complex64>> {
    let scale = (0..n).map(|i| a[i * n + i].norm()).fold(0.0, f64::max);
    if scale.is_nan() || scale <= 0.0 || !scale.is_finite() {
        return None;
    }
    let mut m = a.to_vec();
    let mut inv = vec![Complex64::new(0.0, 0.0); n * n];
    (0..n).for_each(|i| inv[i * n + i] = Complex64::new(1.0, 0.0));
    for col in 0..n {
        let p =
            (col..n).max_by(|&x, &y| m[x * n + col].norm().total_cmp(&m[y * n + col].norm()))?;
        if m[p * n + col].norm() < 1e-10 * scale {
            return None;
        }
        for j in 0..n {
            m.swap(col * n + j, p * n + j);
            inv.swap(col * n + j, p * n + j);
        }
        let d = m[col * n + col];
        for j in 0..n {
            m[col * n + j] /= d;
            inv[col * n + j] /= d;
        }
        for r in (0..n).filter(|&r| r != col) {
            let f = m[r * n + col];
            for j in 0..n {
                let (mc, ic) = (m[col * n + j], inv[col * n + j]);
                m[r * n + j] -= f * mc;
                inv[r * n + j] -= f * ic;
            }
        }
    }
    Some(inv)
}

/// The arrays of input `i` from the solutions per grid frequency.
fn pair(input: &str, output: &str, grid: &[f64], sol: &[Option<Solved>], i: usize) -> PairResponse {
    let get = |f: &dyn Fn(&Solved) -> f64| -> Vec<f64> {
        sol.iter().map(|s| s.as_ref().map_or(f64::NAN, f)).collect()
    };
    let re = get(&|s| s.h[i].re);
    let im = get(&|s| s.h[i].im);
    let eps = get(&|s| s.eps[i]);
    let phase = unwrap_deg(&re, &im);
    PairResponse {
        input: input.to_string(),
        output: output.to_string(),
        frequency_hz: grid.to_vec(),
        magnitude_db: re.iter().zip(&im).map(|(a, b)| 20.0 * a.hypot(*b).log10()).collect(),
        phase_deg: phase,
        coherence: get(&|s| s.partial[i]),
        multiple_coherence: get(&|s| s.multiple),
        magnitude_error_db: eps.iter().map(|e| 20.0 * (1.0 + e).log10()).collect(),
        phase_error_deg: eps.iter().map(|e| e.to_degrees()).collect(),
        random_error: eps,
        re,
        im,
    }
}

/// Phase in degrees, unwrapped along the grid (a jump over 180° between successive identified
/// points is taken as a wrap); `NaN` where not identified.
pub fn unwrap_deg(re: &[f64], im: &[f64]) -> Vec<f64> {
    let mut last: Option<f64> = None;
    re.iter()
        .zip(im)
        .map(|(a, b)| {
            let mut p = b.atan2(*a).to_degrees();
            if !p.is_finite() {
                return f64::NAN;
            }
            if let Some(l) = last {
                p += 360.0 * ((l - p) / 360.0).round();
            }
            last = Some(p);
            p
        })
        .collect()
}

#[cfg(test)]
mod tests;
