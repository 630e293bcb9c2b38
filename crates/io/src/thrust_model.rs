//! Thrust from a law when the record has no thrust channel: `[thrust_model]` in a mapping.
//!
//! Without thrust, the force equations see drag minus thrust, and the drag terms are reported
//! not identified. A small UAV logs its throttle and often its motor speed, not its thrust; two
//! laws turn them into thrust, evaluated per sample, so every estimator sees the thrust as if
//! it had been measured (the `thrust_n` sample field):
//!
//! - **`propeller`**: `T = ρ n² D⁴ · (ct0 + ct_j · J)`, `J = V / (n D)`, with `n` the shaft
//!   speed in revolutions per second (the mapping's `prop_speed` channel), `D` the diameter.
//!   The thrust coefficient linear in the advance ratio is the usual first approximation of a
//!   fixed-pitch propeller below its zero-thrust advance ratio (McCormick, *Aerodynamics,
//!   Aeronautics, and Flight Mechanics*, the propeller chapter; the wind-tunnel cT(J) of small
//!   UAV propellers in Brandt & Selig, AIAA 2011-1255, fall nearly linearly with J over most
//!   of their operating range).
//!   `ct0` and `ct_j` come from the propeller's data or a static/wind-tunnel test.
//! - **`throttle`**: `T = static_thrust · throttle^exponent · (1 − V / zero_thrust_speed)`, the
//!   static thrust falling linearly to zero at the speed where the propeller stops pulling (the
//!   `throttle` channel, 0 … 1). A cruder law for a log without motor speed; its three
//!   constants come from a static thrust-stand test and the propeller's pitch speed.
//!
//! A negative result (a windmilling propeller: `J` beyond `−ct0/ct_j`, `V` beyond the zero-
//! thrust speed) is kept: the propeller then drags, which is what the law says. The moment of
//! the thrust is the mapping's `thrust_arm`/`thrust_moment`, as for a measured thrust.

use serde::Deserialize;

/// A thrust law (module doc), constants SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ThrustModel {
    /// `T = ρ n² D⁴ (ct0 + ct_j J)`, `J = V/(n D)`; `n` rev/s from the `prop_speed` channel.
    Propeller {
        /// Propeller diameter `D`, m.
        diameter_m: f64,
        /// Static thrust coefficient `cT(J = 0)`.
        ct0: f64,
        /// Slope of the thrust coefficient with the advance ratio, `dcT/dJ` (usually < 0).
        ct_j: f64,
    },
    /// `T = static_thrust_n · throttle^exponent · (1 − V / zero_thrust_speed_mps)`.
    Throttle {
        /// Thrust at full throttle and zero airspeed, N.
        static_thrust_n: f64,
        /// Airspeed at which the thrust falls to zero, m/s.
        zero_thrust_speed_mps: f64,
        /// Exponent of the throttle (1: thrust proportional to throttle).
        exponent: f64,
    },
}

/// The record channel a law reads besides ρ and V (the mapping's `prop_speed` or `throttle`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LawInput {
    /// Propeller shaft speed, rad/s.
    PropSpeed,
    /// Throttle, 0 … 1.
    Throttle,
}

/// `[thrust_model]` as written in a mapping file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ThrustModelFile {
    law: String,
    diameter_m: Option<f64>,
    ct0: Option<f64>,
    ct_j: Option<f64>,
    static_thrust_n: Option<f64>,
    zero_thrust_speed_mps: Option<f64>,
    exponent: Option<f64>,
}

impl ThrustModelFile {
    /// The law, its constants checked: `Err` with the reason (the key and value at fault).
    pub(crate) fn resolve(&self) -> Result<ThrustModel, String> {
        let need = |key: &str, v: Option<f64>| {
            v.ok_or_else(|| format!("law `{}` needs `{key}`", self.law))
        };
        let refuse_others = |allowed: &[&str]| -> Result<(), String> {
            let given = [
                ("diameter_m", self.diameter_m),
                ("ct0", self.ct0),
                ("ct_j", self.ct_j),
                ("static_thrust_n", self.static_thrust_n),
                ("zero_thrust_speed_mps", self.zero_thrust_speed_mps),
                ("exponent", self.exponent),
            ];
            match given.iter().find(|(k, v)| v.is_some() && !allowed.contains(k)) {
                Some((k, _)) => Err(format!("`{k}` is not a constant of law `{}`", self.law)),
                None => Ok(()),
            }
        };
        let model = match self.law.as_str() {
            "propeller" => {
                refuse_others(&["diameter_m", "ct0", "ct_j"])?;
                ThrustModel::Propeller {
                    diameter_m: need("diameter_m", self.diameter_m)?,
                    ct0: need("ct0", self.ct0)?,
                    ct_j: self.ct_j.unwrap_or(0.0),
                }
            }
            "throttle" => {
                refuse_others(&["static_thrust_n", "zero_thrust_speed_mps", "exponent"])?;
                ThrustModel::Throttle {
                    static_thrust_n: need("static_thrust_n", self.static_thrust_n)?,
                    zero_thrust_speed_mps: need(
                        "zero_thrust_speed_mps",
                        self.zero_thrust_speed_mps,
                    )?,
                    exponent: self.exponent.unwrap_or(1.0),
                }
            }
            other => {
                return Err(format!(
                    "unknown law `{other}` (known: `propeller`, T = ρ n² D⁴ (ct0 + ct_j J); `throttle`, T = static_thrust_n · throttle^exponent · (1 − V/zero_thrust_speed_mps))"
                ));
            }
        };
        model.check()?;
        Ok(model)
    }
}

impl ThrustModel {
    /// Refuses constants no propeller has: a diameter or speeds that are not positive and
    /// finite, a static thrust below 0, coefficients that are not finite, an exponent outside
    /// (0, 4].
    fn check(&self) -> Result<(), String> {
        let positive = |key: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(format!("`{key}` = {v} must be > 0"))
            }
        };
        let finite = |key: &str, v: f64| {
            if v.is_finite() { Ok(()) } else { Err(format!("`{key}` = {v} is not finite")) }
        };
        match *self {
            Self::Propeller { diameter_m, ct0, ct_j } => {
                positive("diameter_m", diameter_m)?;
                finite("ct0", ct0)?;
                finite("ct_j", ct_j)
            }
            Self::Throttle { static_thrust_n, zero_thrust_speed_mps, exponent } => {
                positive("static_thrust_n", static_thrust_n)?;
                positive("zero_thrust_speed_mps", zero_thrust_speed_mps)?;
                if exponent > 0.0 && exponent <= 4.0 {
                    Ok(())
                } else {
                    Err(format!("`exponent` = {exponent} must lie in (0, 4]"))
                }
            }
        }
    }

    /// What the law reads besides ρ and V.
    pub fn input(&self) -> LawInput {
        match self {
            Self::Propeller { .. } => LawInput::PropSpeed,
            Self::Throttle { .. } => LawInput::Throttle,
        }
    }

    /// Thrust, N, at air density `rho_kgpm3`, true airspeed `vt_mps` and the law's input
    /// (`prop_speed_rad_s` for `propeller`, `throttle` 0 … 1 for `throttle`). A propeller at
    /// rest gives 0 (the `J` term vanishes with `n`: `ρ n D³ ct_j V`).
    pub fn thrust_n(&self, rho_kgpm3: f64, vt_mps: f64, input: f64) -> f64 {
        match *self {
            Self::Propeller { diameter_m: d, ct0, ct_j } => {
                let n = input / core::f64::consts::TAU;
                // ρ n² D⁴ (ct0 + ct_j V/(n D)) written without the division by n.
                rho_kgpm3 * d.powi(3) * n * (ct0 * n * d + ct_j * vt_mps)
            }
            Self::Throttle { static_thrust_n, zero_thrust_speed_mps, exponent } => {
                static_thrust_n
                    * input.max(0.0).powf(exponent)
                    * (1.0 - vt_mps / zero_thrust_speed_mps)
            }
        }
    }

    /// One line for a summary or a message: the law with its constants.
    pub fn describe(&self) -> String {
        match *self {
            Self::Propeller { diameter_m, ct0, ct_j } => format!(
                "thrust from the propeller law T = ρ n² D⁴ (ct0 + ct_j J), D = {diameter_m} m, ct0 = {ct0}, ct_j = {ct_j}"
            ),
            Self::Throttle { static_thrust_n, zero_thrust_speed_mps, exponent } => format!(
                "thrust from the throttle law T = {static_thrust_n} N · throttle^{exponent} · (1 − V/{zero_thrust_speed_mps} m/s)"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<ThrustModel, String> {
        toml::from_str::<ThrustModelFile>(text).map_err(|e| e.to_string())?.resolve()
    }

    /// The propeller law by hand: a 0.28 m propeller at 9000 rpm (150 rev/s) and 15 m/s,
    /// ρ 1.2: J = 15/(150·0.28) = 0.357143, cT = 0.1 − 0.12·J = 0.057143,
    /// T = 1.2·150²·0.28⁴·0.057143 = 9.4833 N.
    #[test]
    fn analytic_propeller_thrust_by_hand() {
        let m = parse("law = \"propeller\"\ndiameter_m = 0.28\nct0 = 0.1\nct_j = -0.12").unwrap();
        let omega = 9000.0 * core::f64::consts::TAU / 60.0;
        let by_hand = 1.2 * 150.0f64.powi(2) * 0.28f64.powi(4) * (0.1 - 0.12 * 15.0 / 42.0);
        assert!((m.thrust_n(1.2, 15.0, omega) - by_hand).abs() < 1e-12 * by_hand);
        assert!((by_hand - 9.4833).abs() < 1e-4, "{by_hand}");
        assert_eq!(m.thrust_n(1.2, 15.0, 0.0), 0.0, "a propeller at rest");
    }

    /// The throttle law by hand: 30 N static, zero at 40 m/s, exponent 1.5; at 64 % throttle
    /// and 10 m/s: 30 · 0.512 · 0.75 = 11.52 N.
    #[test]
    fn analytic_throttle_thrust_by_hand() {
        let text =
            "law = \"throttle\"\nstatic_thrust_n = 30\nzero_thrust_speed_mps = 40\nexponent = 1.5";
        let m = parse(text).unwrap();
        assert!((m.thrust_n(1.2, 10.0, 0.64) - 11.52).abs() < 1e-12);
        assert_eq!(m.thrust_n(1.2, 10.0, -0.1), 0.0, "a throttle below idle gives none");
    }

    #[test]
    fn errors_name_the_constant_at_fault() {
        let e = parse("law = \"propeller\"\nct0 = 0.1").unwrap_err();
        assert!(e.contains("needs `diameter_m`"), "{e}");
        let e = parse("law = \"propeller\"\ndiameter_m = -1\nct0 = 0.1").unwrap_err();
        assert!(e.contains("`diameter_m` = -1 must be > 0"), "{e}");
        let e =
            parse("law = \"throttle\"\nstatic_thrust_n = 1\nzero_thrust_speed_mps = 9\nct0 = 1")
                .unwrap_err();
        assert!(e.contains("`ct0` is not a constant of law `throttle`"), "{e}");
        let e = parse("law = \"jet\"").unwrap_err();
        assert!(e.contains("unknown law `jet`"), "{e}");
    }
}
