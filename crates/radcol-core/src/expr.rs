//! Functions of position given as text: `rho`, `E` and exact solutions such as
//! `0.5 + 0.2*x`, `1 + z^2`, `sin(pi*x)*exp(-y)`. Parsing and evaluation are
//! exmex's; this module maps our vocabulary onto it (`pi`, natural `log`) and
//! rejects variables other than x, y, z with a clear message.

use crate::error::InputError;
use exmex::prelude::*;
use glam::DVec3;

/// A parsed expression in x, y, z.
#[derive(Clone, Debug)]
pub struct Expr {
    text: String,
    flat: exmex::FlatEx<f64>,
    /// For each exmex variable (alphabetical), its coordinate index 0..3.
    coords: Vec<usize>,
}

impl Expr {
    /// Parses `text`: numbers, x y z, + - * / ^, parentheses, sin cos tan exp
    /// log (natural) sqrt abs, and the constant pi.
    pub fn parse(text: &str) -> Result<Self, InputError> {
        let translated = translate(text);
        let err = |message: String| InputError::Expression {
            expr: text.to_string(),
            message,
        };
        if text.trim().is_empty() {
            return Err(err("the expression is empty".into()));
        }
        let flat = exmex::parse::<f64>(&translated).map_err(|e| err(e.to_string()))?;
        let mut coords = Vec::new();
        for v in flat.var_names() {
            match v.as_str() {
                "x" => coords.push(0),
                "y" => coords.push(1),
                "z" => coords.push(2),
                other => {
                    return Err(err(format!(
                        "unknown name '{other}' (use x, y, z, pi and the functions sin cos tan exp log sqrt abs)"
                    )))
                }
            }
        }
        let e = Self {
            text: text.to_string(),
            flat,
            coords,
        };
        // One trial evaluation surfaces evaluation errors at parse time.
        e.try_eval(DVec3::new(0.3, 0.2, 0.1)).map_err(err)?;
        Ok(e)
    }

    /// The text as given.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Value at `p`; NaN if the expression cannot be evaluated there.
    pub fn eval(&self, p: DVec3) -> f64 {
        self.try_eval(p).unwrap_or(f64::NAN)
    }

    fn try_eval(&self, p: DVec3) -> Result<f64, String> {
        let xyz = [p.x, p.y, p.z];
        let mut vals = [0.0f64; 3];
        for (v, &c) in vals.iter_mut().zip(&self.coords) {
            *v = xyz[c];
        }
        self.flat
            .eval(&vals[..self.coords.len()])
            .map_err(|e| e.to_string())
    }
}

/// Renames whole identifiers (`pi` → `PI`, `log` → `ln`) and writes numbers in
/// scientific notation (`1e-3`) as plain decimals, which exmex expects.
fn translate(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 8);
    let mut i = 0;
    while i < chars.len() {
        let ch = chars[i];
        if ch.is_ascii_alphabetic() || ch == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let ident: String = chars[start..i].iter().collect();
            out.push_str(match ident.as_str() {
                "pi" => "PI",
                "log" => "ln",
                s => s,
            });
        } else if ch.is_ascii_digit() || ch == '.' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // An exponent: e or E, an optional sign, at least one digit.
            let mut j = i;
            if j < chars.len() && (chars[j] == 'e' || chars[j] == 'E') {
                j += 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    while j < chars.len() && chars[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            let literal: String = chars[start..i].iter().collect();
            match literal.parse::<f64>() {
                // Display of f64 is the shortest round-trip decimal, without exponent.
                Ok(v) if literal.contains(['e', 'E']) => out.push_str(&format!("{v}")),
                _ => out.push_str(&literal),
            }
        } else {
            out.push(ch);
            i += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluates_with_our_vocabulary() {
        let p = DVec3::new(0.5, -1.0, 2.0);
        let cases = [
            ("x*y+z", 1.5),
            ("2^3 - z", 6.0),
            ("sin(pi*x)", 1.0),
            ("log(exp(z))", 2.0),
            ("sqrt(abs(y)) + cos(0)", 2.0),
            ("1e-3*x", 5e-4),
            ("-x + 3", 2.5),
        ];
        for (text, want) in cases {
            let e = Expr::parse(text).unwrap();
            assert!(
                (e.eval(p) - want).abs() < 1e-14,
                "{text}: {} vs {want}",
                e.eval(p)
            );
        }
    }

    #[test]
    fn rejects_bad_expressions_with_a_reason() {
        for bad in ["x +", "w*2", "sin(", "", "foo(x)"] {
            let e = Expr::parse(bad).unwrap_err();
            assert!(e.to_string().contains("expression"), "{bad}: {e}");
        }
        assert!(Expr::parse("w*2").unwrap_err().to_string().contains("'w'"));
    }

    #[test]
    fn translation_touches_whole_identifiers_only() {
        assert_eq!(translate("pi*pix+log(x)+xlog"), "PI*pix+ln(x)+xlog");
        assert_eq!(translate("2.5e-3*x1+1E2"), "0.0025*x1+100");
    }
}
