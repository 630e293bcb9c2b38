//! The air-data computer of the Stevens–Lewis F-16 model (SLJ §3.5, subroutine ADC): a linear
//! temperature lapse to 35 000 ft and an isothermal layer above, density by a power law.
//!
//! ```text
//! tfac = 1 − 0.703e-5·h ;  T = 519·tfac °R (390 °R for h ≥ 35 000 ft) ;  ρ = 2.377e-3·tfac^4.14
//! M = V / √(1.4·1716.3·T) ;  q̄ = ½ ρ V²
//! ```
//! WARNING: this is the textbook's approximation, not the 1976 standard atmosphere; above
//! about 142 000 ft `tfac` ≤ 0 and the model is undefined ([`ModelError::InvalidValue`]).

use crate::ModelError;
use crate::f16::data::AtmosphereConstants;

/// Air data at one altitude and airspeed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirData {
    /// Mach number.
    pub mach: f64,
    /// Dynamic pressure q̄ = ½ρV², lbf/ft².
    pub qbar_psf: f64,
    /// Density, slug/ft³.
    pub rho_slug_ft3: f64,
    /// Static temperature, °R.
    pub temperature_r: f64,
}

/// Air data for true airspeed `vt_fps` (ft/s) at altitude `alt_ft` (ft, up), SLJ §3.5 ADC.
///
/// # Errors
/// [`ModelError::InvalidValue`] when the altitude is not finite or above the model's domain
/// (`tfac ≤ 0`), or `vt_fps` is not finite.
#[inline]
pub fn air_data(c: &AtmosphereConstants, vt_fps: f64, alt_ft: f64) -> Result<AirData, ModelError> {
    let tfac = 1.0 - c.temperature_factor_per_ft * alt_ft;
    if !(tfac > 0.0 && tfac.is_finite()) {
        return Err(ModelError::InvalidValue {
            field: "alt_ft",
            value: alt_ft,
            reason: "outside the ADC model's domain (tfac <= 0)",
        });
    }
    if !vt_fps.is_finite() {
        return Err(ModelError::InvalidValue {
            field: "vt_fps",
            value: vt_fps,
            reason: "not finite",
        });
    }
    let temperature_r = if alt_ft >= c.tropopause_altitude_ft {
        c.t_above_tropopause_rankine
    } else {
        c.t0_rankine * tfac
    };
    let rho_slug_ft3 = c.rho0_slug_per_ft3 * tfac.powf(c.density_exponent);
    let mach = vt_fps / (c.gamma * c.gas_constant_speed_of_sound * temperature_r).sqrt();
    Ok(AirData {
        mach,
        qbar_psf: 0.5 * rho_slug_ft3 * vt_fps * vt_fps,
        rho_slug_ft3,
        temperature_r,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::f16::F16Data;

    #[test]
    fn val_slj_adc_check_values() {
        // Check values printed in the data set (h = 10 000 ft, V = 500 ft/s): M 0.4643595, q̄ 219.72452.
        let a = air_data(&F16Data::embedded().atmosphere, 500.0, 10_000.0).unwrap();
        assert!((a.mach - 0.464_359_45).abs() < 1e-7);
        assert!((a.qbar_psf - 219.724_52).abs() < 1e-4);
    }

    #[test]
    fn analytic_sea_level_and_tropopause() {
        let c = &F16Data::embedded().atmosphere;
        let a = air_data(c, 0.0, 0.0).unwrap();
        assert_eq!(a.rho_slug_ft3, 2.377e-3);
        assert_eq!(a.temperature_r, 519.0);
        let b = air_data(c, 100.0, 40_000.0).unwrap();
        assert_eq!(b.temperature_r, 390.0);
        let tfac: f64 = 1.0 - 0.703e-5 * 40_000.0;
        assert!((b.rho_slug_ft3 - 2.377e-3 * tfac.powf(4.14)).abs() < 1e-15);
        assert!(air_data(c, 100.0, 200_000.0).is_err());
        assert!(air_data(c, f64::NAN, 0.0).is_err());
    }
}
