use super::*;

/// Value of `text` at (x, y, z) = (0.5, −1, 2).
fn at_p(text: &str) -> f64 {
    Expr::parse(text)
        .unwrap_or_else(|e| panic!("{text}: {e}"))
        .eval(DVec3::new(0.5, -1.0, 2.0))
}

#[test]
fn precedence_and_associativity_as_on_paper() {
    // Every value below is worked by hand with x = 0.5, y = −1, z = 2.
    let cases: &[(&str, f64)] = &[
        ("-2^2", -4.0),
        ("(-2)^2", 4.0),
        ("2^3^2", 512.0),
        ("(2^3)^2", 64.0),
        ("2^-1", 0.5),
        ("-2^-2", -0.25),
        ("2^-1^2", 0.5), // 2^(−(1²))
        ("-z^2", -4.0),  // −(z²)
        ("exp(-z^2)", (-4.0f64).exp()),
        ("1 - z^2", -3.0),
        ("z^2 - 1", 3.0),
        ("--z", 2.0),
        ("-+-z", 2.0),
        ("2*-z", -4.0),
        ("z^-z", 0.25),
        ("-x*z", -1.0),
        ("-(x*z)", -1.0),
        ("8/4/2", 1.0),     // (8/4)/2
        ("8-4-2", 2.0),     // (8−4)−2
        ("2/3", 2.0 / 3.0), // no integer division
        ("2*3^2", 18.0),
        ("2^3*2", 16.0),
        ("-y^2", -1.0), // −((−1)²)
        ("y^3", -1.0),  // negative base, integer power
        ("(-8)^(1/3)", f64::NAN),
        ("z**3", 8.0),
        ("2**-1", 0.5),
        ("1e-3*z", 2e-3),
        ("1E+2 + .5", 100.5),
        ("3.", 3.0),
        ("pi/2 - asin(1)", 0.0),
        ("log(exp(z))", 2.0),
        ("ln(z) - log(z)", 0.0),
        ("log10(1000)", 3.0),
        ("sqrt(abs(y)) + cos(0)", 2.0),
        ("sin(pi*x)", 1.0),
        (
            "tanh(0) + sinh(0) + cosh(0) + atan(0) + acos(1) + tan(0)",
            1.0,
        ),
        ("x*y+z", 1.5),
        ("  x  *  ( y + z )  ", 0.5),
    ];
    for &(text, want) in cases {
        let got = at_p(text);
        let ok = if want.is_nan() {
            got.is_nan()
        } else {
            (got - want).abs() <= 1e-15 * want.abs().max(1.0)
        };
        assert!(ok, "{text}: {got} vs {want}");
    }
}

#[test]
fn parse_errors_say_what_and_where_in_words() {
    let cases: &[(&str, &str)] = &[
        ("", "empty"),
        ("   ", "empty"),
        ("x +", "ends after '+'"),
        ("sin(", "ends after '('"),
        ("(x + 1", "'(' at column 1 is never closed"),
        ("x + 1)", "')' at column 6 has no matching '('"),
        ("2x", "operator is missing between the number 2 and 'x'"),
        ("2 x", "operator is missing"),
        ("(x)(y)", "operator is missing"),
        ("w*2", "unknown name 'w' at column 1"),
        ("x1", "unknown name 'x1'"),
        ("foo(x)", "unknown name 'foo'"),
        (
            "sin x",
            "'sin' at column 1 needs its argument in parentheses",
        ),
        ("x % 2", "'%' at column 3 is not part of an expression"),
        ("x * * y", "'*' at column 5 cannot start an operand"),
        ("1..2", "'1..2' at column 1 is not a number"),
        ("1e999", "too large"),
        ("x ^", "ends after '^'"),
        ("é", "'é' at column 1"),
    ];
    for &(text, want) in cases {
        let e = Expr::parse(text).unwrap_err().to_string();
        assert!(e.contains(want), "{text:?}: {e}");
        assert!(e.starts_with("expression '"), "{text:?}: {e}");
    }
}

#[test]
fn nesting_is_bounded_not_a_stack_overflow() {
    let deep = format!("{}x{}", "(".repeat(100_000), ")".repeat(100_000));
    let e = Expr::parse(&deep).unwrap_err().to_string();
    assert!(e.contains("nested more than 64"), "{e}");
    let signs = format!("{}x", "-".repeat(100_000));
    assert!(Expr::parse(&signs).is_err());
    // Long but flat formulas are fine: a sum of 10 000 terms.
    let long = vec!["x"; 10_000].join("+");
    assert_eq!(Expr::parse(&long).unwrap().eval(DVec3::X), 10_000.0);
    // The shape that keeps the most operands pending per nesting level (a
    // sum's left side, a product's, a power's base): at the deepest nesting
    // accepted it stays within the evaluator's fixed stack.
    let nest = |n: usize| format!("{}1{}", "1+2*3^(".repeat(n), ")".repeat(n));
    let deepest = (1..100)
        .take_while(|&n| Expr::parse(&nest(n)).is_ok())
        .last()
        .unwrap();
    let e = Expr::parse(&nest(deepest)).unwrap();
    assert!(stack_depth(&e.program) >= 3 * deepest && stack_depth(&e.program) <= MAX_STACK);
    assert!(e.eval(DVec3::ZERO).is_infinite());
}

#[test]
fn evaluation_stack_depth_matches_the_program() {
    let e = Expr::parse("1+2*(3+4*(5+6))").unwrap();
    assert_eq!(stack_depth(&e.program), 6);
    assert_eq!(e.eval(DVec3::ZERO), 1.0 + 2.0 * (3.0 + 4.0 * 11.0));
}

#[test]
fn both_evaluator_stacks_give_the_same_values() {
    // 20 pending operands: past the small stack, so the large one runs.
    let text = format!("{}x{}", "1+2*(".repeat(10), ")".repeat(10));
    let e = Expr::parse(&text).unwrap();
    assert!(e.depth > SMALL_STACK);
    let p = DVec3::new(0.25, 0.0, 0.0);
    // 2^10 - 1 plus 2^10 x: each level doubles and adds one.
    assert_eq!(e.eval(p), 1023.0 + 1024.0 * 0.25);
    let small = Expr::parse("1+2*(1+2*x)").unwrap();
    assert!(small.depth <= SMALL_STACK);
    assert_eq!(small.eval(p), 4.0);
    assert_eq!(run::<MAX_STACK>(&small.program, p), 4.0);
}
