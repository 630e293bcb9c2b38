//! Modes of a [`FlyableAircraft`] (a model-file aircraft, [`super::ModelFileAircraft`])
//! outside what a conventional aircraft flies, each named with the derivatives behind it: an identified model can trim and linearize and still hold
//! a roll mode no airframe has (a roll damping beyond its plausible range, an inertia typed
//! wrong), which a user would otherwise first meet as a simulator that diverges.
//!
//! The ranges:
//! - roll subsidence: stable, and no faster than the largest conventional roll damping gives,
//!   `|λ| ≤ q̄ S b² |Cl_p|max / (2 V Jx)` with `|Cl_p|max` the upper end of the plausible range
//!   ([`aeroident_estimators::prior::plausible_range`]; the roll mode is `L_p` to first order,
//!   Stevens & Lewis §4.5);
//! - short period: stable, and its control anticipation parameter `CAP = ωn² / n_α`
//!   (`n_α = q̄ S CL_alpha / (m g)`, g per rad) within 0.038–10 1/s², the Level 2 bounds of
//!   MIL-F-8785C §3.2.2.1.1 over its flight-phase categories;
//! - spiral: stable, or its time to double at least 4 s (MIL-F-8785C §3.3.1.3, Level 3);
//! - Dutch roll: damped (ζ > 0).

use super::FlyableAircraft;
use aeroident_estimators::AircraftConstants;
use aeroident_estimators::vocabulary::{Coefficient, ModelStructure, Param, Term};
use aeroident_models::aircraft::AircraftTrim;
use aeroident_models::linearize::{Mode, ModeName};
use aeroident_models::rigid_body as rb;
use aeroident_physics::text::Short;

/// MIL-F-8785C's Level 2 CAP bounds over its categories, 1/s².
const CAP_RANGE: (f64, f64) = (0.038, 10.0);
/// MIL-F-8785C's Level 3 least spiral time to double, s.
const SPIRAL_MIN_DOUBLE_S: f64 = 4.0;

/// The flags of `modes` of `aircraft` linearized about `trim` (module doc); empty when every
/// mode is in range, or when the aircraft's air or derivatives at the trim are unknown.
pub fn mode_flags<const N: usize>(
    aircraft: &impl FlyableAircraft<N>,
    trim: &AircraftTrim<N>,
    modes: &[Mode],
) -> Vec<String> {
    let state = aircraft.rigid_body_si(&trim.state);
    let (Ok(rho), Ok(theta)) =
        (aircraft.density_kgpm3(state[rb::ALT]), aircraft.flown_values(trim))
    else {
        return Vec::new();
    };
    let (vt, constants) = (state[rb::VT], aircraft.constants());
    let structure = aircraft.flown_structure();
    let at = Trimmed { structure, theta, constants, vt, qbar: 0.5 * rho * vt * vt };
    modes.iter().filter_map(|m| at.flag(m)).collect()
}

/// The aircraft's derivatives and constants at its trim's speed and dynamic pressure.
struct Trimmed {
    structure: ModelStructure,
    theta: Vec<f64>,
    constants: AircraftConstants,
    vt: f64,
    qbar: f64,
}

impl Trimmed {
    /// The value the aircraft flies for `coefficient_term`, 0 when its model has none.
    fn value(&self, coefficient: Coefficient, term: Term) -> f64 {
        let p = Param::new(coefficient, term);
        self.structure.params().position(|q| q == p).map_or(0.0, |i| self.theta[i])
    }

    /// `names` with the values flown, for a message.
    fn named(&self, names: &[(Coefficient, Term)]) -> String {
        let one = |&(c, t): &(Coefficient, Term)| {
            format!("{} = {}", Param::new(c, t).name(), Short(self.value(c, t)))
        };
        names.iter().map(one).collect::<Vec<_>>().join(", ")
    }

    fn flag(&self, m: &Mode) -> Option<String> {
        use Coefficient::*;
        let re = m.eigenvalue.re;
        match m.name {
            ModeName::Roll => self.roll(re),
            ModeName::ShortPeriod => self.short_period(m),
            ModeName::ShortPeriodReal if re > 0.0 => Some(format!(
                "short period diverges (λ = {} 1/s): {}",
                Short(re),
                self.named(&[(Cm, Term::Alpha), (Cm, Term::Q), (CL, Term::Alpha)])
            )),
            ModeName::Spiral if re > 0.0 && 2f64.ln() / re < SPIRAL_MIN_DOUBLE_S => Some(format!(
                "spiral doubles in {} s (under MIL-F-8785C's Level 3 {SPIRAL_MIN_DOUBLE_S} s): {}",
                Short(2f64.ln() / re),
                self.named(&[(Cl, Term::Beta), (Cn, Term::Beta), (Cl, Term::R), (Cn, Term::R)])
            )),
            ModeName::DutchRoll if m.zeta <= 0.0 => Some(format!(
                "Dutch roll undamped (ζ = {}): {}",
                Short(m.zeta),
                self.named(&[(Cn, Term::Beta), (Cn, Term::R), (Cl, Term::Beta)])
            )),
            _ => None,
        }
    }

    /// The roll mode against the stability and the conventional damping bound (module doc).
    fn roll(&self, re: f64) -> Option<String> {
        let c = &self.constants;
        let (span, jx) = (c.b_m.unwrap_or(f64::NAN), c.Ixx_kgm2.unwrap_or(f64::NAN));
        let cl_p = Param::new(Coefficient::Cl, Term::P);
        let largest = aeroident_estimators::prior::plausible_range(cl_p).map_or(1.5, |r| r.0.abs());
        let bound = self.qbar * c.S_m2 * span.powi(2) * largest / (2.0 * self.vt * jx);
        let named =
            format!("{}, Jx = {} kg·m²", self.named(&[(Coefficient::Cl, Term::P)]), Short(jx));
        if re >= 0.0 {
            return Some(format!("roll mode not damped (λ = {} 1/s): {named}", Short(re)));
        }
        (-re > bound).then(|| {
            format!(
                "roll mode λ = {} 1/s (time constant {} s) is faster than the largest conventional roll damping gives (|Cl_p| = {}: −{} 1/s): {named}",
                Short(re),
                Short(-1.0 / re),
                Short(largest),
                Short(bound)
            )
        })
    }

    /// The short period against stability and the CAP range (module doc).
    fn short_period(&self, m: &Mode) -> Option<String> {
        use Coefficient::*;
        let named = self.named(&[(Cm, Term::Alpha), (Cm, Term::Q), (CL, Term::Alpha)]);
        if m.zeta <= 0.0 {
            return Some(format!("short period undamped (ζ = {}): {named}", Short(m.zeta)));
        }
        let c = &self.constants;
        let n_alpha = self.qbar * c.S_m2 * self.value(CL, Term::Alpha)
            / (c.mass_kg * aeroident_physics::units::G0_MPS2);
        let cap = m.wn_rad_s.powi(2) / n_alpha;
        let inside = n_alpha > 0.0 && (CAP_RANGE.0..=CAP_RANGE.1).contains(&cap);
        (!inside).then(|| {
            format!(
                "short period ωn {} rad/s gives CAP {} 1/s² (n_α {} g/rad), outside MIL-F-8785C's Level 2 {}–{}: {named}",
                Short(m.wn_rad_s),
                Short(cap),
                Short(n_alpha),
                CAP_RANGE.0,
                CAP_RANGE.1
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airframe::ModelFileAircraft;
    use nalgebra::Complex;

    /// An elevator-and-aileron UAV (3.3 kg, Jx 0.17 kg·m², S 0.384 m², b 1.6 m) with
    /// CL_alpha 4.8 and Cl_p −0.45, from files as a user gives them.
    fn uav() -> ModelFileAircraft {
        let thread = format!("{:?}", std::thread::current().id()).replace(['(', ')'], "");
        let dir =
            std::env::temp_dir().join(format!("aeroident-modes-{}-{thread}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut model = String::from(
            "description = \"uav\"\n[coefficients]\nCL = [\"0\", \"alpha\"]\nCD = [\"0\"]\nCY = [\"beta\"]\nCl = [\"beta\", \"p\", \"da\"]\nCm = [\"0\", \"alpha\", \"q\", \"de\"]\nCn = [\"beta\", \"r\"]\n",
        );
        for (n, v) in [
            ("CL_0", 0.3),
            ("CL_alpha", 4.8),
            ("CD_0", 0.03),
            ("CY_beta", -0.3),
            ("Cl_beta", -0.08),
            ("Cl_p", -0.45),
            ("Cl_da", -0.25),
            ("Cm_0", 0.02),
            ("Cm_alpha", -0.6),
            ("Cm_q", -9.0),
            ("Cm_de", -1.0),
            ("Cn_beta", 0.06),
            ("Cn_r", -0.08),
        ] {
            model.push_str(&format!("[reference.{n}]\nvalue = {v}\nsource = \"t\"\n"));
        }
        let map = "description = \"c\"\n[time]\ncolumn = \"t\"\nunit = \"s\"\n[channels]\nvt = { column = \"v\", unit = \"m/s\" }\nalpha = { column = \"a\", unit = \"rad\" }\nqbar = { column = \"q\", unit = \"Pa\" }\nmass = { value = 3.3, unit = \"kg\" }\nIxx = { value = 0.17, unit = \"kg*m2\" }\nIyy = { value = 0.289, unit = \"kg*m2\" }\nIzz = { value = 0.443, unit = \"kg*m2\" }\nS = { value = 0.384, unit = \"m2\" }\nb = { value = 1.6, unit = \"m\" }\ncbar = { value = 0.24, unit = \"m\" }\n";
        let (m, c) = (dir.join("uav.toml"), dir.join("c.toml"));
        std::fs::write(&m, model).unwrap();
        std::fs::write(&c, map).unwrap();
        crate::airframe::load(&m, None, &c).unwrap()
    }

    /// 18 m/s at sea level (ISA ρ 1.225 kg/m³): q̄ = 198.45 Pa.
    fn state() -> AircraftTrim<{ super::super::N_STATES }> {
        let mut state = super::super::AirframeState::zeros();
        state[rb::VT] = 18.0;
        let controls = aeroident_models::aircraft::ControlVector::zeros();
        AircraftTrim { state, controls, max_abs_residual: 0.0 }
    }

    const QBAR: f64 = 0.5 * 1.225 * 18.0 * 18.0;

    fn mode(name: ModeName, re: f64, im: f64) -> Mode {
        let wn = (re * re + im * im).sqrt();
        Mode { name, eigenvalue: Complex::new(re, im), wn_rad_s: wn, zeta: -re / wn }
    }

    #[test]
    fn the_roll_mode_at_the_largest_conventional_damping_and_beyond() {
        // |λ| ≤ q̄ S b² · 1.5 / (2 V Jx), computed here from the numbers above.
        let bound = QBAR * 0.384 * 1.6 * 1.6 * 1.5 / (2.0 * 18.0 * 0.17);
        let (a, x) = (uav(), state());
        assert!(mode_flags(&a, &x, &[mode(ModeName::Roll, -bound * 0.999, 0.0)]).is_empty());
        let f = mode_flags(&a, &x, &[mode(ModeName::Roll, -bound * 1.001, 0.0)]);
        assert!(
            f.len() == 1 && f[0].contains("Cl_p = -0.45") && f[0].contains("Jx = 0.17"),
            "{f:?}"
        );
        assert_eq!(mode_flags(&a, &x, &[mode(ModeName::Roll, 0.01, 0.0)]).len(), 1);
    }

    #[test]
    fn the_short_period_cap_at_both_ends_and_an_undamped_one() {
        let n_alpha = QBAR * 0.384 * 4.8 / (3.3 * 9.80665);
        let (a, x) = (uav(), state());
        let sp = |cap: f64| {
            let wn = (cap * n_alpha).sqrt();
            mode(ModeName::ShortPeriod, -0.5 * wn, wn * 0.75f64.sqrt())
        };
        for (cap, flagged) in [(0.0379, true), (0.0381, false), (9.99, false), (10.01, true)] {
            let f = mode_flags(&a, &x, &[sp(cap)]);
            assert_eq!(f.len(), usize::from(flagged), "CAP {cap}: {f:?}");
            if flagged {
                assert!(f[0].contains("Cm_alpha = -0.6") && f[0].contains("CL_alpha = 4.8"));
            }
        }
        let undamped = mode(ModeName::ShortPeriod, 0.0, 5.0);
        assert!(mode_flags(&a, &x, &[undamped])[0].contains("undamped"));
    }

    #[test]
    fn the_spiral_at_four_seconds_to_double_and_an_undamped_dutch_roll() {
        let (a, x) = (uav(), state());
        let at = 2f64.ln() / 4.0;
        assert!(mode_flags(&a, &x, &[mode(ModeName::Spiral, at * 0.999, 0.0)]).is_empty());
        let f = mode_flags(&a, &x, &[mode(ModeName::Spiral, at * 1.001, 0.0)]);
        assert!(f.len() == 1 && f[0].contains("Cn_r = -0.08"), "{f:?}");
        assert!(mode_flags(&a, &x, &[mode(ModeName::DutchRoll, -0.01, 3.0)]).is_empty());
        let f = mode_flags(&a, &x, &[mode(ModeName::DutchRoll, 0.0, 3.0)]);
        assert!(f.len() == 1 && f[0].contains("Cn_beta = 0.06"), "{f:?}");
    }

    /// A partial test card (no rudder derivative) trims with the rudder held at 0, says so,
    /// and its modes at 18 m/s are a conventional UAV's: none is flagged.
    #[test]
    fn an_elevator_and_aileron_model_trims_with_the_rudder_held_and_flies_conventional_modes() {
        let a = uav();
        assert_eq!(a.held_surfaces(), ["dr"]);
        assert!(a.held_surfaces_note().unwrap().contains("`dr`"));
        let l = aeroident_models::aircraft::linearize_level(&a, 18.0, 0.0).unwrap();
        assert_eq!(l.trim.controls[3], 0.0);
        assert!(l.trim.max_abs_residual < 1e-10);
        let flags = mode_flags(&a, &l.trim, &l.modes);
        assert!(flags.is_empty() && l.modes.len() >= 4, "{flags:?} {:?}", l.modes);
    }
}
