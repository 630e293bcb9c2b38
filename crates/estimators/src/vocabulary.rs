//! The one aerodynamic model vocabulary: coefficient × term, parameter names
//! `<coefficient>_<term>`, model structures and their presets.
//!
//! A model structure declares, for each of the eight coefficients, which terms explain it
//! (linear in the parameters, Klein & Morelli, *Aircraft System Identification*, AIAA 2006,
//! §5.1 and ch. 12 "model structure determination"):
//!
//! ```text
//! C_k = Σ_j  C_k_j · ξ_j(sample)        e.g.  Cm = Cm_0 + Cm_alpha α + Cm_q q̂ + Cm_de δe
//! ```
//!
//! Terms ξ (all dimensionless or per rad; [`Term::value`]):
//!
//! | term | name | ξ |
//! |---|---|---|
//! | bias | `0` | 1 |
//! | α | `alpha` | α, rad |
//! | β | `beta` | β, rad |
//! | p̂ | `p` | p b / (2V) |
//! | q̂ | `q` | q c̄ / (2V) |
//! | r̂ | `r` | r b / (2V) |
//! | α̇-hat | `alphadot` | α̇ c̄ / (2V) |
//! | δe, δa, δr | `de`, `da`, `dr` | rad |
//! | V/V0 | `V` | V / V0 (Jategaonkar 2015 eq. 5.86) |
//! | α² | `alpha2` | α², rad² |
//! | α·δe | `alpha_de` | α δe, rad² |
//! | α·β | `alpha_beta` | α β, rad² |
//! | q̂0 | `q0` | q c̄ / (2 V0): the pitch rate normalised with the reference speed, as Jategaonkar 2015 eq. 5.86 (HFB-320 test case 4) writes `Cm_q` |
//! | α·p̂, α·q̂, α·r̂ | `alpha_p`, `alpha_q`, `alpha_r` | α p̂, α q̂, α r̂ (rad) |
//! | α·δa, α·δr | `alpha_da`, `alpha_dr` | α δa, α δr, rad² |
//! | (α − k_i)₊ | `alpha_k1` … `alpha_k4` | max(α − k_i, 0), rad: the structure's i-th α knot [`AlphaKnots`] |
//! | M | `mach` | V / a, a the speed of sound at the density altitude ([`AirDataSample::mach`]) |
//! | M² | `mach2` | (V / a)² |
//!
//! The α splines are first-degree truncated power splines (Klein & Morelli 2006 §5.4, SIDPAC
//! `splgen`): with `CL_alpha_k1` in a model, the lift slope is `CL_alpha` below the knot `k1`
//! and `CL_alpha + CL_alpha_k1` above it, and the coefficient is continuous across the knot.
//! The knots belong to the structure ([`ModelStructure::with_knots`]), not to the sample, so
//! every estimator that holds the structure forms the same regressors.
//!
//! The α products are the first-order α-dependence of a derivative (Klein & Morelli 2006 §5.4:
//! a damping or control derivative that varies with α, as the F-16's tables do, Stevens & Lewis
//! 2003 table B-4): with `Cl_alpha_p` in the model, `Cl_p` is the roll damping at α = 0 and
//! the local one at α is `Cl_p + Cl_alpha_p α`.
//!
//! Parameter names follow the field: `Cm_alpha`, `Cm_q`, `Cm_alphadot`, `CL_alpha`, `CY_beta`,
//! `Cl_p`, `Cn_r`, `Cn_dr`, `Cm_V`, `Cm_alpha2`, `CD_0` … Parameters are ordered coefficient by
//! coefficient (order of [`Coefficient::ALL`]) and, within one, term by term (order of
//! [`Term::ALL`]).

use crate::sample::AirDataSample;

/// Most parameters one structure may hold (fixed capacity: estimators stay allocation-free).
pub const MAX_PARAMS: usize = 48;

/// The eight non-dimensional aerodynamic coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Coefficient {
    /// Body-axis axial force `X / (q̄ S)`.
    CX,
    /// Body-axis side force `Y / (q̄ S)`.
    CY,
    /// Body-axis normal force `Z / (q̄ S)`.
    CZ,
    /// Lift, stability axes: `−CZ cos α + CX sin α`.
    CL,
    /// Drag, stability axes: `−CX cos α − CZ sin α`.
    CD,
    /// Rolling moment about the CG, body axes, `L / (q̄ S b)`.
    Cl,
    /// Pitching moment about the CG, `M / (q̄ S c̄)`.
    Cm,
    /// Yawing moment about the CG, body axes, `N / (q̄ S b)`.
    Cn,
}

impl Coefficient {
    /// The first channel or constant the measured value of this coefficient
    /// ([`AirDataSample::measured_coefficients`]) needs that `s` lacks, by its field name
    /// (`Ixz_kgm2`, `b_m`, `pdot_rad_s2` …, as `AeroidentSample` and the mapping's sample
    /// fields spell it), so that a refusal names what to supply rather than the coefficient;
    /// `None` when the value can be formed.
    pub fn missing_field(self, s: &AirDataSample) -> Option<&'static str> {
        use Coefficient as C;
        let k = &s.constants;
        if !(s.qbar_pa > 0.0 && s.qbar_pa.is_finite()) {
            return Some("qbar_pa");
        }
        if !(k.S_m2 > 0.0 && k.S_m2.is_finite()) {
            return Some("S_m2");
        }
        let needs: &[(&'static str, bool)] = match self {
            C::CX => &[("ax_mps2", s.ax_mps2.is_some())],
            C::CY => &[("ay_mps2", s.ay_mps2.is_some())],
            C::CZ => &[("az_mps2", s.az_mps2.is_some())],
            C::CL | C::CD => &[("ax_mps2", s.ax_mps2.is_some()), ("az_mps2", s.az_mps2.is_some())],
            C::Cm => &[
                ("qdot_rad_s2", s.qdot_rad_s2.is_some()),
                ("Iyy_kgm2", k.Iyy_kgm2.is_some()),
                ("cbar_m", k.cbar_m.is_some()),
            ],
            C::Cl | C::Cn => &[
                ("Ixx_kgm2", k.Ixx_kgm2.is_some()),
                ("Iyy_kgm2", k.Iyy_kgm2.is_some()),
                ("Izz_kgm2", k.Izz_kgm2.is_some()),
                ("Ixz_kgm2", k.Ixz_kgm2.is_some()),
                ("b_m", k.b_m.is_some()),
                ("p_rad_s", s.p_rad_s.is_some()),
                ("q_rad_s", s.q_rad_s.is_some()),
                ("r_rad_s", s.r_rad_s.is_some()),
                ("pdot_rad_s2", s.pdot_rad_s2.is_some()),
                ("rdot_rad_s2", s.rdot_rad_s2.is_some()),
            ],
        };
        needs.iter().find(|(_, present)| !present).map(|(field, _)| *field)
    }

    /// All eight, in parameter order (and the order of
    /// [`CoefficientValues`](crate::sample::CoefficientValues)).
    pub const ALL: [Coefficient; 8] = [
        Coefficient::CX,
        Coefficient::CY,
        Coefficient::CZ,
        Coefficient::CL,
        Coefficient::CD,
        Coefficient::Cl,
        Coefficient::Cm,
        Coefficient::Cn,
    ];

    /// Index in [`Coefficient::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The name as written in parameter names: `CX`, `CY`, `CZ`, `CL`, `CD`, `Cl`, `Cm`, `Cn`.
    pub fn name(self) -> &'static str {
        COEFFICIENT_NAMES[self.index()]
    }

    /// Parses a [`Coefficient::name`] (case-sensitive: `CL` is lift, `Cl` rolling moment).
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == s)
    }
}

const COEFFICIENT_NAMES: [&str; 8] = ["CX", "CY", "CZ", "CL", "CD", "Cl", "Cm", "Cn"];

/// Number of terms in the vocabulary.
pub const N_TERMS: usize = 26;

/// One quantity a term's regressor is formed from ([`Term::inputs`]): a sample channel, an
/// aircraft constant, the structure's α knot, or the air density.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TermInput {
    /// Angle of attack α (always in a sample).
    Alpha,
    /// Sideslip β.
    Beta,
    /// Roll rate p.
    P,
    /// Pitch rate q.
    Q,
    /// Yaw rate r.
    R,
    /// α̇, recorded or differentiated from α.
    Alphadot,
    /// Elevator δe.
    De,
    /// Aileron δa.
    Da,
    /// Rudder δr.
    Dr,
    /// Airspeed V (always in a sample).
    Vt,
    /// Mean aerodynamic chord c̄ (constant).
    Cbar,
    /// Wing span b (constant).
    Span,
    /// Reference airspeed V0 (constant).
    V0,
    /// The structure's α knot of a spline term.
    Knot,
    /// Air density ρ (from the sample, or from q̄ and V), for the speed of sound.
    Density,
}

impl TermInput {
    /// The sample field it is read from (`alpha_rad` …; [`AirDataSample::field`]'s names),
    /// `None` for a constant, the knot and the density.
    pub fn field(self) -> Option<&'static str> {
        Some(match self {
            TermInput::Alpha => "alpha_rad",
            TermInput::Beta => "beta_rad",
            TermInput::P => "p_rad_s",
            TermInput::Q => "q_rad_s",
            TermInput::R => "r_rad_s",
            TermInput::Alphadot => "alphadot_rad_s",
            TermInput::De => "de_rad",
            TermInput::Da => "da_rad",
            TermInput::Dr => "dr_rad",
            TermInput::Vt => "vt_mps",
            TermInput::Cbar | TermInput::Span | TermInput::V0 => return None,
            TermInput::Knot | TermInput::Density => return None,
        })
    }

    /// Whether every sample has it (α and V are required channels), so that no record lacks
    /// it.
    pub fn always_present(self) -> bool {
        matches!(self, TermInput::Alpha | TermInput::Vt)
    }

    /// Whether sample `s` has it (the knot is the structure's, not the sample's: present).
    pub fn present(self, s: &AirDataSample) -> bool {
        let c = &s.constants;
        match self {
            TermInput::Cbar => c.cbar_m.is_some(),
            TermInput::Span => c.b_m.is_some(),
            TermInput::V0 => c.v0_mps.is_some(),
            TermInput::Knot => true,
            TermInput::Density => s.speed_of_sound_mps().is_some(),
            other => other.always_present() || other.field().is_some_and(|f| s.field(f).is_some()),
        }
    }

    /// Its name among the sample's fields and constants (`p_rad_s`, `b_m`, `v0_mps` …, as
    /// `AeroidentSample` spells them), for a refusal that names what to supply.
    pub fn sample_name(self) -> &'static str {
        match self {
            TermInput::Cbar => "cbar_m",
            TermInput::Span => "b_m",
            TermInput::V0 => "v0_mps",
            TermInput::Knot => "alpha knot",
            TermInput::Density => "rho_kgpm3 (density outside the standard atmosphere)",
            other => other.field().unwrap_or("regressor"),
        }
    }

    /// What a record must give for it, in the mapping's words.
    pub fn needs(self) -> &'static str {
        match self {
            TermInput::Alpha => "alpha",
            TermInput::Beta => "beta",
            TermInput::P => "p",
            TermInput::Q => "q",
            TermInput::R => "r",
            TermInput::Alphadot => "alphadot (or alpha to differentiate)",
            TermInput::De => "de",
            TermInput::Da => "da",
            TermInput::Dr => "dr",
            TermInput::Vt => "vt",
            TermInput::Cbar => "cbar",
            TermInput::Span => "the span b",
            TermInput::V0 => "v0",
            TermInput::Knot => "its alpha knot in the model",
            TermInput::Density => "a density within the standard atmosphere (-1 to 20 km)",
        }
    }
}

/// One regressor of a linear coefficient model (table in the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Term {
    /// Constant 1 (the `_0` parameter).
    Bias,
    /// `α`, rad.
    Alpha,
    /// `β`, rad.
    Beta,
    /// `p̂ = p b / (2V)`.
    P,
    /// `q̂ = q c̄ / (2V)`.
    Q,
    /// `r̂ = r b / (2V)`.
    R,
    /// `α̇ c̄ / (2V)`.
    Alphadot,
    /// `δe`, rad.
    De,
    /// `δa`, rad.
    Da,
    /// `δr`, rad.
    Dr,
    /// `V / V0`.
    V,
    /// `α²`, rad².
    Alpha2,
    /// `α δe`, rad².
    AlphaDe,
    /// `α β`, rad².
    AlphaBeta,
    /// `q c̄ / (2 V0)`: pitch rate normalised with the constant reference speed `V0`
    /// (Jategaonkar 2015 eq. 5.86, the HFB-320 model of test case 4), not with `V` as [`Term::Q`].
    Q0,
    /// `α p̂`, rad: the α-dependence of the `p̂` derivative.
    AlphaP,
    /// `α q̂`, rad.
    AlphaQ,
    /// `α r̂`, rad.
    AlphaR,
    /// `α δa`, rad².
    AlphaDa,
    /// `α δr`, rad².
    AlphaDr,
    /// `(α − k1)₊ = max(α − k1, 0)`, rad: the first α knot of the structure ([`AlphaKnots`]).
    AlphaK1,
    /// `(α − k2)₊`, rad.
    AlphaK2,
    /// `(α − k3)₊`, rad.
    AlphaK3,
    /// `(α − k4)₊`, rad.
    AlphaK4,
    /// Mach number `V / a`, `a` the speed of sound at the density altitude
    /// ([`AirDataSample::mach`]).
    Mach,
    /// `M²`.
    Mach2,
}

const TERM_NAMES: [&str; N_TERMS] = [
    "0",
    "alpha",
    "beta",
    "p",
    "q",
    "r",
    "alphadot",
    "de",
    "da",
    "dr",
    "V",
    "alpha2",
    "alpha_de",
    "alpha_beta",
    "q0",
    "alpha_p",
    "alpha_q",
    "alpha_r",
    "alpha_da",
    "alpha_dr",
    "alpha_k1",
    "alpha_k2",
    "alpha_k3",
    "alpha_k4",
    "mach",
    "mach2",
];

macro_rules! param_names {
    ($($c:literal),*) => {
        [$([
            concat!($c, "_0"), concat!($c, "_alpha"), concat!($c, "_beta"), concat!($c, "_p"),
            concat!($c, "_q"), concat!($c, "_r"), concat!($c, "_alphadot"), concat!($c, "_de"),
            concat!($c, "_da"), concat!($c, "_dr"), concat!($c, "_V"), concat!($c, "_alpha2"),
            concat!($c, "_alpha_de"), concat!($c, "_alpha_beta"), concat!($c, "_q0"),
            concat!($c, "_alpha_p"), concat!($c, "_alpha_q"), concat!($c, "_alpha_r"),
            concat!($c, "_alpha_da"), concat!($c, "_alpha_dr"), concat!($c, "_alpha_k1"),
            concat!($c, "_alpha_k2"), concat!($c, "_alpha_k3"), concat!($c, "_alpha_k4"),
            concat!($c, "_mach"), concat!($c, "_mach2"),
        ]),*]
    };
}

/// Every parameter name, `[coefficient][term]`.
const PARAM_NAMES: [[&str; N_TERMS]; 8] =
    param_names!("CX", "CY", "CZ", "CL", "CD", "Cl", "Cm", "Cn");

impl Term {
    /// All terms, in parameter order.
    pub const ALL: [Term; N_TERMS] = [
        Term::Bias,
        Term::Alpha,
        Term::Beta,
        Term::P,
        Term::Q,
        Term::R,
        Term::Alphadot,
        Term::De,
        Term::Da,
        Term::Dr,
        Term::V,
        Term::Alpha2,
        Term::AlphaDe,
        Term::AlphaBeta,
        Term::Q0,
        Term::AlphaP,
        Term::AlphaQ,
        Term::AlphaR,
        Term::AlphaDa,
        Term::AlphaDr,
        Term::AlphaK1,
        Term::AlphaK2,
        Term::AlphaK3,
        Term::AlphaK4,
        Term::Mach,
        Term::Mach2,
    ];

    /// Index in [`Term::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// The name as written after the underscore of a parameter name (`alpha`, `q`, `0` …).
    pub fn name(self) -> &'static str {
        TERM_NAMES[self.index()]
    }

    /// Parses a [`Term::name`].
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == s)
    }

    /// The two factors of a product term (`alpha2`: α twice; `alpha_p`: α and p̂ …), `None`
    /// for a first-order term.
    pub fn factors(self) -> Option<(Term, Term)> {
        use Term::*;
        let other = match self {
            Alpha2 => Alpha,
            AlphaBeta => Beta,
            AlphaDe => De,
            AlphaP => P,
            AlphaQ => Q,
            AlphaR => R,
            AlphaDa => Da,
            AlphaDr => Dr,
            _ => return None,
        };
        Some((Alpha, other))
    }

    /// What the term's regressor ([`Term::value`]) is formed from: the sample channels and
    /// aircraft constants it reads, besides the airspeed that normalises a rate
    /// (`p̂ = p b / 2V`). The one statement of what a term needs from a record: the replay's
    /// model check, the constant-channel warning and the flight model's inputs read it.
    pub fn inputs(self) -> &'static [TermInput] {
        use TermInput as I;
        match self {
            Term::Bias => &[],
            Term::Alpha | Term::Alpha2 => &[I::Alpha],
            Term::Beta => &[I::Beta],
            Term::P => &[I::P, I::Span],
            Term::Q => &[I::Q, I::Cbar],
            Term::R => &[I::R, I::Span],
            Term::Alphadot => &[I::Alphadot, I::Cbar],
            Term::De => &[I::De],
            Term::Da => &[I::Da],
            Term::Dr => &[I::Dr],
            Term::V => &[I::Vt, I::V0],
            Term::Q0 => &[I::Q, I::Cbar, I::V0],
            Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => &[I::Alpha, I::Knot],
            Term::Mach | Term::Mach2 => &[I::Vt, I::Density],
            Term::AlphaDe => &[I::Alpha, I::De],
            Term::AlphaBeta => &[I::Alpha, I::Beta],
            Term::AlphaP => &[I::Alpha, I::P, I::Span],
            Term::AlphaQ => &[I::Alpha, I::Q, I::Cbar],
            Term::AlphaR => &[I::Alpha, I::R, I::Span],
            Term::AlphaDa => &[I::Alpha, I::Da],
            Term::AlphaDr => &[I::Alpha, I::Dr],
        }
    }

    /// The knot number (0-based, in [`AlphaKnots`]) of an α spline term, `None` for the others.
    pub fn knot(self) -> Option<usize> {
        match self {
            Term::AlphaK1 => Some(0),
            Term::AlphaK2 => Some(1),
            Term::AlphaK3 => Some(2),
            Term::AlphaK4 => Some(3),
            _ => None,
        }
    }

    /// The lower-order terms a power or product term is built from (`alpha2` → `alpha`,
    /// `alpha_de` → `alpha`, `de`, a spline → `alpha`, `mach2` → `mach`); empty for the others.
    /// A structure keeps a term's parents beside it (the model hierarchy of Klein & Morelli
    /// 2006 §5.4 and SIDPAC's `swr`): `α²` without `α` makes the curvature carry the slope.
    pub fn parents(self) -> &'static [Term] {
        match self {
            Term::Alpha2 | Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => {
                &[Term::Alpha]
            }
            Term::AlphaDe => &[Term::Alpha, Term::De],
            Term::AlphaBeta => &[Term::Alpha, Term::Beta],
            Term::AlphaP => &[Term::Alpha, Term::P],
            Term::AlphaQ => &[Term::Alpha, Term::Q],
            Term::AlphaR => &[Term::Alpha, Term::R],
            Term::AlphaDa => &[Term::Alpha, Term::Da],
            Term::AlphaDr => &[Term::Alpha, Term::Dr],
            Term::Mach2 => &[Term::Mach],
            _ => &[],
        }
    }

    /// The α spline term of knot `i` (0-based), `None` past [`MAX_KNOTS`].
    pub fn spline(i: usize) -> Option<Term> {
        [Term::AlphaK1, Term::AlphaK2, Term::AlphaK3, Term::AlphaK4].get(i).copied()
    }

    /// The first of its [`inputs`](Self::inputs) sample `s` lacks, by its sample name
    /// ([`TermInput::sample_name`]), so that a refusal names what to supply; `None` when every
    /// input is present.
    pub fn missing_field(self, s: &AirDataSample) -> Option<&'static str> {
        self.inputs().iter().find(|i| !i.present(s)).map(|i| i.sample_name())
    }

    /// The regressor value `ξ` of this term at sample `s` (module doc), with the α knots of the
    /// structure; `None` when a channel, constant or knot it needs is absent (e.g. `p̂` without
    /// `p` or the span, `alpha_k2` with one knot).
    pub fn value(self, s: &AirDataSample, knots: &AlphaKnots) -> Option<f64> {
        let two_v = 2.0 * s.vt_mps;
        let c = &s.constants;
        Some(match self {
            Term::Bias => 1.0,
            Term::Alpha => s.alpha_rad,
            Term::Beta => s.beta_rad?,
            Term::P => s.p_rad_s? * c.b_m? / two_v,
            Term::Q => s.q_rad_s? * c.cbar_m? / two_v,
            Term::R => s.r_rad_s? * c.b_m? / two_v,
            Term::Alphadot => s.alphadot_rad_s? * c.cbar_m? / two_v,
            Term::De => s.de_rad?,
            Term::Da => s.da_rad?,
            Term::Dr => s.dr_rad?,
            Term::V => s.vt_mps / c.v0_mps?,
            Term::Q0 => s.q_rad_s? * c.cbar_m? / (2.0 * c.v0_mps?),
            Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => {
                spline(s.alpha_rad, knots.get(self.knot()?)?)
            }
            Term::Mach => s.mach()?,
            Term::Mach2 => s.mach()? * s.mach()?,
            Term::Alpha2
            | Term::AlphaDe
            | Term::AlphaBeta
            | Term::AlphaP
            | Term::AlphaQ
            | Term::AlphaR
            | Term::AlphaDa
            | Term::AlphaDr => {
                let (a, b) = self.factors()?;
                a.value(s, knots)? * b.value(s, knots)?
            }
        })
    }
}

/// `(α − k)₊ = max(α − k, 0)`, rad.
pub fn spline(alpha_rad: f64, knot_rad: f64) -> f64 {
    if alpha_rad > knot_rad { alpha_rad - knot_rad } else { 0.0 }
}

/// Most α knots one structure holds (one [`Term`] per knot: `alpha_k1` … `alpha_k4`).
pub const MAX_KNOTS: usize = 4;

/// The α knots of a structure's spline terms, rad, strictly ascending, finite, within ±90°.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AlphaKnots {
    rad: [f64; MAX_KNOTS],
    n: usize,
}

/// Why a list of α knots was refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum KnotError {
    /// More than [`MAX_KNOTS`].
    #[error("{0} α knots; at most {MAX_KNOTS} are supported")]
    TooMany(usize),
    /// A knot that is not finite or beyond ±90°.
    #[error("α knot {index} ({} rad) is not a finite angle within ±90°", aeroident_physics::text::Short(*value))]
    NotAnAngle {
        /// 0-based position in the list.
        index: usize,
        /// The value, rad.
        value: f64,
    },
    /// A knot not above the one before it (unsorted or repeated).
    #[error(
        "α knot {index} ({} rad) is not above the one before it: list the knots ascending, each once",
        aeroident_physics::text::Short(*value)
    )]
    NotAscending {
        /// 0-based position in the list.
        index: usize,
        /// The value, rad.
        value: f64,
    },
}

impl AlphaKnots {
    /// No knots.
    pub const NONE: AlphaKnots = AlphaKnots { rad: [0.0; MAX_KNOTS], n: 0 };

    /// The knots `knots_rad`, rad.
    ///
    /// # Errors
    /// [`KnotError`]: more than [`MAX_KNOTS`], a knot not finite or beyond ±90°, or a list not
    /// strictly ascending.
    pub fn new(knots_rad: &[f64]) -> Result<Self, KnotError> {
        if knots_rad.len() > MAX_KNOTS {
            return Err(KnotError::TooMany(knots_rad.len()));
        }
        let mut k = Self::NONE;
        for (index, &value) in knots_rad.iter().enumerate() {
            if !value.is_finite() || value.abs() > core::f64::consts::FRAC_PI_2 {
                return Err(KnotError::NotAnAngle { index, value });
            }
            if index > 0 && value <= knots_rad[index - 1] {
                return Err(KnotError::NotAscending { index, value });
            }
            k.rad[index] = value;
        }
        k.n = knots_rad.len();
        Ok(k)
    }

    /// The knots, rad, ascending.
    pub fn as_slice(&self) -> &[f64] {
        &self.rad[..self.n]
    }

    /// Knot `i` (0-based), rad.
    pub fn get(&self, i: usize) -> Option<f64> {
        self.as_slice().get(i).copied()
    }

    /// Number of knots.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether there is no knot.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
}

/// One parameter: a coefficient and a term, named `<coefficient>_<term>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Param {
    /// The coefficient it belongs to.
    pub coefficient: Coefficient,
    /// The term it multiplies.
    pub term: Term,
}

impl Param {
    /// A parameter.
    pub const fn new(coefficient: Coefficient, term: Term) -> Self {
        Self { coefficient, term }
    }

    /// `<coefficient>_<term>`, e.g. `Cm_alpha`, `Cl_p`, `CD_0`.
    pub fn name(self) -> &'static str {
        PARAM_NAMES[self.coefficient.index()][self.term.index()]
    }

    /// Parses a [`Param::name`]. The coefficient is the part before the first `_`.
    pub fn from_name(s: &str) -> Option<Self> {
        let (c, t) = s.split_once('_')?;
        Some(Self { coefficient: Coefficient::from_name(c)?, term: Term::from_name(t)? })
    }
}

/// Why a structure could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum StructureError {
    /// More than [`MAX_PARAMS`] parameters.
    #[error("model structure has {0} parameters; at most {MAX_PARAMS} are supported")]
    TooManyParams(usize),
    /// A structure with no parameter.
    #[error("model structure declares no parameter")]
    Empty,
    /// Forces declared both in body axes (CX/CZ) and stability axes (CL/CD).
    #[error(
        "model structure declares `{0}` and `{1}`: choose body axes (CX, CZ) or stability axes (CL, CD) for the longitudinal forces"
    )]
    MixedAxes(&'static str, &'static str),
    /// A spline term whose knot the structure does not have.
    #[error(
        "model structure has the term `{0}` but only {1} α knot(s): give one knot per spline term"
    )]
    MissingKnot(&'static str, usize),
}

/// A model structure: for each coefficient the set of its terms (a bit set over
/// [`Term::ALL`]), and the α knots of its spline terms. Copy, fixed size, `no_std`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModelStructure {
    terms: [u32; 8],
    knots: AlphaKnots,
}

impl ModelStructure {
    /// The empty structure (build one with [`ModelStructure::with`]).
    pub const fn empty() -> Self {
        Self { terms: [0; 8], knots: AlphaKnots::NONE }
    }

    /// This structure with the α knots `knots` (replacing any it had): knot `i` is the one of
    /// spline term [`Term::spline`]`(i)`.
    pub fn with_knots(mut self, knots: AlphaKnots) -> Self {
        self.knots = knots;
        self
    }

    /// The α knots of the spline terms.
    pub fn knots(&self) -> &AlphaKnots {
        &self.knots
    }

    /// The regressor of term `t` at sample `s` with this structure's knots ([`Term::value`]).
    pub fn value(&self, t: Term, s: &AirDataSample) -> Option<f64> {
        t.value(s, &self.knots)
    }

    /// This structure with `coefficient` explained by `terms` (added to any it had).
    pub fn with(mut self, coefficient: Coefficient, terms: &[Term]) -> Self {
        for t in terms {
            self.terms[coefficient.index()] |= 1 << t.index();
        }
        self
    }

    /// Adds one parameter.
    pub fn insert(&mut self, p: Param) {
        self.terms[p.coefficient.index()] |= 1 << p.term.index();
    }

    /// Removes one parameter (nothing when it is not in the structure).
    pub fn remove(&mut self, p: Param) {
        self.terms[p.coefficient.index()] &= !(1 << p.term.index());
    }

    /// Whether the structure has parameter `p`.
    pub fn contains(&self, p: Param) -> bool {
        self.terms[p.coefficient.index()] & (1 << p.term.index()) != 0
    }

    /// Checks the capacity, non-emptiness and that CX/CZ and CL/CD are not mixed.
    ///
    /// # Errors
    /// [`StructureError`].
    pub fn validated(self) -> Result<Self, StructureError> {
        let n = self.n_params();
        if n == 0 {
            return Err(StructureError::Empty);
        }
        if n > MAX_PARAMS {
            return Err(StructureError::TooManyParams(n));
        }
        let has = |c: Coefficient| self.terms[c.index()] != 0;
        for body in [Coefficient::CX, Coefficient::CZ] {
            for stab in [Coefficient::CL, Coefficient::CD] {
                if has(body) && has(stab) {
                    return Err(StructureError::MixedAxes(body.name(), stab.name()));
                }
            }
        }
        if let Some(p) = self.params().find(|p| p.term.knot().is_some_and(|i| i >= self.knots.n)) {
            return Err(StructureError::MissingKnot(p.term.name(), self.knots.n));
        }
        Ok(self)
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.terms.iter().map(|t| t.count_ones() as usize).sum()
    }

    /// Whether coefficient `c` is modelled.
    pub fn has(&self, c: Coefficient) -> bool {
        self.terms[c.index()] != 0
    }

    /// The modelled coefficients, in order.
    pub fn coefficients(&self) -> impl Iterator<Item = Coefficient> + '_ {
        Coefficient::ALL.into_iter().filter(|c| self.has(*c))
    }

    /// The terms of coefficient `c`, in order.
    pub fn terms_of(&self, c: Coefficient) -> impl Iterator<Item = Term> + '_ {
        let mask = self.terms[c.index()];
        Term::ALL.into_iter().filter(move |t| mask & (1 << t.index()) != 0)
    }

    /// Number of terms of coefficient `c`.
    pub fn n_terms(&self, c: Coefficient) -> usize {
        self.terms[c.index()].count_ones() as usize
    }

    /// All parameters, in parameter order.
    pub fn params(&self) -> impl Iterator<Item = Param> + '_ {
        self.coefficients().flat_map(move |c| self.terms_of(c).map(move |t| Param::new(c, t)))
    }

    /// The `i`-th parameter.
    pub fn param(&self, i: usize) -> Option<Param> {
        self.params().nth(i)
    }

    /// Index of parameter `p`, if present.
    pub fn index_of(&self, p: Param) -> Option<usize> {
        self.params().position(|q| q == p)
    }

    /// Index of the first parameter of coefficient `c` (its parameters are contiguous).
    pub fn first_index(&self, c: Coefficient) -> usize {
        Coefficient::ALL[..c.index()].iter().map(|k| self.n_terms(*k)).sum()
    }

    /// Whether every term and every modelled coefficient can be formed from sample `s`
    /// (its channels and constants are present). `measured` are the sample's measured
    /// coefficients, [`AirDataSample::measured_coefficients`].
    pub fn supported_by(&self, s: &AirDataSample, measured: &[Option<f64>; 8]) -> bool {
        self.params().all(|p| self.value(p.term, s).is_some())
            && self.coefficients().all(|c| measured[c.index()].is_some())
    }

    /// The names of the parameters, in order (for headers).
    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.params().map(Param::name)
    }

    /// Longitudinal preset: `CL`, `CD`, `Cm` each with `_0, _alpha, _q, _de` (12 parameters;
    /// Klein & Morelli 2006 eq. 5.1–5.3 form).
    pub fn longitudinal() -> Self {
        const T: [Term; 4] = [Term::Bias, Term::Alpha, Term::Q, Term::De];
        Self::empty().with(Coefficient::CL, &T).with(Coefficient::CD, &T).with(Coefficient::Cm, &T)
    }

    /// Lateral-directional preset: `CY`, `Cl`, `Cn` each with `_0, _beta, _p, _r, _da, _dr`
    /// (18 parameters; Klein & Morelli 2006 eq. 5.4–5.6 form).
    pub fn lateral() -> Self {
        const T: [Term; 6] = [Term::Bias, Term::Beta, Term::P, Term::R, Term::Da, Term::Dr];
        Self::empty().with(Coefficient::CY, &T).with(Coefficient::Cl, &T).with(Coefficient::Cn, &T)
    }

    /// Both presets (30 parameters).
    pub fn six_axis() -> Self {
        let lon = Self::longitudinal();
        let lat = Self::lateral();
        let mut s = Self::empty();
        for i in 0..8 {
            s.terms[i] = lon.terms[i] | lat.terms[i];
        }
        s
    }

    /// A preset by name: `longitudinal`, `lateral` or `six-axis`.
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "longitudinal" => Some(Self::longitudinal()),
            "lateral" => Some(Self::lateral()),
            "six-axis" => Some(Self::six_axis()),
            _ => None,
        }
    }

    /// The preset names, richest first.
    pub const PRESETS: [&'static str; 3] = ["six-axis", "longitudinal", "lateral"];
}

/// A coefficient model value: `Σ θ_j ξ_j` for coefficient `c` of `structure` with parameter
/// vector `theta` (length ≥ `structure.n_params()`), or `None` if a term is unavailable.
pub fn coefficient_value(
    structure: &ModelStructure,
    theta: &[f64],
    c: Coefficient,
    s: &AirDataSample,
) -> Option<f64> {
    let first = structure.first_index(c);
    let mut sum = 0.0;
    for (k, t) in structure.terms_of(c).enumerate() {
        sum += theta[first + k] * structure.value(t, s)?;
    }
    Some(sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_follow_the_field() {
        for c in Coefficient::ALL {
            for t in Term::ALL {
                let p = Param::new(c, t);
                assert_eq!(Param::from_name(p.name()), Some(p), "{}", p.name());
                assert_eq!(p.name(), format!("{}_{}", c.name(), t.name()));
            }
        }
        assert_eq!(Param::new(Coefficient::Cm, Term::Alphadot).name(), "Cm_alphadot");
        assert_eq!(Param::new(Coefficient::Cl, Term::P).name(), "Cl_p");
        assert_eq!(Param::new(Coefficient::CD, Term::Bias).name(), "CD_0");
        assert_eq!(Param::new(Coefficient::Cm, Term::Alpha2).name(), "Cm_alpha2");
        assert_eq!(Param::from_name("CL_q").unwrap().coefficient, Coefficient::CL);
        assert_eq!(Param::from_name("Cl_q").unwrap().coefficient, Coefficient::Cl);
        assert!(Param::from_name("Cm_alphadotx").is_none());
        assert!(Param::from_name("Cx_alpha").is_none());
    }

    #[test]
    fn presets_have_the_documented_parameters_in_order() {
        let lon = ModelStructure::longitudinal();
        let names: std::vec::Vec<_> = lon.names().collect();
        assert_eq!(
            names,
            [
                "CL_0", "CL_alpha", "CL_q", "CL_de", "CD_0", "CD_alpha", "CD_q", "CD_de", "Cm_0",
                "Cm_alpha", "Cm_q", "Cm_de"
            ]
        );
        let lat = ModelStructure::lateral();
        assert_eq!(lat.n_params(), 18);
        assert_eq!(lat.param(7).unwrap().name(), "Cl_beta");
        assert_eq!(ModelStructure::six_axis().n_params(), 30);
        assert_eq!(
            ModelStructure::six_axis().index_of(Param::from_name("Cn_dr").unwrap()),
            Some(29)
        );
        assert_eq!(lon.first_index(Coefficient::Cm), 8);
        assert!(ModelStructure::six_axis().validated().is_ok());
        let mixed = lon.with(Coefficient::CX, &[Term::Alpha]);
        assert!(matches!(mixed.validated(), Err(StructureError::MixedAxes("CX", "CL"))));
        assert_eq!(ModelStructure::empty().validated(), Err(StructureError::Empty));
    }

    /// `Term::inputs` is what `Term::value` reads: with every input present each term has a
    /// value, and taking one quantity away leaves a term without one exactly when the
    /// quantity is among its inputs (α and V are never absent; a change of either changes the
    /// value of exactly the terms that list it, spline terms above their knot).
    #[test]
    fn term_inputs_are_what_the_value_reads() {
        let full = AirDataSample {
            vt_mps: 100.0,
            alpha_rad: 0.3,
            qbar_pa: 5_000.0,
            beta_rad: Some(0.02),
            p_rad_s: Some(0.4),
            q_rad_s: Some(0.05),
            r_rad_s: Some(-0.1),
            alphadot_rad_s: Some(0.2),
            de_rad: Some(-0.03),
            da_rad: Some(0.01),
            dr_rad: Some(0.02),
            constants: crate::sample::AircraftConstants {
                cbar_m: Some(3.0),
                b_m: Some(10.0),
                v0_mps: Some(80.0),
                ..Default::default()
            },
            ..Default::default()
        };
        let knots = AlphaKnots::new(&[0.0, 0.05, 0.1, 0.2]).unwrap();
        use TermInput as I;
        let without = |i: I| -> (AirDataSample, AlphaKnots) {
            let (mut s, mut k) = (full, knots);
            match i {
                I::Beta => s.beta_rad = None,
                I::P => s.p_rad_s = None,
                I::Q => s.q_rad_s = None,
                I::R => s.r_rad_s = None,
                I::Alphadot => s.alphadot_rad_s = None,
                I::De => s.de_rad = None,
                I::Da => s.da_rad = None,
                I::Dr => s.dr_rad = None,
                I::Cbar => s.constants.cbar_m = None,
                I::Span => s.constants.b_m = None,
                I::V0 => s.constants.v0_mps = None,
                I::Knot => k = AlphaKnots::NONE,
                // q̄ = 0: a density of 0, beyond the standard atmosphere's 20 km.
                I::Density => s.qbar_pa = 0.0,
                I::Alpha | I::Vt => unreachable!("never absent"),
            }
            (s, k)
        };
        let removable = [
            I::Beta,
            I::P,
            I::Q,
            I::R,
            I::Alphadot,
            I::De,
            I::Da,
            I::Dr,
            I::Cbar,
            I::Span,
            I::V0,
            I::Knot,
            I::Density,
        ];
        for t in Term::ALL {
            assert!(t.value(&full, &knots).is_some(), "{}", t.name());
            for i in removable {
                let (s, k) = without(i);
                let lost = t.value(&s, &k).is_none();
                assert_eq!(lost, t.inputs().contains(&i), "{} without {i:?}", t.name());
            }
            for (i, moved) in [
                (I::Alpha, AirDataSample { alpha_rad: 0.31, ..full }),
                (I::Vt, AirDataSample { vt_mps: 101.0, ..full }),
            ] {
                let normalised =
                    matches!(i, I::Vt) && t.value(&moved, &knots) != t.value(&full, &knots);
                let listed = t.inputs().contains(&i);
                // V also normalises the rates (p̂ = p b / 2V), which inputs() leaves out.
                let rate = t.inputs().iter().any(|x| matches!(x, I::P | I::Q | I::R | I::Alphadot));
                match i {
                    I::Alpha => assert_eq!(
                        t.value(&moved, &knots) != t.value(&full, &knots),
                        listed,
                        "{} with α moved",
                        t.name()
                    ),
                    _ => assert_eq!(
                        normalised,
                        listed || (rate && t != Term::Q0),
                        "{} with V moved",
                        t.name()
                    ),
                }
            }
        }
        assert!(I::Alpha.always_present() && I::Vt.always_present() && !I::Beta.always_present());
        assert_eq!(I::Span.field(), None);
        assert_eq!(I::De.field(), Some("de_rad"));
    }

    #[test]
    fn analytic_term_values() {
        let s = AirDataSample {
            vt_mps: 100.0,
            alpha_rad: 0.1,
            beta_rad: Some(0.02),
            p_rad_s: Some(0.4),
            q_rad_s: Some(0.05),
            r_rad_s: Some(-0.1),
            alphadot_rad_s: Some(0.2),
            de_rad: Some(-0.03),
            constants: crate::sample::AircraftConstants {
                cbar_m: Some(3.0),
                b_m: Some(10.0),
                v0_mps: Some(80.0),
                ..Default::default()
            },
            ..Default::default()
        };
        let v = |t: Term| t.value(&s, &AlphaKnots::NONE).unwrap();
        assert_eq!(v(Term::Bias), 1.0);
        assert!((v(Term::P) - 0.4 * 10.0 / 200.0).abs() < 1e-15);
        assert!((v(Term::Q) - 0.05 * 3.0 / 200.0).abs() < 1e-15);
        assert!((v(Term::R) + 0.1 * 10.0 / 200.0).abs() < 1e-15);
        assert!((v(Term::Alphadot) - 0.2 * 3.0 / 200.0).abs() < 1e-15);
        assert!((v(Term::V) - 1.25).abs() < 1e-15);
        assert!((v(Term::AlphaDe) + 0.003).abs() < 1e-15);
        assert!((v(Term::AlphaBeta) - 0.002).abs() < 1e-15);
        assert!((v(Term::Q0) - 0.05 * 3.0 / 160.0).abs() < 1e-15);
        assert_eq!(Param::from_name("Cm_q0"), Some(Param::new(Coefficient::Cm, Term::Q0)));
        assert!((v(Term::AlphaP) - 0.1 * 0.4 * 10.0 / 200.0).abs() < 1e-15);
        assert!((v(Term::AlphaQ) - 0.1 * 0.05 * 3.0 / 200.0).abs() < 1e-15);
        assert!((v(Term::AlphaR) + 0.1 * 0.1 * 10.0 / 200.0).abs() < 1e-15);
        assert_eq!(Param::from_name("Cl_alpha_p"), Some(Param::new(Coefficient::Cl, Term::AlphaP)));
        assert_eq!(Param::new(Coefficient::Cn, Term::AlphaDr).name(), "Cn_alpha_dr");
        let none = AlphaKnots::NONE;
        assert!(Term::Da.value(&s, &none).is_none() && Term::AlphaDa.value(&s, &none).is_none());
        // Terms past the 16th still form structures (the bit set is 32 wide).
        let wide = ModelStructure::empty().with(Coefficient::Cl, &Term::ALL);
        assert_eq!(wide.terms_of(Coefficient::Cl).count(), N_TERMS);
        assert!(wide.contains(Param::new(Coefficient::Cl, Term::AlphaDr)));
        let st = ModelStructure::empty().with(Coefficient::Cm, &[Term::Bias, Term::Alpha, Term::Q]);
        let cm = coefficient_value(&st, &[0.1, -1.0, -20.0], Coefficient::Cm, &s).unwrap();
        assert!((cm - (0.1 - 0.1 - 20.0 * 0.05 * 3.0 / 200.0)).abs() < 1e-15);
    }

    /// `(α − k)₊` by hand on both sides of a knot, a missing knot, and Mach at the standard
    /// sea-level density (a = 340.294 m/s, ICAO Doc 7488).
    #[test]
    fn analytic_spline_and_mach_values() {
        let s = AirDataSample {
            vt_mps: 170.147,
            alpha_rad: 0.2,
            qbar_pa: 0.5 * 1.225 * 170.147 * 170.147,
            ..Default::default()
        };
        let k = AlphaKnots::new(&[0.05, 0.2, 0.25]).unwrap();
        assert!((Term::AlphaK1.value(&s, &k).unwrap() - 0.15).abs() < 1e-15);
        assert_eq!(Term::AlphaK2.value(&s, &k), Some(0.0));
        assert_eq!(Term::AlphaK3.value(&s, &k), Some(0.0));
        assert_eq!(Term::AlphaK4.value(&s, &k), None);
        assert_eq!(Param::new(Coefficient::CL, Term::AlphaK2).name(), "CL_alpha_k2");
        assert_eq!(Term::spline(3), Some(Term::AlphaK4));
        assert_eq!(Term::spline(4), None);
        let m = Term::Mach.value(&s, &k).unwrap();
        assert!((m - 0.5).abs() < 1e-4, "{m}");
        assert!((Term::Mach2.value(&s, &k).unwrap() - m * m).abs() < 1e-15);
        let st = ModelStructure::longitudinal().with(Coefficient::CL, &[Term::AlphaK2]);
        assert_eq!(st.validated(), Err(StructureError::MissingKnot("alpha_k2", 0)));
        let one = AlphaKnots::new(&[0.1]).unwrap();
        assert_eq!(st.with_knots(one).validated(), Err(StructureError::MissingKnot("alpha_k2", 1)));
        assert!(st.with_knots(k).validated().is_ok());
    }

    /// Knots are refused unsorted, repeated, not finite, beyond ±90° or more than four.
    #[test]
    fn bad_knots_are_refused() {
        assert_eq!(
            AlphaKnots::new(&[0.1, 0.05]),
            Err(KnotError::NotAscending { index: 1, value: 0.05 })
        );
        assert_eq!(
            AlphaKnots::new(&[0.1, 0.1]),
            Err(KnotError::NotAscending { index: 1, value: 0.1 })
        );
        assert!(matches!(
            AlphaKnots::new(&[f64::NAN]),
            Err(KnotError::NotAnAngle { index: 0, .. })
        ));
        assert!(matches!(
            AlphaKnots::new(&[0.0, f64::INFINITY]),
            Err(KnotError::NotAnAngle { index: 1, .. })
        ));
        assert!(matches!(AlphaKnots::new(&[2.0]), Err(KnotError::NotAnAngle { index: 0, .. })));
        assert_eq!(AlphaKnots::new(&[0.0, 0.1, 0.2, 0.3, 0.4]), Err(KnotError::TooMany(5)));
        assert_eq!(AlphaKnots::new(&[-0.1, 0.3]).unwrap().as_slice(), &[-0.1, 0.3]);
    }
}
