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
    /// A name called as a function that is none, naming it and the functions there are; for
    /// other text that is not an expression of this grammar, what is wrong and where, in the
    /// grammar's terms (the number that is not one, the operator without a value, the
    /// parenthesis not closed, with its character).
    pub fn parse(text: &str) -> Result<Self, String> {
        check_functions(text)?;
        let flat = FlatEx::<f64, ChannelOps, ChannelNumber>::parse(text)
            .map_err(|_| cause_of_failure(text))?;
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
/// as a column and answer about a parenthesis instead of the unknown function. Refuses a `{`
/// that is not closed.
fn check_functions(text: &str) -> Result<(), String> {
    let chars: Vec<char> = text.chars().collect();
    let mut k = 0;
    while k < chars.len() {
        if chars[k] == '{' {
            // A braced column name: anything up to its closing brace. Without one, exmex would
            // take the rest of the text for a column name (`{x + 1` reading a column `x + 1`).
            let Some(p) = chars[k..].iter().position(|c| *c == '}') else {
                return Err(format!("the `{{` at character {} has no closing `}}`", k + 1));
            };
            k += p + 1;
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

/// What a token of a channel expression is, for [`cause_of_failure`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// A number, a column or a named constant (`PI`).
    Value,
    /// A function of one argument (`sqrt`).
    Function,
    /// `*`, `/`, `^` or a named binary operator (`min`).
    Binary,
    /// `+` or `-`: binary after a value, a sign before one.
    Sign,
    /// `(`
    Open,
    /// `)`
    Close,
}

/// One token: its kind, its text and the 1-based character it starts at.
struct Token {
    kind: Kind,
    text: String,
    at: usize,
}

/// Why `text` is not a channel expression, in the mapping's terms: what is wrong and at which
/// character. Called when the parser refused `text`: its own messages speak of its internals
/// ("we have 1 ops and 3 node"), which tell a user nothing about `2e * x`.
fn cause_of_failure(text: &str) -> String {
    match tokens(text).and_then(|t| check_order(&t)) {
        Err(cause) => cause,
        // Every token in its place, yet the parser refused: say so without its internals.
        Ok(()) => format!(
            "cannot parse `{text}` as an expression of the mapping grammar (docs/mapping.md): \
             arithmetic `+ - * / ^`, parentheses, numbers, columns and functions"
        ),
    }
}

/// The end of the number starting at `chars[k]` (the form of [`ChannelNumber`]), or why the
/// word there is not one (`2e`, `3.`, `2x`).
fn number_end(chars: &[char], k: usize) -> Result<usize, String> {
    let word = |from: usize, to: usize| chars[from..to].iter().collect::<String>();
    let digits = |mut j: usize| {
        while j < chars.len() && chars[j].is_ascii_digit() {
            j += 1;
        }
        j
    };
    let mut j = digits(k);
    if j < chars.len() && chars[j] == '.' {
        let after = digits(j + 1);
        if after == j + 1 {
            return Err(format!(
                "`{}` is not a number: a decimal point needs digits after it, as in `{}0`",
                word(k, j + 1),
                word(k, j + 1)
            ));
        }
        j = after;
    }
    if j < chars.len() && matches!(chars[j], 'e' | 'E') {
        let mut m = j + 1;
        if m < chars.len() && matches!(chars[m], '+' | '-') {
            m += 1;
        }
        let end = digits(m);
        if end == m {
            return Err(format!(
                "`{}` is not a number: exponent notation needs digits after `{}`, as in `2e-3`",
                word(k, m),
                chars[j]
            ));
        }
        j = end;
    }
    let word_char = |c: char| c.is_alphanumeric() || c == '_' || c == '.';
    if j < chars.len() && word_char(chars[j]) {
        let end = (j..chars.len()).find(|&e| !word_char(chars[e])).unwrap_or(chars.len());
        let w = word(k, end);
        if w.matches('.').count() > 1 {
            return Err(format!("`{w}` is not a number: it has more than one decimal point"));
        }
        return Err(format!(
            "`{w}` is not a number, nor a column name (a column name starts with a letter or `_`; \
             a product needs `*`, as in `2 * x`)"
        ));
    }
    Ok(j)
}

/// The tokens of `text`, or why a character or word there is no token of the grammar.
fn tokens(text: &str) -> Result<Vec<Token>, String> {
    let ops = ChannelOps::make();
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < chars.len() {
        let c = chars[k];
        let (kind, end) = match c {
            _ if c.is_whitespace() => {
                k += 1;
                continue;
            }
            '{' => match chars[k..].iter().position(|c| *c == '}') {
                Some(p) => (Kind::Value, k + p + 1),
                None => return Err(format!("the `{{` at character {} has no closing `}}`", k + 1)),
            },
            '0'..='9' => (Kind::Value, number_end(&chars, k)?),
            '.' if chars.get(k + 1).is_some_and(char::is_ascii_digit) => {
                (Kind::Value, number_end(&chars, k)?)
            }
            '+' | '-' => (Kind::Sign, k + 1),
            '*' | '/' | '^' => (Kind::Binary, k + 1),
            '(' => (Kind::Open, k + 1),
            ')' => (Kind::Close, k + 1),
            _ if c.is_alphabetic() || c == '_' => {
                let end = (k..chars.len())
                    .find(|&e| !(chars[e].is_alphanumeric() || chars[e] == '_'))
                    .unwrap_or(chars.len());
                let name: String = chars[k..end].iter().collect();
                let kind = match ops.iter().find(|o| o.repr() == name) {
                    Some(o) if o.constant().is_some() => Kind::Value,
                    Some(o) if o.has_bin() => Kind::Binary,
                    Some(_) => Kind::Function,
                    None => Kind::Value,
                };
                (kind, end)
            }
            _ => {
                return Err(format!(
                    "`{c}` (character {}) is not part of an expression: arithmetic `+ - * / ^`, \
                     parentheses, numbers, columns (`{{…}}` for a name with other characters) \
                     and functions",
                    k + 1
                ));
            }
        };
        out.push(Token { kind, text: chars[k..end].iter().collect(), at: k + 1 });
        k = end;
    }
    Ok(out)
}

/// Checks that values and operators alternate and parentheses pair up, naming the first token
/// out of place.
fn check_order(tokens: &[Token]) -> Result<(), String> {
    let mut want_value = true;
    let mut open: Vec<usize> = Vec::new();
    let mut prev: Option<&Token> = None;
    for t in tokens {
        match t.kind {
            Kind::Value | Kind::Function | Kind::Open if !want_value => {
                let before = prev.map_or("", |p| p.text.as_str());
                return Err(format!(
                    "no operator between `{before}` and `{}` (character {}): a product needs \
                     `*`, as in `2 * x`",
                    t.text, t.at
                ));
            }
            Kind::Value | Kind::Close => want_value = false,
            Kind::Function | Kind::Sign => want_value = true,
            Kind::Open => open.push(t.at),
            Kind::Binary if want_value => {
                return Err(format!("`{}` at character {} has no value on its left", t.text, t.at));
            }
            Kind::Binary => want_value = true,
        }
        if t.kind == Kind::Close {
            if prev.is_some_and(|p| p.kind == Kind::Open) {
                return Err(format!("the `()` at character {} holds no value", t.at - 1));
            }
            if let Some(p) = prev.filter(|p| p.kind != Kind::Value && p.kind != Kind::Close) {
                return Err(format!(
                    "the `)` at character {} follows `{}`: a value is missing",
                    t.at, p.text
                ));
            }
            if open.pop().is_none() {
                return Err(format!("the `)` at character {} closes no `(`", t.at));
            }
        }
        prev = Some(t);
    }
    match (prev, open.last()) {
        (None, _) => Err("the expression is empty".into()),
        (Some(p), _) if want_value => {
            Err(format!("the expression ends with `{}`: a value is missing after it", p.text))
        }
        (_, Some(at)) => Err(format!("the `(` at character {at} is not closed")),
        _ => Ok(()),
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

    /// Text the parser refuses is explained token by token: a constant and a function are
    /// told from a column, an empty pair of parentheses and a missing argument are named, and
    /// nothing of the parser's own wording remains.
    #[test]
    fn refused_text_is_explained_in_the_grammar_s_terms() {
        for (text, cause) in [
            ("2 PI", "no operator between `2` and `PI` (character 3)"),
            ("x * sqrt", "the expression ends with `sqrt`: a value is missing after it"),
            ("sqrt() + x", "the `()` at character 5 holds no value"),
            ("(x +) * 2", "the `)` at character 5 follows `+`: a value is missing"),
            ("   ", "the expression is empty"),
            ("x min", "the expression ends with `min`"),
            (".5.5 * x", "`.5.5` is not a number: it has more than one decimal point"),
        ] {
            let e = Expression::parse(text).unwrap_err();
            assert!(e.contains(cause), "{text}: {e}");
        }
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
