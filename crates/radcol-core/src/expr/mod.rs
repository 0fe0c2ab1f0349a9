//! Functions of position given as text: `rho`, `E` and exact solutions such as
//! `0.5 + 0.2*x`, `1 + z^2`, `sin(pi*x)*exp(-y^2)`.
//!
//! Precedence is the one on paper: `-z^2` = −(z²), `^` is right-associative
//! (`2^3^2` = 2⁹), `*` `/` bind tighter than `+` `-`, and both pairs are
//! left-associative. `**` is accepted for `^`. The `parse` module says which.
//!
//! Written here rather than taken from a crate: of the expression crates
//! measured, exmex gives unary minus priority over `^` by design (`-z^2` =
//! z²), evalexpr groups `2^3^2` as 64 and divides integers (`2/3` = 0), and
//! meval, which is right, is unmaintained since 2017. A wrong precedence
//! changes ρ or E without a word, so the grammar is ours and tested.

mod parse;

use crate::error::InputError;
use glam::DVec3;

/// One step of the evaluator (reverse Polish order).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Num(f64),
    /// Coordinate 0, 1, 2 = x, y, z.
    Var(u8),
    Neg,
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Call(Func),
}

/// The functions an expression may call, each of one argument.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Func {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    /// Natural logarithm (also spelt `ln`).
    Log,
    Log10,
    Sqrt,
    Abs,
}

impl Func {
    const NAMES: &'static str =
        "sin cos tan asin acos atan sinh cosh tanh exp log (natural, also ln) log10 sqrt abs";

    fn named(name: &str) -> Option<Self> {
        Some(match name {
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            "tan" => Func::Tan,
            "asin" => Func::Asin,
            "acos" => Func::Acos,
            "atan" => Func::Atan,
            "sinh" => Func::Sinh,
            "cosh" => Func::Cosh,
            "tanh" => Func::Tanh,
            "exp" => Func::Exp,
            "log" | "ln" => Func::Log,
            "log10" => Func::Log10,
            "sqrt" => Func::Sqrt,
            "abs" => Func::Abs,
            _ => return None,
        })
    }

    fn apply(self, v: f64) -> f64 {
        match self {
            Func::Sin => v.sin(),
            Func::Cos => v.cos(),
            Func::Tan => v.tan(),
            Func::Asin => v.asin(),
            Func::Acos => v.acos(),
            Func::Atan => v.atan(),
            Func::Sinh => v.sinh(),
            Func::Cosh => v.cosh(),
            Func::Tanh => v.tanh(),
            Func::Exp => v.exp(),
            Func::Log => v.ln(),
            Func::Log10 => v.log10(),
            Func::Sqrt => v.sqrt(),
            Func::Abs => v.abs(),
        }
    }
}

/// Most operands the evaluator keeps at once; programs needing more are
/// refused when parsed. The parser's nesting limit keeps real formulas far below.
const MAX_STACK: usize = 256;

/// A parsed expression in x, y, z.
#[derive(Clone, Debug)]
pub struct Expr {
    text: String,
    program: Vec<Op>,
    /// Most operands on the evaluator's stack at once.
    depth: usize,
}

impl Expr {
    /// Parses `text`: numbers (`2`, `0.5`, `1e-3`), x y z, pi, `+ - * / ^`
    /// (or `**`), parentheses, and the functions sin cos tan asin acos atan
    /// sinh cosh tanh exp log (natural; also ln) log10 sqrt abs.
    pub fn parse(text: &str) -> Result<Self, InputError> {
        let program = parse::parse(text).map_err(|message| InputError::Expression {
            expr: text.to_string(),
            message,
        })?;
        let depth = stack_depth(&program);
        if depth > MAX_STACK {
            return Err(InputError::Expression {
                expr: text.to_string(),
                message: format!(
                    "more than {MAX_STACK} partial results are pending at once; split the formula"
                ),
            });
        }
        Ok(Self {
            text: text.to_string(),
            program,
            depth,
        })
    }

    /// The text as given.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Value at `p`: NaN or ±∞ where the formula has none (`log(x)` at x ≤ 0,
    /// `1/x` at 0); callers check values where they use them.
    pub fn eval(&self, p: DVec3) -> f64 {
        // A small stack for everyday formulas (no 2 KiB to clear per call).
        if self.depth <= SMALL_STACK {
            run::<SMALL_STACK>(&self.program, p)
        } else {
            run::<MAX_STACK>(&self.program, p)
        }
    }
}

/// Stack size of the evaluator's fast path.
const SMALL_STACK: usize = 16;

/// Runs `program` at `p` on a stack of `N` ≥ its depth.
fn run<const N: usize>(program: &[Op], p: DVec3) -> f64 {
    let xyz = [p.x, p.y, p.z];
    let mut stack = [0.0f64; N];
    let mut top = 0usize;
    for &op in program {
        match op {
            Op::Num(v) => {
                stack[top] = v;
                top += 1;
            }
            Op::Var(c) => {
                stack[top] = xyz[c as usize];
                top += 1;
            }
            Op::Neg => stack[top - 1] = -stack[top - 1],
            Op::Call(f) => stack[top - 1] = f.apply(stack[top - 1]),
            binary => {
                top -= 1;
                let (a, b) = (stack[top - 1], stack[top]);
                stack[top - 1] = match binary {
                    Op::Add => a + b,
                    Op::Sub => a - b,
                    Op::Mul => a * b,
                    Op::Div => a / b,
                    _ => a.powf(b),
                };
            }
        }
    }
    stack[0]
}

/// The largest number of operands on the evaluator's stack while running
/// `program`.
fn stack_depth(program: &[Op]) -> usize {
    let (mut top, mut most) = (0usize, 0usize);
    for op in program {
        match op {
            Op::Num(_) | Op::Var(_) => top += 1,
            Op::Neg | Op::Call(_) => {}
            _ => top -= 1,
        }
        most = most.max(top);
    }
    most
}

#[cfg(test)]
mod tests;
