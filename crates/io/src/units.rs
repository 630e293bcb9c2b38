//! Physical units of recorded channels and their conversion to the internal SI system.
//!
//! **Internal unit system: SI** — s, m, kg, N, Pa, rad (m/s, rad/s, m/s², kg·m², kg/m³, N·m).
//! Two of the shipped records are SI (HFB-320, ATTAS) and two English (Twin Otter, JSBSim);
//! the non-dimensional coefficients the estimators identify do not depend on the choice.
//! Conversion factors are exact where defined so (ft = 0.3048 m, lb = 0.45359237 kg,
//! g₀ = 9.80665 m/s², kt = 1852/3600 m/s; NIST SP 811 appendix B); they are defined once, in
//! [`aeroident_physics::units`].

use std::fmt;

/// The physical dimension a channel must have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Time.
    Time,
    /// Plane angle.
    Angle,
    /// Angular rate.
    AngularRate,
    /// Angular acceleration.
    AngularAcceleration,
    /// Length.
    Length,
    /// Speed.
    Speed,
    /// Linear acceleration (accelerometers).
    Acceleration,
    /// Pressure (dynamic pressure).
    Pressure,
    /// Force (thrust).
    Force,
    /// Moment (thrust pitching moment).
    Moment,
    /// Mass.
    Mass,
    /// Moment of inertia.
    Inertia,
    /// Area.
    Area,
    /// Density.
    Density,
    /// No dimension.
    Dimensionless,
}

impl fmt::Display for Dimension {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            Dimension::Time => "time (s, ms, us)",
            Dimension::Angle => "angle (rad, deg)",
            Dimension::AngularRate => "angular rate (rad/s, deg/s, rpm, rev/s)",
            Dimension::AngularAcceleration => "angular acceleration (rad/s2, deg/s2)",
            Dimension::Length => "length (m, ft, in)",
            Dimension::Speed => "speed (m/s, ft/s, kt, km/h)",
            Dimension::Acceleration => "acceleration (m/s2, ft/s2, g)",
            Dimension::Pressure => "pressure (Pa, hPa, kPa, psf, psi)",
            Dimension::Force => "force (N, kN, lbf)",
            Dimension::Moment => "moment (N*m, lbf*ft)",
            Dimension::Mass => "mass (kg, slug, lb)",
            Dimension::Inertia => "moment of inertia (kg*m2, slug*ft2)",
            Dimension::Area => "area (m2, ft2)",
            Dimension::Density => "density (kg/m3, slug/ft3)",
            Dimension::Dimensionless => "dimensionless (1, -)",
        };
        f.write_str(s)
    }
}

use aeroident_physics::units::{
    KG_PER_LB, KG_PER_SLUG, KGM2_PER_SLUGFT2, KGPM3_PER_SLUGPFT3, M_PER_FT, M_PER_IN, M2_PER_FT2,
    MPS_PER_KT, N_PER_LBF, NM_PER_LBFFT, PA_PER_PSF, PA_PER_PSI,
};

/// Standard gravity, m/s² (the `g` unit of accelerometers; re-exported from
/// [`aeroident_physics::units`]).
pub use aeroident_physics::units::G0_MPS2;

/// A parsed unit: its dimension and the factor that converts a value to SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    /// What the unit measures.
    pub dimension: Dimension,
    /// SI value = value × `to_si`.
    pub to_si: f64,
}

/// Error: a unit string that is not recognised.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "unit `{0}` is not recognised (e.g. s, ms, us, rad, deg, deg/s, rad/s2, m, ft, m/s, ft/s, kt, m/s2, g, Pa, psf, N, lbf, kg, slug, kg*m2, slug*ft2, m2, ft2, kg/m3, slug/ft3, N*m, lbf*ft, 1)"
)]
pub struct UnknownUnit(pub String);

impl Unit {
    /// Parses a unit string such as `"deg/s"`, `"ft/s²"`, `"slug·ft^2"`, `"kt"`.
    /// Case-insensitive except that `Pa`/`pa` are the same; `²`, `³`, `^`, `·` and spaces are
    /// normalised.
    ///
    /// # Errors
    /// [`UnknownUnit`] naming the string.
    pub fn parse(s: &str) -> Result<Self, UnknownUnit> {
        use Dimension as D;
        let norm: String = s
            .trim()
            .to_lowercase()
            .replace('²', "2")
            .replace('³', "3")
            .replace(['^', ' '], "")
            .replace(['·', '.'], "*");
        let (dimension, to_si) = match norm.as_str() {
            "s" | "sec" => (D::Time, 1.0),
            "ms" => (D::Time, 1e-3),
            // PX4 ULog and ArduPilot DataFlash timestamps are microseconds.
            "us" | "µs" | "μs" | "usec" => (D::Time, 1e-6),
            "rad" => (D::Angle, 1.0),
            "deg" => (D::Angle, core::f64::consts::PI / 180.0),
            "rad/s" | "radps" => (D::AngularRate, 1.0),
            "deg/s" | "degps" => (D::AngularRate, core::f64::consts::PI / 180.0),
            "rpm" => (D::AngularRate, core::f64::consts::TAU / 60.0),
            "rev/s" | "rps" => (D::AngularRate, core::f64::consts::TAU),
            "rad/s2" | "radps2" => (D::AngularAcceleration, 1.0),
            "deg/s2" | "degps2" => (D::AngularAcceleration, core::f64::consts::PI / 180.0),
            "m" => (D::Length, 1.0),
            "ft" => (D::Length, M_PER_FT),
            "in" => (D::Length, M_PER_IN),
            "m/s" | "mps" => (D::Speed, 1.0),
            "ft/s" | "fps" => (D::Speed, M_PER_FT),
            "kt" | "kts" => (D::Speed, MPS_PER_KT),
            "km/h" | "kph" => (D::Speed, 1.0 / 3.6),
            "m/s2" | "mps2" => (D::Acceleration, 1.0),
            "ft/s2" | "fps2" => (D::Acceleration, M_PER_FT),
            "g" => (D::Acceleration, G0_MPS2),
            "pa" | "n/m2" => (D::Pressure, 1.0),
            "hpa" | "mbar" => (D::Pressure, 100.0),
            "kpa" => (D::Pressure, 1000.0),
            "psf" | "lbf/ft2" => (D::Pressure, PA_PER_PSF),
            "psi" | "lbf/in2" => (D::Pressure, PA_PER_PSI),
            "n" => (D::Force, 1.0),
            "kn" => (D::Force, 1000.0),
            "lbf" | "lbs" => (D::Force, N_PER_LBF),
            "n*m" | "nm" | "m*n" => (D::Moment, 1.0),
            "lbf*ft" | "ft*lbf" | "lbsft" | "lbs*ft" => (D::Moment, NM_PER_LBFFT),
            "kg" => (D::Mass, 1.0),
            "slug" => (D::Mass, KG_PER_SLUG),
            "lb" | "lbm" => (D::Mass, KG_PER_LB),
            "kg*m2" | "kgm2" => (D::Inertia, 1.0),
            "slug*ft2" | "slugft2" => (D::Inertia, KGM2_PER_SLUGFT2),
            "m2" => (D::Area, 1.0),
            "ft2" => (D::Area, M2_PER_FT2),
            "kg/m3" | "kgpm3" => (D::Density, 1.0),
            "slug/ft3" | "slugft3" => (D::Density, KGPM3_PER_SLUGPFT3),
            "1" | "-" | "" | "none" => (D::Dimensionless, 1.0),
            _ => return Err(UnknownUnit(s.to_string())),
        };
        Ok(Self { dimension, to_si })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn val_nist_sp811_conversion_factors() {
        // NIST SP 811 App. B: 1 lbf = 4.448 222 N, 1 slug = 14.593 90 kg, 1 psf = 47.880 26 Pa,
        // 1 kt = 0.514 444 m/s, 1 slug/ft³ = 515.3788 kg/m³, 1 slug·ft² = 1.355 818 kg·m².
        let close = |u: &str, v: f64, tol: f64| {
            let got = Unit::parse(u).unwrap().to_si;
            assert!((got - v).abs() < tol * v, "{u}: {got} vs {v}");
        };
        close("lbf", 4.448_222, 1e-6);
        close("slug", 14.593_90, 1e-6);
        close("psf", 47.880_26, 1e-6);
        close("kt", 0.514_444, 1e-6);
        close("slug/ft3", 515.3788, 1e-6);
        close("slug*ft2", 1.355_818, 1e-6);
        close("deg", 0.017_453_292_519_943_295, 1e-15);
        close("g", 9.80665, 1e-15);
        close("ft/s²", 0.3048, 1e-15);
        close("slug·ft^2", 1.355_818, 1e-6);
        assert_eq!(Unit::parse("deg/s").unwrap().dimension, Dimension::AngularRate);
        assert_eq!(Unit::parse("Pa").unwrap(), Unit::parse("pa").unwrap());
    }

    #[test]
    fn analytic_time_units_s_ms_us() {
        // 1 ms = 10⁻³ s, 1 µs = 10⁻⁶ s (SI prefixes); both spellings of µ and ASCII `us`.
        for (u, f) in [("s", 1.0), ("ms", 1e-3), ("us", 1e-6), ("µs", 1e-6), ("μs", 1e-6)] {
            let unit = Unit::parse(u).unwrap();
            assert_eq!(unit.dimension, Dimension::Time, "{u}");
            assert_eq!(unit.to_si, f, "{u}");
        }
        // A ULog timestamp in µs converts to the seconds the reader works in.
        assert_eq!(1_234_567.0 * Unit::parse("us").unwrap().to_si, 1.234_567);
    }

    #[test]
    fn errors_unknown_unit_names_it() {
        let e = Unit::parse("furlong/fortnight").unwrap_err();
        assert!(e.to_string().contains("furlong/fortnight"));
    }
}
