//! The International Standard Atmosphere to 20 km: what a flight log's pressure altitude and
//! static temperature mean, so that air density can be formed from them.
//!
//! Source: ISO 2533:1975 / ICAO Doc 7488 (identical to the U.S. Standard Atmosphere 1976 below
//! 32 km): sea level 101 325 Pa, 288.15 K; a lapse of 6.5 K/km to the tropopause at 11 km
//! geopotential; isothermal at 216.65 K from 11 to 20 km. With `R = 287.052 87 J/(kg·K)` and
//! `g0 = 9.806 65 m/s²`:
//!
//! ```text
//! h ≤ 11 km:  T = T0 − L h,  p = p0 (T / T0)^(g0 / (R L))
//! h > 11 km:  T = T11,       p = p11 exp(−g0 (h − 11 km) / (R T11))
//! ρ = p / (R T)   (ideal gas: with the *measured* static temperature on a non-standard day)
//! ```
//!
//! Pressure altitude is, by definition, the altitude at which the standard atmosphere has the
//! measured static pressure, so `pressure_pa(pressure altitude)` is the static pressure whatever
//! the day; the temperature of the day comes from the outside-air-temperature probe.

use crate::units::G0_MPS2;

/// Sea-level standard pressure, Pa.
pub const P0_PA: f64 = 101_325.0;
/// Sea-level standard temperature, K.
pub const T0_K: f64 = 288.15;
/// Tropospheric temperature lapse rate, K/m.
pub const LAPSE_K_PER_M: f64 = 0.0065;
/// Tropopause (geopotential) altitude, m.
pub const TROPOPAUSE_M: f64 = 11_000.0;
/// Upper end of this model (top of the isothermal layer), m.
pub const TOP_M: f64 = 20_000.0;
/// Lowest altitude accepted, m (below the Dead Sea shore, above any plausible error).
pub const BOTTOM_M: f64 = -1_000.0;
/// Specific gas constant of dry air, J/(kg·K).
pub const R_AIR_J_PER_KG_K: f64 = 287.052_87;

/// Standard temperature at geopotential altitude `h_m`, K; `None` outside
/// [`BOTTOM_M`]..=[`TOP_M`] or not finite.
pub fn temperature_k(h_m: f64) -> Option<f64> {
    if !(BOTTOM_M..=TOP_M).contains(&h_m) {
        return None;
    }
    Some(T0_K - LAPSE_K_PER_M * h_m.min(TROPOPAUSE_M))
}

/// Standard static pressure at geopotential (pressure) altitude `h_m`, Pa; `None` outside
/// [`BOTTOM_M`]..=[`TOP_M`] or not finite.
pub fn pressure_pa(h_m: f64) -> Option<f64> {
    let t = temperature_k(h_m)?;
    let exponent = G0_MPS2 / (R_AIR_J_PER_KG_K * LAPSE_K_PER_M);
    if h_m <= TROPOPAUSE_M {
        return Some(P0_PA * libm::pow(t / T0_K, exponent));
    }
    let t11 = T0_K - LAPSE_K_PER_M * TROPOPAUSE_M;
    let p11 = P0_PA * libm::pow(t11 / T0_K, exponent);
    Some(p11 * libm::exp(-G0_MPS2 * (h_m - TROPOPAUSE_M) / (R_AIR_J_PER_KG_K * t11)))
}

/// Air density from static pressure `p_pa` (Pa) and static temperature `t_k` (K) by the ideal
/// gas law, kg/m³.
pub fn density_kgpm3(p_pa: f64, t_k: f64) -> f64 {
    p_pa / (R_AIR_J_PER_KG_K * t_k)
}

/// Ratio of specific heats of dry air, –.
pub const GAMMA_AIR: f64 = 1.4;

/// The standard temperature at the altitude whose standard density is `rho_kgpm3`, K (the
/// temperature of the *density altitude*); `None` for a density that is not finite or lies
/// outside the model's range ([`BOTTOM_M`]..=[`TOP_M`]).
///
/// Below the tropopause the standard atmosphere has `ρ/ρ0 = (T/T0)^(n − 1)`, `n = g0/(R L)`,
/// so `T = T0 (ρ/ρ0)^(1/(n − 1))`; above it `T` is 216.65 K. On a day `ΔT` off standard at a
/// given pressure altitude this is not the day's temperature: the density altitude's standard
/// temperature is then about `T_std − 0.235 ΔT`, an error of `−1.235 ΔT` (from `ρ ∝ p/T` and
/// `p ∝ T^n` along the standard atmosphere), so that a speed of sound formed from it is off by
/// about `−0.62 ΔT/T` (−3.2 % at ISA + 15 K near sea level).
pub fn temperature_of_density_k(rho_kgpm3: f64) -> Option<f64> {
    let n = G0_MPS2 / (R_AIR_J_PER_KG_K * LAPSE_K_PER_M);
    let rho0 = density_kgpm3(P0_PA, T0_K);
    let t11 = T0_K - LAPSE_K_PER_M * TROPOPAUSE_M;
    let rho_of = |h: f64| Some(density_kgpm3(pressure_pa(h)?, temperature_k(h)?));
    let (top, bottom, rho11) = (rho_of(TOP_M)?, rho_of(BOTTOM_M)?, rho_of(TROPOPAUSE_M)?);
    if !(top..=bottom).contains(&rho_kgpm3) {
        return None;
    }
    if rho_kgpm3 <= rho11 {
        return Some(t11);
    }
    Some(T0_K * libm::pow(rho_kgpm3 / rho0, 1.0 / (n - 1.0)))
}

/// Speed of sound in dry air at static temperature `t_k`, m/s: `√(γ R T)`.
pub fn speed_of_sound_mps(t_k: f64) -> f64 {
    libm::sqrt(GAMMA_AIR * R_AIR_J_PER_KG_K * t_k)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published ISA table values (ICAO Doc 7488 / U.S. Standard Atmosphere 1976, Table I):
    /// pressure and density at sea level, 5 km, 11 km and 20 km.
    #[test]
    fn matches_the_standard_atmosphere_table() {
        for (h, p, rho) in [
            (0.0, 101_325.0, 1.2250),
            (5_000.0, 54_019.9, 0.736_12),
            (11_000.0, 22_632.1, 0.363_92),
            (20_000.0, 5_474.89, 0.088_035),
        ] {
            let pp = pressure_pa(h).unwrap();
            let rr = density_kgpm3(pp, temperature_k(h).unwrap());
            assert!((pp / p - 1.0).abs() < 2e-5, "{h} m: {pp} Pa vs {p}");
            assert!((rr / rho - 1.0).abs() < 2e-4, "{h} m: {rr} kg/m3 vs {rho}");
        }
        assert_eq!(pressure_pa(20_001.0), None);
        assert_eq!(pressure_pa(f64::NAN), None);
    }

    /// The density altitude's temperature reads back the standard temperature of the standard
    /// density (ICAO Doc 7488 table values: 1.2250 kg/m³ → 288.15 K, 0.736 12 → 255.65 K,
    /// 0.363 92 → 216.65 K, 0.2 kg/m³ in the isothermal layer → 216.65 K) and the speed of
    /// sound at sea level is 340.29 m/s (same table).
    #[test]
    fn temperature_of_density_inverts_the_table() {
        for (rho, t) in [(1.2250, 288.15), (0.736_12, 255.65), (0.363_92, 216.65), (0.2, 216.65)] {
            let got = temperature_of_density_k(rho).unwrap();
            assert!((got - t).abs() < 0.02, "{rho} kg/m3: {got} K vs {t}");
        }
        assert!((speed_of_sound_mps(288.15) - 340.294).abs() < 0.01);
        assert_eq!(temperature_of_density_k(f64::NAN), None);
        assert_eq!(temperature_of_density_k(2.0), None);
        assert_eq!(temperature_of_density_k(0.01), None);
    }
}
