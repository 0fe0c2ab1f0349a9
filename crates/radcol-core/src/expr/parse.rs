//! Text to a program for the evaluator: a tokenizer and a recursive-descent
//! parser with the usual mathematical precedence.
//!
//! From loosest to tightest: `+ -` (left), `* /` (left), unary `- +`, `^`
//! (right). The exponent of `^` may itself carry a sign, so `-z^2` = −(z²),
//! `2^3^2` = 2⁹, `2^-1` = 0.5 and `-2^-2` = −0.25, as on paper.
//!
//! Errors say what was expected where, by column, in words rather than in
//! terms of the parser's state.

use super::{Func, Op};

/// Deepest nesting of signs, powers and parentheses: far above any formula a
/// person writes, low enough to bound the parser's recursion.
pub(super) const MAX_DEPTH: usize = 64;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Tok<'a> {
    Num(f64),
    Name(&'a str),
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    Open,
    Close,
}

/// A token and the column (1-based, in characters) where it starts.
type Spanned<'a> = (Tok<'a>, usize);

fn describe(t: Tok) -> String {
    match t {
        Tok::Num(v) => format!("the number {v}"),
        Tok::Name(n) => format!("'{n}'"),
        Tok::Plus => "'+'".into(),
        Tok::Minus => "'-'".into(),
        Tok::Star => "'*'".into(),
        Tok::Slash => "'/'".into(),
        Tok::Caret => "'^'".into(),
        Tok::Open => "'('".into(),
        Tok::Close => "')'".into(),
    }
}

fn tokenize(text: &str) -> Result<Vec<Spanned<'_>>, String> {
    let mut out = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    let column = |byte: usize| text[..byte].chars().count() + 1;
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        let tok = match c {
            b' ' | b'\t' | b'\n' | b'\r' => {
                i += 1;
                continue;
            }
            b'0'..=b'9' | b'.' => {
                while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
                    i += 1;
                }
                // An exponent: e or E, an optional sign, at least one digit.
                if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
                    let mut j = i + 1;
                    if j < bytes.len() && (bytes[j] == b'+' || bytes[j] == b'-') {
                        j += 1;
                    }
                    if j < bytes.len() && bytes[j].is_ascii_digit() {
                        while j < bytes.len() && bytes[j].is_ascii_digit() {
                            j += 1;
                        }
                        i = j;
                    }
                }
                let literal = &text[start..i];
                match literal.parse::<f64>() {
                    Ok(v) if v.is_finite() => Tok::Num(v),
                    Ok(_) => {
                        return Err(format!(
                            "the number {literal} at column {} is too large for double precision",
                            column(start)
                        ))
                    }
                    Err(_) => {
                        return Err(format!(
                            "'{literal}' at column {} is not a number",
                            column(start)
                        ))
                    }
                }
            }
            b'a'..=b'z' | b'A'..=b'Z' | b'_' => {
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                Tok::Name(&text[start..i])
            }
            b'*' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                out.push((Tok::Caret, column(start)));
                continue;
            }
            b'+' => Tok::Plus,
            b'-' => Tok::Minus,
            b'*' => Tok::Star,
            b'/' => Tok::Slash,
            b'^' => Tok::Caret,
            b'(' => Tok::Open,
            b')' => Tok::Close,
            _ => {
                let ch = text[start..].chars().next().unwrap_or('?');
                return Err(format!(
                    "'{ch}' at column {} is not part of an expression (use numbers, x, y, z, pi, + - * / ^, parentheses and functions)",
                    column(start)
                ));
            }
        };
        if !matches!(tok, Tok::Num(_) | Tok::Name(_)) {
            i += 1;
        }
        out.push((tok, column(start)));
    }
    Ok(out)
}

struct Parser<'a> {
    toks: Vec<Spanned<'a>>,
    at: usize,
    depth: usize,
    /// Length of the source in characters, for "ends after" messages.
    end_column: usize,
    program: Vec<Op>,
}

/// Parses `text` into a program in reverse Polish order.
pub(super) fn parse(text: &str) -> Result<Vec<Op>, String> {
    let toks = tokenize(text)?;
    if toks.is_empty() {
        return Err("the expression is empty".into());
    }
    let mut p = Parser {
        toks,
        at: 0,
        depth: 0,
        end_column: text.chars().count() + 1,
        program: Vec::new(),
    };
    p.sum()?;
    if let Some(&(t, col)) = p.toks.get(p.at) {
        return Err(match t {
            Tok::Close => format!("')' at column {col} has no matching '('"),
            _ => p.missing_operator(t, col),
        });
    }
    Ok(p.program)
}

impl<'a> Parser<'a> {
    fn peek(&self) -> Option<Tok<'a>> {
        self.toks.get(self.at).map(|&(t, _)| t)
    }

    fn column(&self) -> usize {
        self.toks.get(self.at).map_or(self.end_column, |&(_, c)| c)
    }

    fn enter(&mut self) -> Result<(), String> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(format!(
                "the expression is nested more than {MAX_DEPTH} levels deep at column {}",
                self.column()
            ));
        }
        Ok(())
    }

    fn missing_operator(&self, t: Tok, col: usize) -> String {
        let before = describe(self.toks[self.at - 1].0);
        format!(
            "an operator is missing between {before} and {} at column {col} (write 2*x, not 2x or 2 x)",
            describe(t)
        )
    }

    /// sum := product (('+' | '-') product)*
    fn sum(&mut self) -> Result<(), String> {
        self.product()?;
        while let Some(op @ (Tok::Plus | Tok::Minus)) = self.peek() {
            self.at += 1;
            self.product()?;
            self.program
                .push(if op == Tok::Plus { Op::Add } else { Op::Sub });
        }
        Ok(())
    }

    /// product := unary (('*' | '/') unary)*
    fn product(&mut self) -> Result<(), String> {
        self.unary()?;
        while let Some(op @ (Tok::Star | Tok::Slash)) = self.peek() {
            self.at += 1;
            self.unary()?;
            self.program
                .push(if op == Tok::Star { Op::Mul } else { Op::Div });
        }
        Ok(())
    }

    /// unary := ('-' | '+') unary | power
    fn unary(&mut self) -> Result<(), String> {
        self.enter()?;
        match self.peek() {
            Some(Tok::Minus) => {
                self.at += 1;
                self.unary()?;
                self.program.push(Op::Neg);
            }
            Some(Tok::Plus) => {
                self.at += 1;
                self.unary()?;
            }
            _ => self.power()?,
        }
        self.depth -= 1;
        Ok(())
    }

    /// power := atom ('^' unary)?  — right-associative through `unary`.
    fn power(&mut self) -> Result<(), String> {
        self.atom()?;
        if self.peek() == Some(Tok::Caret) {
            self.at += 1;
            self.unary()?;
            self.program.push(Op::Pow);
        }
        Ok(())
    }

    /// atom := number | x | y | z | pi | function '(' sum ')' | '(' sum ')'
    fn atom(&mut self) -> Result<(), String> {
        let col = self.column();
        let Some(t) = self.peek() else {
            let last = describe(self.toks[self.at - 1].0);
            return Err(format!(
                "the expression ends after {last}: a number, x, y, z, a function or '(' must follow"
            ));
        };
        self.at += 1;
        match t {
            Tok::Num(v) => self.program.push(Op::Num(v)),
            Tok::Open => self.group(col)?,
            Tok::Name(name) => self.name(name, col)?,
            other => {
                return Err(format!(
                    "{} at column {col} cannot start an operand: a number, x, y, z, a function or '(' is expected",
                    describe(other)
                ))
            }
        }
        Ok(())
    }

    /// The rest of a parenthesised sum whose '(' was at `open`.
    fn group(&mut self, open: usize) -> Result<(), String> {
        self.sum()?;
        match self.peek() {
            Some(Tok::Close) => {
                self.at += 1;
                Ok(())
            }
            None => Err(format!("the '(' at column {open} is never closed")),
            Some(t) => Err(self.missing_operator(t, self.column())),
        }
    }

    fn name(&mut self, name: &str, col: usize) -> Result<(), String> {
        let var = match name {
            "x" => Some(Op::Var(0)),
            "y" => Some(Op::Var(1)),
            "z" => Some(Op::Var(2)),
            "pi" => Some(Op::Num(std::f64::consts::PI)),
            _ => None,
        };
        if let Some(op) = var {
            self.program.push(op);
            return Ok(());
        }
        let Some(func) = Func::named(name) else {
            return Err(format!(
                "unknown name '{name}' at column {col} (use x, y, z, pi and the functions {})",
                Func::NAMES
            ));
        };
        if self.peek() != Some(Tok::Open) {
            return Err(format!(
                "the function '{name}' at column {col} needs its argument in parentheses: {name}(...)"
            ));
        }
        let open = self.column();
        self.at += 1;
        self.group(open)?;
        self.program.push(Op::Call(func));
        Ok(())
    }
}
