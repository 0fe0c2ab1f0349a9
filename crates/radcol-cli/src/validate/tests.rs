//! Parsing of levels and α.

use super::*;

#[test]
fn levels_accept_both_range_forms() {
    assert_eq!(parse_levels("0..3").unwrap(), 0..=3);
    assert_eq!(parse_levels(" 1..=2 ").unwrap(), 1..=2);
    assert_eq!(parse_levels("2..2").unwrap(), 2..=2);
}

#[test]
fn levels_reject_bad_ranges() {
    assert!(parse_levels("3..1").unwrap_err().0.contains("greater"));
    assert!(parse_levels("a..2")
        .unwrap_err()
        .0
        .contains("'a' is not a level"));
    assert!(parse_levels("2").unwrap_err().0.contains("expected A..B"));
    assert!(parse_levels("-1..2").is_err());
}

#[test]
fn alpha_is_auto_or_inside_the_open_interval() {
    assert_eq!(parse_alpha("auto").unwrap(), AlphaSpec::Auto);
    assert_eq!(parse_alpha("0.1").unwrap(), AlphaSpec::Value(0.1));
    assert!(parse_alpha("0.4").is_err());
    assert!(parse_alpha("0").is_err());
    assert!(parse_alpha("nan").is_err());
    assert!(parse_alpha("x").is_err());
}
