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
//! Arithmetic `+ − * / ^`, parentheses, numbers (all `f64`: `1/2` is 0.5; exponents as
//! `1e-3`, `1.5E2`), the functions of
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
use exmex::{FloatOpsFactory, MakeOperators, MatchLiteral, Operator};

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

// Numbers as a mapping writes them: exmex's own form (`12`, `1.5`, `.5`) with an optional
// exponent (`1e-3`, `1.5E2`), which its default matcher would split into a number and a column
// `e` and then refuse with an internal message about its operator and node counts.
exmex::literal_matcher_from_pattern!(ChannelNumber, r"^(\.?[0-9]+(\.[0-9]+)?([eE][+-]?[0-9]+)?)");

/// A parsed channel expression: its text and the columns it reads.
#[derive(Debug, Clone)]
pub struct Expression {
    text: String,
    flat: FlatEx<f64, ChannelOps, ChannelNumber>,
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
    /// A name called as a function that is none, naming it and the functions there are; the
    /// parser's message, for other text that is not an expression of this grammar.
    pub fn parse(text: &str) -> Result<Self, String> {
        check_functions(text)?;
        let flat = FlatEx::<f64, ChannelOps, ChannelNumber>::parse(text).map_err(|e| {
            format!("not an expression of the mapping grammar (docs/mapping.md): {e}")
        })?;
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

/// Refuses a name followed by `(` that is not a function of [`ChannelOps`]: exmex would read it
/// as a column and answer about a parenthesis instead of the unknown function.
fn check_functions(text: &str) -> Result<(), String> {
    let chars: Vec<char> = text.chars().collect();
    let mut k = 0;
    while k < chars.len() {
        if chars[k] == '{' {
            // A braced column name: anything up to its closing brace.
            k = chars[k..].iter().position(|c| *c == '}').map_or(chars.len(), |p| k + p + 1);
            continue;
        }
        let starts = chars[k].is_ascii_alphabetic() || chars[k] == '_';
        let after_number = k > 0 && (chars[k - 1].is_ascii_digit() || chars[k - 1] == '.');
        if !starts || after_number {
            k += 1;
            continue;
        }
        let end = (k..chars.len())
            .find(|&j| !(chars[j].is_ascii_alphanumeric() || chars[j] == '_'))
            .unwrap_or(chars.len());
        let name: String = chars[k..end].iter().collect();
        let next = chars[end..].iter().find(|c| !c.is_whitespace());
        if next == Some(&'(') && !functions().contains(&name) {
            return Err(format!(
                "`{name}(…)` calls no function of a channel expression: they are {}",
                functions().join(", ")
            ));
        }
        k = end;
    }
    Ok(())
}

/// The names of the unary functions a channel expression can call.
fn functions() -> Vec<String> {
    let mut names: Vec<String> = ChannelOps::make()
        .iter()
        .filter(|o| {
            o.has_unary() && o.repr().chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        })
        .map(|o| o.repr().to_string())
        .collect();
    names.sort();
    names.dedup();
    names
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

    /// Numbers with an exponent are numbers (against the same numbers written out), not a
    /// number and a column `e`; a column whose name starts with `e` still is one.
    #[test]
    fn exponent_notation_is_a_number() {
        for (text, value) in [
            ("x * 1e-3", 2.0e-3),
            ("1.5E2 + x", 152.0),
            ("x / 2.5e+1", 0.08),
            (".5e1 * x", 10.0),
            ("2E0 ^ x", 4.0),
        ] {
            let e = Expression::parse(text).unwrap_or_else(|m| panic!("{text}: {m}"));
            assert_eq!(e.columns(), ["x"], "{text}");
            assert!((e.eval(&[2.0]) - value).abs() < 1e-12, "{text}: {}", e.eval(&[2.0]));
        }
        let e = Expression::parse("e1 + exp_x").unwrap();
        assert_eq!(e.columns(), ["e1", "exp_x"]);
    }

    /// A call of a function that does not exist names it and the functions there are (a
    /// known function, a braced column followed by a parenthesised factor, and a column
    /// times a parenthesis are not calls of an unknown function).
    #[test]
    fn unknown_function_is_named() {
        let e = Expression::parse("isa_presure(h) / 2").unwrap_err();
        assert!(e.starts_with("`isa_presure(…)` calls no function"), "{e}");
        assert!(e.contains("isa_pressure") && e.contains("sqrt"), "{e}");
        let e = Expression::parse("3 * foo (x)").unwrap_err();
        assert!(e.contains("`foo(…)`"), "{e}");
        assert!(Expression::parse("sqrt(x) + isa_density(h)").is_ok());
        assert!(Expression::parse("{a(b)} * (x + 1)").is_ok());
    }
}
