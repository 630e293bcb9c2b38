//! Channel expressions of the mapping files: a channel computed from columns, for what a raw
//! log does not record directly (mass from fuel used, density from pressure altitude and
//! temperature, a sum or a unit conversion the `scale`/`offset` form cannot write).
//!
//! ```toml
//! mass = { expr = "17631 - fuel_used_kg", unit = "kg" }
//! rho  = { expr = "isa_pressure(h_qnh_ft * 0.3048) / (287.05287 * sat_K)", unit = "kg/m3" }
//! de   = { expr = "({elev.left} + {elev.right}) / 2", unit = "deg" }
//! ```
//!
//! Arithmetic `+ − * / ^`, parentheses, numbers (all `f64`: `1/2` is 0.5), the functions of
//! exmex's float operators (`sqrt`, `sin`, `cos`, `tan`, `exp`, `ln`, `log10`, `abs`, `atan`,
//! …; `PI`), and the standard-atmosphere functions of [`aeroident_physics::isa`]:
//!
//! | function | value |
//! |---|---|
//! | `isa_pressure(h_m)` | static pressure, Pa, at pressure altitude `h_m` (metres) |
//! | `isa_temperature(h_m)` | standard temperature, K, at `h_m` |
//! | `isa_density(h_m)` | standard-day density, kg/m³, at `h_m` (no temperature probe) |
//!
//! Outside the atmosphere model (−1 km to 20 km) they are NaN, and the row is rejected naming
//! the channel. Every other name is a column of the record; a column whose name is not a plain
//! identifier (letters, digits, `_`) is written in braces, `{ATT.Roll}`. The expression's
//! value is in the channel's `unit`; `scale` and `offset` apply after it as for a column.

use aeroident_physics::isa;
use exmex::prelude::*;
use exmex::{FloatOpsFactory, MakeOperators, Operator};

/// The operators of a channel expression: exmex's float operators and the standard atmosphere.
#[derive(Clone, Debug)]
pub struct ChannelOps;

impl MakeOperators<f64> for ChannelOps {
    fn make<'a>() -> Vec<Operator<'a, f64>> {
        let mut ops = FloatOpsFactory::<f64>::make();
        ops.push(Operator::make_unary("isa_pressure", isa_pressure));
        ops.push(Operator::make_unary("isa_temperature", isa_temperature));
        ops.push(Operator::make_unary("isa_density", isa_density));
        ops
    }
}

fn isa_pressure(h_m: f64) -> f64 {
    isa::pressure_pa(h_m).unwrap_or(f64::NAN)
}

fn isa_temperature(h_m: f64) -> f64 {
    isa::temperature_k(h_m).unwrap_or(f64::NAN)
}

fn isa_density(h_m: f64) -> f64 {
    isa_pressure(h_m) / (isa::R_AIR_J_PER_KG_K * isa_temperature(h_m))
}

/// A parsed channel expression: its text and the columns it reads.
#[derive(Debug, Clone)]
pub struct Expression {
    text: String,
    flat: FlatEx<f64, ChannelOps>,
    columns: Vec<String>,
}

impl PartialEq for Expression {
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

impl Expression {
    /// Parses `text` (module doc).
    ///
    /// # Errors
    /// The parser's message, for text that is not an expression of this grammar.
    pub fn parse(text: &str) -> Result<Self, String> {
        let flat = FlatEx::<f64, ChannelOps>::parse(text).map_err(|e| e.to_string())?;
        let columns = flat.var_names().iter().map(|n| unbraced(n).to_string()).collect();
        Ok(Self { text: text.to_string(), flat, columns })
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The column names it reads, braces removed, in the order [`Expression::eval`] takes
    /// their values.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The value for the column values `values` (order of [`Expression::columns`]); NaN when
    /// it cannot be evaluated (wrong count, a function outside its domain).
    pub fn eval(&self, values: &[f64]) -> f64 {
        self.flat.eval(values).unwrap_or(f64::NAN)
    }
}

fn unbraced(name: &str) -> &str {
    name.strip_prefix('{').and_then(|n| n.strip_suffix('}')).unwrap_or(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values against hand arithmetic and the standard atmosphere's published sea-level and
    /// 5 km values; columns in evaluation order, braces removed; float division.
    #[test]
    fn evaluates_arithmetic_columns_and_the_standard_atmosphere() {
        let e = Expression::parse("({elev.left} + elev_right) / 2 + 1/2").unwrap();
        assert_eq!(e.columns(), ["elev.left", "elev_right"]);
        assert_eq!(e.eval(&[3.0, 5.0]), 4.5);
        let rho = Expression::parse("isa_pressure(h_ft * 0.3048) / (287.05287 * t_K)").unwrap();
        assert!((rho.eval(&[0.0, 288.15]) - 1.2250).abs() < 1e-4);
        let std = Expression::parse("isa_density(h)").unwrap();
        assert!((std.eval(&[5000.0]) - 0.736_12).abs() < 2e-4);
        assert!(std.eval(&[30_000.0]).is_nan());
        assert!(Expression::parse("a b").is_err());
        assert!(Expression::parse("(a + b").is_err());
    }
}
