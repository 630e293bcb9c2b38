//! Rigid-body flight model over any declared [`ModelStructure`]: the state equations
//! `ẋ = f(x, u, θ)` for the states `(V, α, β, p, q, r, φ, θ)` and the measurement model `y = h`,
//! generic over [`Scalar`] so one code path gives values and exact partials (with [`Dual`]
//! numbers). Used by the extended Kalman filter ([`crate::ekf`]).
//!
//! # Equations (flat, non-rotating earth; constant mass; body axes x forward, y right, z down)
//!
//! The rigid-body equations are the shared kernel's ([`aeroident_physics::rigid_body`], the same
//! functions the F-16 simulator evaluates; Stevens, Lewis & Johnson, *Aircraft Control and
//! Simulation*, 3rd ed. (SLJ), §1.3, §2.3, §2.5 and the subroutine F of §3.5; Klein & Morelli
//! 2006 §3.3, §3.6), with gravity `g0` ([`G0_MPS2`]) and no rotor momentum.
//!
//! Body velocities from the wind-axis states (SLJ §2.3):
//! `u = V cos α cos β`, `v = V sin β`, `w = V sin α cos β`.
//!
//! Force equations in body axes (SLJ §2.5), with `a = (ax, ay, az)` the specific force
//! (aerodynamic plus thrust force over mass) and gravity resolved through `φ, θ`:
//!
//! ```text
//! u̇ = r v − q w − g sin θ        + ax
//! v̇ = p w − r u + g sin φ cos θ  + ay
//! ẇ = q u − p v + g cos φ cos θ  + az
//! ```
//!
//! The wind-axis states follow by differentiating `V = |(u, v, w)|`, `α = atan(w/u)`,
//! `β = asin(v/V)` (SLJ §3.5, subroutine F):
//!
//! ```text
//! V̇ = (u u̇ + v v̇ + w ẇ) / V
//! α̇ = (u ẇ − w u̇) / (u² + w²)
//! β̇ = (V v̇ − v V̇) cos β / (u² + w²)      (= (V v̇ − v V̇) / (V² cos β))
//! ```
//!
//! Moment equations (Euler's equations, SLJ §2.5, with `Jxy = Jyz = 0`, the inertia tensor
//! `[[Jx, 0, −Jxz], [0, Jy, 0], [−Jxz, 0, Jz]]`, solved with the inertia constants `c1 … c9`,
//! `Γ = Jx Jz − Jxz²`):
//!
//! ```text
//! ṗ = (c2 p + c1 r) q + c3 L + c4 N
//! q̇ = c5 p r + c6 (r² − p²) + c7 M
//! ṙ = (c8 p − c2 r) q + c4 L + c9 N
//! ```
//!
//! Euler kinematics (SLJ §1.3): `φ̇ = p + tan θ (q sin φ + r cos φ)`, `θ̇ = q cos φ − r sin φ`.
//!
//! # Forces and moments
//!
//! `q̄ = ½ ρ V²` with the model's `V`. The aerodynamic coefficients are the structure's
//! linear-in-parameters model `C_k = Σ_j θ_kj ξ_j`; a term's regressor `ξ_j` is formed from the
//! **model** states where it depends on a state (`α`, `β`, `p̂ = p b/2V`, `q̂ = q c̄/2V`,
//! `r̂ = r b/2V`, `V/V0`, `α²`, `α β`, `α δe`, `q c̄/2V0`) and from the sample for the controls.
//! Lift and drag (stability axes) are rotated into body axes through `α` (the inverse of the
//! relation in [`crate::sample`]): `CX = CL sin α − CD cos α`, `CZ = −CL cos α − CD sin α`; or
//! `CX`, `CZ` are used directly. Thrust `T` acts along the thrust line inclined by `σT`
//! (`+T cos σT` on x, `−T sin σT` on z) and its pitching moment is the recorded
//! `thrust_moment_nm`, else `thrust_arm_m · T` (as in [`AirDataSample::measured_coefficients`]).
//! `X = q̄S CX + T cos σT`, `Y = q̄S CY`, `Z = q̄S CZ − T sin σT`, `L = q̄Sb Cl`,
//! `M = q̄Sc̄ Cm + M_T`, `N = q̄Sb Cn`, moments about the CG.
//!
//! # The α̇ term is implicit, solved exactly
//!
//! A `Term::Alphadot` regressor `α̇ c̄/2V` makes the forces depend on `α̇`, which depends on the
//! forces. Every force is affine in `α̇`: `a = a0 + a1 α̇` with
//! `a1 = q̄S (∂C/∂α̇-hat) c̄/(2 V m)` rotated to body axes. Inserting into the `α̇` equation,
//! `α̇ (1 − (u a1z − w a1x)/(u² + w²)) = (u ẇ0 − w u̇0)/(u² + w²)`, i.e. for stability-axis
//! forces `α̇ (1 + q̄ S c̄ CL_alphadot / (2 m V² cos β)) = …`: one division, exact (no iteration,
//! no lag). A denominator that is not positive is refused as [`EstimatorError::Numerical`]
//! (that would need `CL_alphadot < −2mV²cosβ/(q̄Sc̄)`). The solved `α̇` then enters every
//! coefficient with an α̇ term, including `Cm_alphadot` in `q̇`.
//!
//! # State sets ([`StateSet`])
//!
//! - **Longitudinal** `(V, α, θ, q)`: a force pair (`CL`+`CD` or `CX`+`CZ`) and `Cm` declared,
//!   no lateral coefficient. `β, p, r, φ` are inputs from the sample, 0 when a record lacks
//!   them (the symmetric-flight longitudinal model, Klein & Morelli 2006 ch. 3,
//!   decoupled longitudinal equations); the side force is the
//!   measured `ay` (0 when absent). The `(Jz − Jx) p r − Jxz(p² − r²)` coupling needs
//!   `Ixx, Izz, Ixz` only when the sample has `p` and `r`.
//! - **Lateral-directional** `(β, p, r, φ)`: `CY`, `Cl`, `Cn` declared, no longitudinal one.
//!   `V, α, θ, q` are inputs from the sample (`theta_rad`, `q_rad_s` required) and the
//!   longitudinal forces are the measured `ax`, `az` (required). An α̇ term then needs the
//!   sample's `alphadot_rad_s`.
//! - **Coupled** (all eight): both groups declared.
//!
//! A structure that determines none of these (e.g. `Cm` alone, `CL`+`CD` without `Cm`, `Cl`
//! without `Cn`) is refused with [`EstimatorError::InvalidConfig`] naming what is missing: a
//! partial state set would silently take model states from noisy measurements.
//!
//! # Outputs (measurement model)
//!
//! The set's states, the specific forces the set models (`ax`, `az` with the longitudinal
//! forces, `ay` with `CY`) and the angular accelerations whose moments it models (`q̇` with
//! `Cm`, `ṗ`, `ṙ` with `Cl`, `Cn`); each is used only when the sample has it.

use crate::EstimatorError;
use crate::dual::Scalar;
use crate::sample::AirDataSample;
use crate::vocabulary::{Coefficient, MAX_PARAMS, ModelStructure, Term};
use aeroident_physics::rigid_body::{self as rb, Inertia, InertiaConstants, SinCos};

#[cfg(doc)]
use crate::dual::Dual;

/// Standard gravity, m/s² (re-exported from [`aeroident_physics::units`]).
pub use aeroident_physics::units::G0_MPS2;

/// Number of states of the full model.
pub const N_STATES: usize = 8;

/// Indices of the states in the full state vector `(V, α, β, p, q, r, φ, θ)`.
pub mod state {
    /// True airspeed, m/s.
    pub const V: usize = 0;
    /// Angle of attack, rad.
    pub const ALPHA: usize = 1;
    /// Sideslip, rad.
    pub const BETA: usize = 2;
    /// Roll rate, rad/s.
    pub const P: usize = 3;
    /// Pitch rate, rad/s.
    pub const Q: usize = 4;
    /// Yaw rate, rad/s.
    pub const R: usize = 5;
    /// Bank angle, rad.
    pub const PHI: usize = 6;
    /// Pitch attitude, rad.
    pub const THETA: usize = 7;
}

/// Sample field names of the states, in full-state order.
pub const STATE_NAMES: [&str; N_STATES] =
    ["vt_mps", "alpha_rad", "beta_rad", "p_rad_s", "q_rad_s", "r_rad_s", "phi_rad", "theta_rad"];

/// The measured outputs the model can predict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// True airspeed, m/s.
    Vt,
    /// Angle of attack, rad.
    Alpha,
    /// Sideslip, rad.
    Beta,
    /// Roll rate, rad/s.
    P,
    /// Pitch rate, rad/s.
    Q,
    /// Yaw rate, rad/s.
    R,
    /// Bank angle, rad.
    Phi,
    /// Pitch attitude, rad.
    Theta,
    /// Body x specific force, m/s².
    Ax,
    /// Body y specific force, m/s².
    Ay,
    /// Body z specific force, m/s².
    Az,
    /// Roll acceleration, rad/s².
    Pdot,
    /// Pitch acceleration, rad/s².
    Qdot,
    /// Yaw acceleration, rad/s².
    Rdot,
}

/// Number of [`Output`]s.
pub const N_OUTPUTS: usize = 14;

impl Output {
    /// All outputs, in index order.
    pub const ALL: [Output; N_OUTPUTS] = [
        Output::Vt,
        Output::Alpha,
        Output::Beta,
        Output::P,
        Output::Q,
        Output::R,
        Output::Phi,
        Output::Theta,
        Output::Ax,
        Output::Ay,
        Output::Az,
        Output::Pdot,
        Output::Qdot,
        Output::Rdot,
    ];

    /// Index in [`Output::ALL`]; the first eight equal the full-state indices.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The sample field name (`vt_mps`, `ax_mps2`, `qdot_rad_s2` …).
    pub fn name(self) -> &'static str {
        [
            "vt_mps",
            "alpha_rad",
            "beta_rad",
            "p_rad_s",
            "q_rad_s",
            "r_rad_s",
            "phi_rad",
            "theta_rad",
            "ax_mps2",
            "ay_mps2",
            "az_mps2",
            "pdot_rad_s2",
            "qdot_rad_s2",
            "rdot_rad_s2",
        ][self.index()]
    }

    /// The measured value of this output in sample `s`, if the sample has it.
    pub fn measured(self, s: &AirDataSample) -> Option<f64> {
        match self {
            Output::Vt => Some(s.vt_mps),
            Output::Alpha => Some(s.alpha_rad),
            Output::Beta => s.beta_rad,
            Output::P => s.p_rad_s,
            Output::Q => s.q_rad_s,
            Output::R => s.r_rad_s,
            Output::Phi => s.phi_rad,
            Output::Theta => s.theta_rad,
            Output::Ax => s.ax_mps2,
            Output::Ay => s.ay_mps2,
            Output::Az => s.az_mps2,
            Output::Pdot => s.pdot_rad_s2,
            Output::Qdot => s.qdot_rad_s2,
            Output::Rdot => s.rdot_rad_s2,
        }
    }

    /// Sets this output's channel of sample `s` to `v` (units as [`Output::name`]): the
    /// inverse of [`Output::measured`], e.g. to put a simulated response in a sample.
    pub fn set_measured(self, s: &mut AirDataSample, v: f64) {
        match self {
            Output::Vt => s.vt_mps = v,
            Output::Alpha => s.alpha_rad = v,
            Output::Beta => s.beta_rad = Some(v),
            Output::P => s.p_rad_s = Some(v),
            Output::Q => s.q_rad_s = Some(v),
            Output::R => s.r_rad_s = Some(v),
            Output::Phi => s.phi_rad = Some(v),
            Output::Theta => s.theta_rad = Some(v),
            Output::Ax => s.ax_mps2 = Some(v),
            Output::Ay => s.ay_mps2 = Some(v),
            Output::Az => s.az_mps2 = Some(v),
            Output::Pdot => s.pdot_rad_s2 = Some(v),
            Output::Qdot => s.qdot_rad_s2 = Some(v),
            Output::Rdot => s.rdot_rad_s2 = Some(v),
        }
    }
}

/// Which states the model integrates (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateSet {
    /// `(V, α, θ, q)`.
    Longitudinal,
    /// `(β, p, r, φ)`.
    Lateral,
    /// All eight.
    Coupled,
}

const LON_STATES: [usize; 4] = [state::V, state::ALPHA, state::THETA, state::Q];
const LAT_STATES: [usize; 4] = [state::BETA, state::P, state::R, state::PHI];
const ALL_STATES: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
const LON_OUTPUTS: [Output; 7] =
    [Output::Vt, Output::Alpha, Output::Theta, Output::Q, Output::Ax, Output::Az, Output::Qdot];
const LAT_OUTPUTS: [Output; 7] =
    [Output::Beta, Output::P, Output::R, Output::Phi, Output::Ay, Output::Pdot, Output::Rdot];

fn invalid(field: &'static str, value: f64, reason: &'static str) -> EstimatorError {
    EstimatorError::InvalidConfig { field, value, reason }
}

impl StateSet {
    /// The state set a structure determines (module doc).
    ///
    /// # Errors
    /// [`EstimatorError::IncompleteAxis`] naming what the axis needs and what the structure
    /// declares when its longitudinal or lateral coefficients are incomplete;
    /// [`EstimatorError::InvalidConfig`] when it mixes CX/CZ with CL/CD.
    pub fn of(structure: &ModelStructure) -> Result<Self, EstimatorError> {
        use Coefficient as C;
        let has = |c: C| structure.has(c);
        let n = structure.n_params() as f64;
        if structure.validated().is_err() {
            return Err(invalid(
                "model structure",
                n,
                "empty, over capacity, mixes CX/CZ with CL/CD, or lacks a spline term's α knot",
            ));
        }
        let any_lon = has(C::CL) || has(C::CD) || has(C::CX) || has(C::CZ) || has(C::Cm);
        let lon = ((has(C::CL) && has(C::CD)) || (has(C::CX) && has(C::CZ))) && has(C::Cm);
        let any_lat = has(C::CY) || has(C::Cl) || has(C::Cn);
        let lat = has(C::CY) && has(C::Cl) && has(C::Cn);
        let declared = C::ALL.iter().enumerate().filter(|(_, c)| has(**c)).map(|(i, _)| 1 << i);
        let declared = declared.fold(0u8, |bits, bit| bits | bit);
        if any_lon && !lon {
            return Err(EstimatorError::IncompleteAxis { lateral: false, declared });
        }
        if any_lat && !lat {
            return Err(EstimatorError::IncompleteAxis { lateral: true, declared });
        }
        Ok(match (lon, lat) {
            (true, true) => StateSet::Coupled,
            (true, false) => StateSet::Longitudinal,
            _ => StateSet::Lateral,
        })
    }

    /// The integrated states, as full-state indices ([`state`]), in filter order.
    pub fn states(self) -> &'static [usize] {
        match self {
            StateSet::Longitudinal => &LON_STATES,
            StateSet::Lateral => &LAT_STATES,
            StateSet::Coupled => &ALL_STATES,
        }
    }

    /// The outputs the set predicts (each used when the sample has it).
    pub fn outputs(self) -> &'static [Output] {
        match self {
            StateSet::Longitudinal => &LON_OUTPUTS,
            StateSet::Lateral => &LAT_OUTPUTS,
            StateSet::Coupled => &Output::ALL,
        }
    }

    /// Whether full-state index `i` is integrated.
    pub fn integrates(self, i: usize) -> bool {
        self.states().contains(&i)
    }

    /// Whether the longitudinal states are integrated.
    pub fn lon(self) -> bool {
        self != StateSet::Lateral
    }

    /// Whether the lateral-directional states are integrated.
    pub fn lat(self) -> bool {
        self != StateSet::Longitudinal
    }
}

/// Everything the model takes from a sample: the measured values of the states it does not
/// integrate, the controls, thrust, density, measured specific forces where they replace a
/// force the model does not have, and the aircraft constants (SI; 0 where not needed).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModelInputs {
    /// Sample time, s.
    pub t_s: f64,
    /// Measured full state `(V, α, β, p, q, r, φ, θ)`; entries a record lacks are 0 (only the
    /// longitudinal set's `β, p, r, φ` may be absent).
    pub x_meas: [f64; N_STATES],
    /// Elevator, aileron, rudder, rad (0 where no term needs them).
    pub de_rad: f64,
    /// Aileron, rad.
    pub da_rad: f64,
    /// Rudder, rad.
    pub dr_rad: f64,
    /// Thrust, N.
    pub thrust_n: f64,
    /// Thrust pitching moment about the CG, N·m.
    pub thrust_moment_nm: f64,
    /// Air density, kg/m³.
    pub rho_kgpm3: f64,
    /// Speed of sound of the Mach terms, m/s ([`AirDataSample::speed_of_sound_mps`]; 0 when
    /// the structure has none).
    pub a_mps: f64,
    /// Measured specific forces `(ax, ay, az)`, m/s² (0 where absent).
    pub accel_meas: [f64; 3],
    /// Measured `α̇`, rad/s (0 where absent and not needed).
    pub alphadot_meas: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Reference area, m².
    pub S_m2: f64,
    /// Chord, m.
    pub cbar_m: f64,
    /// Span, m.
    pub b_m: f64,
    /// `Jx, Jy, Jz, Jxz`, kg·m².
    pub inertia: [f64; 4],
    /// Reference speed of the `V/V0` terms, m/s.
    pub v0_mps: f64,
    /// Thrust inclination, rad.
    pub thrust_incidence_rad: f64,
}

impl ModelInputs {
    /// Linear interpolation `a + w (b − a)` of every field (inputs are interpolated over the
    /// sample interval by the integrator).
    pub fn lerp(a: &Self, b: &Self, w: f64) -> Self {
        let l = |x: f64, y: f64| x + w * (y - x);
        let mut o = *a;
        o.t_s = l(a.t_s, b.t_s);
        for i in 0..N_STATES {
            o.x_meas[i] = l(a.x_meas[i], b.x_meas[i]);
        }
        o.de_rad = l(a.de_rad, b.de_rad);
        o.da_rad = l(a.da_rad, b.da_rad);
        o.dr_rad = l(a.dr_rad, b.dr_rad);
        o.thrust_n = l(a.thrust_n, b.thrust_n);
        o.thrust_moment_nm = l(a.thrust_moment_nm, b.thrust_moment_nm);
        o.rho_kgpm3 = l(a.rho_kgpm3, b.rho_kgpm3);
        o.a_mps = l(a.a_mps, b.a_mps);
        for i in 0..3 {
            o.accel_meas[i] = l(a.accel_meas[i], b.accel_meas[i]);
        }
        o.alphadot_meas = l(a.alphadot_meas, b.alphadot_meas);
        o.mass_kg = l(a.mass_kg, b.mass_kg);
        for i in 0..4 {
            o.inertia[i] = l(a.inertia[i], b.inertia[i]);
        }
        o
    }
}

/// One coefficient of the structure as the model evaluates it.
#[derive(Debug, Clone, Copy)]
struct CoefModel {
    coefficient: Coefficient,
    first: usize,
    n: usize,
    terms: [Term; crate::vocabulary::N_TERMS],
    /// Index of its `Alphadot` parameter, if any.
    alphadot: Option<usize>,
}

/// The flight model of one structure (module doc). Copy, fixed size.
#[derive(Debug, Clone, Copy)]
pub struct FlightModel {
    structure: ModelStructure,
    set: StateSet,
    coefs: [Option<CoefModel>; 8],
    stability_axes: bool,
    needs: Needs,
}

#[derive(Debug, Clone, Copy, Default)]
struct Needs {
    de: bool,
    da: bool,
    dr: bool,
    cbar: bool,
    b: bool,
    v0: bool,
    alphadot: bool,
    mach: bool,
}

impl Needs {
    /// Adds what term `t` reads besides the states ([`Term::inputs`]).
    fn add(&mut self, t: Term) {
        use crate::vocabulary::TermInput as I;
        for input in t.inputs() {
            match input {
                I::De => self.de = true,
                I::Da => self.da = true,
                I::Dr => self.dr = true,
                I::Cbar => self.cbar = true,
                I::Span => self.b = true,
                I::V0 => self.v0 = true,
                I::Alphadot => self.alphadot = true,
                I::Density => self.mach = true,
                // States of the model, or the structure's own knots.
                I::Alpha | I::Beta | I::P | I::Q | I::R | I::Vt | I::Knot => {}
            }
        }
    }
}

/// The model's derivatives and predicted specific forces at one point.
#[derive(Debug, Clone, Copy)]
pub struct Derivatives<T> {
    /// `ẋ` in full-state order; entries of states the set does not integrate are 0.
    pub xdot: [T; N_STATES],
    /// Predicted specific forces `(ax, ay, az)`, m/s²; for a force the set does not model, the
    /// measured input.
    pub accel: [T; 3],
    /// The `α̇` used in the α̇ terms, rad/s.
    pub alphadot: T,
}

impl<T: Scalar> Derivatives<T> {
    /// The model value of output `o` given the full state `x`.
    pub fn output(&self, o: Output, x: &[T; N_STATES]) -> T {
        match o {
            Output::Ax => self.accel[0],
            Output::Ay => self.accel[1],
            Output::Az => self.accel[2],
            Output::Pdot => self.xdot[state::P],
            Output::Qdot => self.xdot[state::Q],
            Output::Rdot => self.xdot[state::R],
            _ => x[o.index()],
        }
    }
}

impl FlightModel {
    /// The model of `structure`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] as [`StateSet::of`].
    pub fn new(structure: ModelStructure) -> Result<Self, EstimatorError> {
        let set = StateSet::of(&structure)?;
        let mut coefs = [None; 8];
        let mut needs = Needs::default();
        for c in structure.coefficients() {
            let mut terms = [Term::Bias; crate::vocabulary::N_TERMS];
            let mut n = 0;
            let first = structure.first_index(c);
            let mut alphadot = None;
            for (k, t) in structure.terms_of(c).enumerate() {
                terms[k] = t;
                n = k + 1;
                needs.add(t);
                if t == Term::Alphadot {
                    alphadot = Some(first + k);
                }
            }
            coefs[c.index()] = Some(CoefModel { coefficient: c, first, n, terms, alphadot });
        }
        if structure.has(Coefficient::Cm) {
            needs.cbar = true;
        }
        if set.lat() {
            needs.b = true;
        }
        Ok(Self { structure, set, coefs, stability_axes: structure.has(Coefficient::CL), needs })
    }

    /// The structure.
    pub fn structure(&self) -> &ModelStructure {
        &self.structure
    }

    /// The state set.
    pub fn state_set(&self) -> StateSet {
        self.set
    }

    /// The modelled coefficients, in parameter order.
    pub fn coefficients(&self) -> impl Iterator<Item = Coefficient> + '_ {
        self.coefs.iter().flatten().map(|c| c.coefficient)
    }

    /// Index of the `Alphadot` parameter of coefficient `c`, if it has one.
    pub fn alphadot_param(&self, c: Coefficient) -> Option<usize> {
        self.coefs[c.index()].and_then(|m| m.alphadot)
    }

    /// The model inputs of sample `s` (module doc), checking that every channel and constant
    /// the structure and state set need is present and valid.
    ///
    /// # Errors
    /// [`EstimatorError::NonFiniteInput`] naming an absent channel (value NaN) or a
    /// non-positive airspeed/density; [`EstimatorError::InvalidConfig`] naming an absent or
    /// non-physical aircraft constant.
    pub fn inputs(&self, s: &AirDataSample) -> Result<ModelInputs, EstimatorError> {
        let t_s = s.t_s;
        let missing =
            |field: &'static str| EstimatorError::NonFiniteInput { field, value: f64::NAN, t_s };
        let need = |v: Option<f64>, field: &'static str| v.ok_or(missing(field));
        let konst = |v: Option<f64>, field: &'static str| -> Result<f64, EstimatorError> {
            match v {
                Some(x) if x > 0.0 && x.is_finite() => Ok(x),
                Some(x) => Err(invalid(field, x, "must be finite and > 0")),
                None => Err(invalid(field, f64::NAN, "absent; the flight model needs it")),
            }
        };
        let c = &s.constants;
        if s.vt_mps.is_nan() || s.vt_mps <= 0.0 {
            return Err(EstimatorError::NonFiniteInput { field: "vt_mps", value: s.vt_mps, t_s });
        }
        let mass_kg = konst(Some(c.mass_kg), "mass_kg")?;
        let S_m2 = konst(Some(c.S_m2), "S_m2")?;
        let rho = s.rho();
        if !(rho > 0.0 && rho.is_finite()) {
            return Err(EstimatorError::NonFiniteInput { field: "rho_kgpm3", value: rho, t_s });
        }
        let set = self.set;
        let mut x_meas = [0.0; N_STATES];
        x_meas[state::V] = s.vt_mps;
        x_meas[state::ALPHA] = s.alpha_rad;
        let lateral_channels =
            [(state::BETA, s.beta_rad), (state::P, s.p_rad_s), (state::R, s.r_rad_s)];
        // Integrated states' measurements are outputs (needed only to initialise); the
        // longitudinal set's lateral inputs are 0 when absent (symmetric flight).
        for (i, v) in lateral_channels.into_iter().chain([(state::PHI, s.phi_rad)]) {
            x_meas[i] = v.unwrap_or(0.0);
        }
        if set == StateSet::Lateral {
            x_meas[state::Q] = need(s.q_rad_s, "q_rad_s")?;
            x_meas[state::THETA] = need(s.theta_rad, "theta_rad")?;
        } else {
            // Integrated states: their measurements are outputs, needed only to initialise.
            x_meas[state::Q] = s.q_rad_s.unwrap_or(0.0);
            x_meas[state::THETA] = s.theta_rad.unwrap_or(0.0);
        }
        let mut accel_meas = [0.0; 3];
        if set == StateSet::Lateral {
            accel_meas[0] = need(s.ax_mps2, "ax_mps2")?;
            accel_meas[2] = need(s.az_mps2, "az_mps2")?;
        }
        if set == StateSet::Longitudinal {
            accel_meas[1] = s.ay_mps2.unwrap_or(0.0);
        }
        let n = self.needs;
        let de_rad = if n.de { need(s.de_rad, "de_rad")? } else { s.de_rad.unwrap_or(0.0) };
        let da_rad = if n.da { need(s.da_rad, "da_rad")? } else { 0.0 };
        let dr_rad = if n.dr { need(s.dr_rad, "dr_rad")? } else { 0.0 };
        let alphadot_meas =
            if n.alphadot && !set.lon() { need(s.alphadot_rad_s, "alphadot_rad_s")? } else { 0.0 };
        let cbar_m = if n.cbar { konst(c.cbar_m, "cbar_m")? } else { 0.0 };
        let b_m = if n.b { konst(c.b_m, "b_m")? } else { 0.0 };
        let v0_mps = if n.v0 { konst(c.v0_mps, "v0_mps")? } else { 0.0 };
        let a_mps = match n.mach {
            true => s.speed_of_sound_mps().ok_or(EstimatorError::NonFiniteInput {
                field: "rho_kgpm3 (outside the standard atmosphere: no speed of sound)",
                value: rho,
                t_s,
            })?,
            false => 0.0,
        };
        let mut inertia = [0.0; 4];
        // The longitudinal set keeps the inertial pitch coupling when p, r and the roll/yaw
        // inertias are all known, and neglects it otherwise (a longitudinal record such as the
        // HFB-320 maps p and r but publishes no Ixx/Izz/Ixz), as the measured Cm does
        // (`AirDataSample::measured_coefficients`). The lateral set always needs them.
        let coupling = set.lat()
            || (s.p_rad_s.is_some()
                && s.r_rad_s.is_some()
                && c.Ixx_kgm2.is_some()
                && c.Izz_kgm2.is_some()
                && c.Ixz_kgm2.is_some());
        if set.lon() {
            inertia[1] = konst(c.Iyy_kgm2, "Iyy_kgm2")?;
        }
        if coupling {
            inertia[0] = konst(c.Ixx_kgm2, "Ixx_kgm2")?;
            inertia[2] = konst(c.Izz_kgm2, "Izz_kgm2")?;
            inertia[3] = c.Ixz_kgm2.ok_or(invalid(
                "Ixz_kgm2",
                f64::NAN,
                "absent; the flight model needs it",
            ))?;
            if set.lat() {
                inertia[1] = konst(c.Iyy_kgm2, "Iyy_kgm2")?;
                if inertia[0] * inertia[2] - inertia[3] * inertia[3] <= 0.0 {
                    return Err(invalid("Ixz_kgm2", inertia[3], "Ixx·Izz − Ixz² must be > 0"));
                }
            }
        }
        let thrust_n = s.thrust_or_zero();
        Ok(ModelInputs {
            t_s,
            x_meas,
            de_rad,
            da_rad,
            dr_rad,
            thrust_n,
            thrust_moment_nm: s.thrust_moment_nm.unwrap_or(c.thrust_arm_m * thrust_n),
            rho_kgpm3: rho,
            a_mps,
            accel_meas,
            alphadot_meas,
            mass_kg,
            S_m2,
            cbar_m,
            b_m,
            inertia,
            v0_mps,
            thrust_incidence_rad: c.thrust_incidence_rad,
        })
    }

    /// The full state at which the model is evaluated: the integrated states from `active`
    /// (filter order, [`StateSet::states`]) and the others from the inputs' measurements.
    pub fn full_state<T: Scalar>(&self, active: &[T], u: &ModelInputs) -> [T; N_STATES] {
        let mut x = [T::cst(0.0); N_STATES];
        for (xi, m) in x.iter_mut().zip(u.x_meas.iter()) {
            *xi = T::cst(*m);
        }
        for (k, &i) in self.set.states().iter().enumerate() {
            x[i] = active[k];
        }
        x
    }

    /// Evaluates the model (module doc) at full state `x` with parameters `theta` (structure
    /// order) and inputs `u`.
    ///
    /// `dc[k]` is added to the non-α̇ part of coefficient `k` (index in
    /// [`Coefficient::ALL`]) and `dd[k]` to its α̇ derivative; pass zeros for plain values, or
    /// seeded [`Dual`] directions to get `∂/∂C_k` and `∂/∂C_k_alphadot` (the model is linear in
    /// every other parameter: `∂/∂θ_j = ∂/∂C_k · ξ_j`). When `xi` is given, the regressor value
    /// `ξ_j` of every parameter is written into it (for an α̇ term, `α̇ c̄/2V`).
    ///
    /// # Errors
    /// [`EstimatorError::Numerical`] when the implicit α̇ equation is singular (module doc).
    pub fn eval<T: Scalar>(
        &self,
        theta: &[f64],
        u: &ModelInputs,
        x: &[T; N_STATES],
        dc: &[T; 8],
        dd: &[T; 8],
        mut xi: Option<&mut [f64; MAX_PARAMS]>,
    ) -> Result<Derivatives<T>, EstimatorError> {
        let zero = T::cst(0.0);
        let [v, al, be, p, q, r, ph, th] = *x;
        let (alpha, beta) = (SinCos::of(al), SinCos::of(be));
        let (sa, ca, cb) = (alpha.sin, alpha.cos, beta.cos);
        let qbar = v * v * (0.5 * u.rho_kgpm3);
        let two_v = v * 2.0;
        let knots = self.structure.knots();
        // (α − k)₊ with its exact partial (1 above the knot, 0 below); the structure is
        // validated, so every spline term has its knot.
        let spline = |t: Term| match t.knot().and_then(|i| knots.get(i)) {
            Some(k) if al.re() > k => al - k,
            _ => zero,
        };
        // Regressor of each term from the model state (controls from the sample).
        let xi_of = |t: Term| -> T {
            match t {
                Term::Bias => T::cst(1.0),
                Term::Alpha => al,
                Term::Beta => be,
                Term::P => p * u.b_m / two_v,
                Term::Q => q * u.cbar_m / two_v,
                Term::R => r * u.b_m / two_v,
                Term::Alphadot => zero,
                Term::De => T::cst(u.de_rad),
                Term::Da => T::cst(u.da_rad),
                Term::Dr => T::cst(u.dr_rad),
                Term::V => v / u.v0_mps,
                Term::Alpha2 => al * al,
                Term::AlphaDe => al * u.de_rad,
                Term::AlphaBeta => al * be,
                Term::Q0 => q * (u.cbar_m / (2.0 * u.v0_mps)),
                Term::AlphaP => al * p * u.b_m / two_v,
                Term::AlphaQ => al * q * u.cbar_m / two_v,
                Term::AlphaR => al * r * u.b_m / two_v,
                Term::AlphaDa => al * u.da_rad,
                Term::AlphaDr => al * u.dr_rad,
                Term::AlphaK1 | Term::AlphaK2 | Term::AlphaK3 | Term::AlphaK4 => spline(t),
                Term::Mach => v / u.a_mps,
                Term::Mach2 => v * v / (u.a_mps * u.a_mps),
            }
        };
        // C0_k (without α̇ term) and D_k = ∂C_k/∂(α̇ c̄/2V).
        let mut c0 = [zero; 8];
        let mut d = [zero; 8];
        for m in self.coefs.iter().flatten() {
            let k = m.coefficient.index();
            let mut sum = dc[k];
            for j in 0..m.n {
                let t = m.terms[j];
                if t == Term::Alphadot {
                    continue;
                }
                let reg = xi_of(t);
                if let Some(xi) = xi.as_deref_mut() {
                    xi[m.first + j] = reg.re();
                }
                sum = sum + reg * theta[m.first + j];
            }
            c0[k] = sum;
            d[k] = dd[k] + m.alphadot.map_or(0.0, |i| theta[i]);
        }
        // Per unit α̇: (c̄/2V).
        let chat = if self.needs.alphadot { T::cst(u.cbar_m) / two_v } else { zero };
        let qs_m = qbar * (u.S_m2 / u.mass_kg);
        use Coefficient as C;
        let set = self.set;
        // Body specific forces a = a0 + a1 α̇.
        let (ax0, az0, ax1, az1) = if set.lon() {
            let (cx0, cz0, cx1, cz1) = if self.stability_axes {
                let (cl0, cd0, cl1, cd1) = (c0[C::CL as usize], c0[C::CD as usize], d[3], d[4]);
                (
                    cl0 * sa - cd0 * ca,
                    -(cl0 * ca) - cd0 * sa,
                    cl1 * sa - cd1 * ca,
                    -(cl1 * ca) - cd1 * sa,
                )
            } else {
                (c0[C::CX as usize], c0[C::CZ as usize], d[C::CX as usize], d[C::CZ as usize])
            };
            let (st, ct) = (libm::sin(u.thrust_incidence_rad), libm::cos(u.thrust_incidence_rad));
            let tm = u.thrust_n / u.mass_kg;
            (qs_m * cx0 + tm * ct, qs_m * cz0 - tm * st, qs_m * cx1 * chat, qs_m * cz1 * chat)
        } else {
            (T::cst(u.accel_meas[0]), T::cst(u.accel_meas[2]), zero, zero)
        };
        let (ay0, ay1) = if set.lat() {
            (qs_m * c0[C::CY as usize], qs_m * d[C::CY as usize] * chat)
        } else {
            (T::cst(u.accel_meas[1]), zero)
        };
        // Body velocity and the α̇-free body acceleration (the kernel's force equations).
        let (phi, theta) = (SinCos::of(ph), SinCos::of(th));
        let omega = [p, q, r];
        let v_body = rb::body_velocity(v, alpha, beta);
        let gravity = rb::gravity_body(G0_MPS2, phi, theta);
        let (a0, a1) = ([ax0, ay0, az0], [ax1, ay1, az1]);
        let v_dot0 = rb::body_acceleration(v_body, omega, gravity, a0);
        let alphadot = if set.lon() {
            // α̇ is linear in the body acceleration, which is v̇0 + a1 α̇: solved in one step.
            let num = rb::alpha_rate(v_body, v_dot0);
            let den = -rb::alpha_rate(v_body, a1) + 1.0;
            if den.re().is_nan() || den.re() <= 0.0 {
                return Err(EstimatorError::Numerical {
                    what: "implicit alpha-dot equation singular (CL_alphadot too negative)",
                    t_s: u.t_s,
                });
            }
            num / den
        } else {
            T::cst(u.alphadot_meas)
        };
        if let Some(xi) = xi {
            for m in self.coefs.iter().flatten() {
                if let Some(i) = m.alphadot {
                    xi[i] = (alphadot * chat).re();
                }
            }
        }
        let [ax, ay, az] = core::array::from_fn(|k| a0[k] + a1[k] * alphadot);
        let v_dot: [T; 3] = core::array::from_fn(|k| v_dot0[k] + a1[k] * alphadot);
        let mut xdot = [zero; N_STATES];
        let adhat = alphadot * chat;
        let [jx, jy, jz, jxz] = u.inertia;
        // Unchecked: without the roll/yaw inertias (longitudinal set, no coupling) only the
        // pitch constants c5 = c6 = 0, c7 = 1/Jy are used; `ModelInputs` validated the rest.
        let c = InertiaConstants::of(&Inertia { jx, jy, jz, jxz });
        let vt_dot = rb::airspeed_rate(v_body, v_dot, v);
        let [phi_dot, theta_dot, _] = rb::euler_rates(omega, phi, theta);
        if set.lon() {
            xdot[state::V] = vt_dot;
            xdot[state::ALPHA] = alphadot;
            let cm = c0[C::Cm as usize] + d[C::Cm as usize] * adhat;
            let m_total = qbar * (u.S_m2 * u.cbar_m) * cm + u.thrust_moment_nm;
            xdot[state::Q] = rb::pitch_acceleration(&c, p, r, m_total, 0.0);
            xdot[state::THETA] = theta_dot;
        }
        if set.lat() {
            xdot[state::BETA] = rb::sideslip_rate(v_body, v_dot, v, vt_dot, cb);
            let qsb = qbar * (u.S_m2 * u.b_m);
            let l = qsb * (c0[C::Cl as usize] + d[C::Cl as usize] * adhat);
            let n = qsb * (c0[C::Cn as usize] + d[C::Cn as usize] * adhat);
            [xdot[state::P], xdot[state::R]] = rb::roll_yaw_acceleration(&c, omega, l, n, 0.0);
            xdot[state::PHI] = phi_dot;
        }
        Ok(Derivatives { xdot, accel: [ax, ay, az], alphadot })
    }
}

/// Values and exact first partials of the model at one point, in the filter's order: rows of
/// `f` for the integrated states ([`StateSet::states`] order) and rows of `h` for the outputs
/// ([`Output`] index; only the set's outputs are written), columns for the integrated states
/// and for the parameters (structure order). Only the active entries are written.
#[derive(Debug, Clone, Copy)]
pub struct Linearisation {
    /// `f` of the integrated states.
    pub f: [f64; N_STATES],
    /// `∂f/∂x`, `[state row][state column]`.
    pub dfdx: [[f64; N_STATES]; N_STATES],
    /// `∂f/∂θ`, `[state row][parameter]`.
    pub dfdtheta: [[f64; MAX_PARAMS]; N_STATES],
    /// `h`, by output index.
    pub y: [f64; N_OUTPUTS],
    /// `∂h/∂x`, `[output][state column]`.
    pub dydx: [[f64; N_STATES]; N_OUTPUTS],
    /// `∂h/∂θ`, `[output][parameter]`.
    pub dydtheta: [[f64; MAX_PARAMS]; N_OUTPUTS],
}

impl Default for Linearisation {
    fn default() -> Self {
        Self {
            f: [0.0; N_STATES],
            dfdx: [[0.0; N_STATES]; N_STATES],
            dfdtheta: [[0.0; MAX_PARAMS]; N_STATES],
            y: [0.0; N_OUTPUTS],
            dydx: [[0.0; N_STATES]; N_OUTPUTS],
            dydtheta: [[0.0; MAX_PARAMS]; N_OUTPUTS],
        }
    }
}

impl FlightModel {
    /// `f` of the integrated states (filter order) at integrated states `active`, parameters
    /// `theta` and inputs `u`.
    ///
    /// # Errors
    /// As [`FlightModel::eval`].
    pub fn derivatives(
        &self,
        theta: &[f64],
        u: &ModelInputs,
        active: &[f64],
    ) -> Result<[f64; N_STATES], EstimatorError> {
        let x = self.full_state(active, u);
        let z = [0.0; 8];
        let d = self.eval(theta, u, &x, &z, &z, None)?;
        let mut f = [0.0; N_STATES];
        for (k, &i) in self.set.states().iter().enumerate() {
            f[k] = d.xdot[i];
        }
        Ok(f)
    }

    /// Number of dual directions [`FlightModel::linearise`] needs: integrated states, modelled
    /// coefficients and coefficients with an α̇ term.
    pub fn n_directions(&self) -> usize {
        self.set.states().len()
            + self.coefs.iter().flatten().count()
            + self.coefs.iter().flatten().filter(|m| m.alphadot.is_some()).count()
    }

    /// Values and exact partials of `f` and `h` ([`Linearisation`]) by forward-mode duals: one
    /// direction per integrated state, one per modelled coefficient (`∂/∂C_k`, times the
    /// regressor for each parameter) and one per α̇ derivative. The dual width is chosen from
    /// [`FlightModel::n_directions`] (8, 16 or 24), so the cost follows the real sizes.
    ///
    /// # Errors
    /// As [`FlightModel::eval`].
    pub fn linearise(
        &self,
        theta: &[f64],
        u: &ModelInputs,
        active: &[f64],
        out: &mut Linearisation,
    ) -> Result<(), EstimatorError> {
        match self.n_directions() {
            0..=8 => self.linearise_n::<8>(theta, u, active, out),
            9..=16 => self.linearise_n::<16>(theta, u, active, out),
            _ => self.linearise_n::<24>(theta, u, active, out),
        }
    }

    fn linearise_n<const N: usize>(
        &self,
        theta: &[f64],
        u: &ModelInputs,
        active: &[f64],
        out: &mut Linearisation,
    ) -> Result<(), EstimatorError> {
        use crate::dual::Dual;
        let states = self.set.states();
        let nx = states.len();
        let mut xa = [Dual::<N>::constant(0.0); N_STATES];
        for k in 0..nx {
            xa[k] = Dual::variable(active[k], k);
        }
        let x = self.full_state(&xa[..nx], u);
        let mut dc = [Dual::<N>::constant(0.0); 8];
        let mut dd = [Dual::<N>::constant(0.0); 8];
        let mut cdir = [0usize; 8];
        let mut ddir = [0usize; 8];
        let mut dir = nx;
        for m in self.coefs.iter().flatten() {
            let k = m.coefficient.index();
            dc[k] = Dual::variable(0.0, dir);
            cdir[k] = dir;
            dir += 1;
        }
        for m in self.coefs.iter().flatten().filter(|m| m.alphadot.is_some()) {
            let k = m.coefficient.index();
            dd[k] = Dual::variable(0.0, dir);
            ddir[k] = dir;
            dir += 1;
        }
        let mut xi = [0.0; MAX_PARAMS];
        let d = self.eval(theta, u, &x, &dc, &dd, Some(&mut xi))?;
        let coefs = &self.coefs;
        let row = |v: &Dual<N>, dx: &mut [f64; N_STATES], dth: &mut [f64; MAX_PARAMS]| {
            dx[..nx].copy_from_slice(&v.eps[..nx]);
            for m in coefs.iter().flatten() {
                let k = m.coefficient.index();
                let dck = v.eps[cdir[k]];
                for j in 0..m.n {
                    let i = m.first + j;
                    dth[i] =
                        if m.terms[j] == Term::Alphadot { v.eps[ddir[k]] } else { dck * xi[i] };
                }
            }
        };
        for (r, &i) in states.iter().enumerate() {
            out.f[r] = d.xdot[i].re;
            row(&d.xdot[i], &mut out.dfdx[r], &mut out.dfdtheta[r]);
        }
        for o in self.set.outputs() {
            let v = d.output(*o, &x);
            let k = o.index();
            out.y[k] = v.re;
            row(&v, &mut out.dydx[k], &mut out.dydtheta[k]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
