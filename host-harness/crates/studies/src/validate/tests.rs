//! The document's unit tests.

use super::rows::*;


/// Every "-" followed by nothing but zeros and a point: a negative zero as people read it.
fn has_negative_zero(s: &str) -> bool {
    s.match_indices('-').any(|(i, _)| {
        let num: String = s[i + 1..].chars().take_while(|c| c.is_ascii_digit() || *c == '.').collect();
        num.starts_with('0') && num.chars().all(|c| c == '0' || c == '.')
    })
}

#[test]
fn no_negative_zero_in_signed_figures() {
    // Table 4's first hit starts at the contact instant, found 1e-17 s before it by the solver:
    // the timeline's legend said "hit 1 (-0.0 ms to +11.2 ms)".
    let tc = 0.224_837_819_134_552_5;
    assert_eq!(ms_after(tc - 1e-17, tc), "+0.0 ms");
    assert_eq!(ms_after(tc - 4e-5, tc), "+0.0 ms");
    assert_eq!(ms_after(tc - 6e-5, tc), "-0.1 ms");
    assert_eq!(ms_after(tc + 0.0112, tc), "+11.2 ms");
    assert_eq!(signed(-0.0, 1), "+0.0");
    assert_eq!(signed(-0.0004, 3), "+0.000");
    assert_eq!(signed(-0.0006, 3), "-0.001");
    assert_eq!(signed(-12.0, 0), "-12");
    assert_eq!(signed(f64::NAN, 1), "NaN");
    // The difference column: Fig. 3's V_p rows printed "-0.000 (+0.0 %".
    let r = num_row("v", 0.4, 0.4 - 1e-12, "m/s", 0.01);
    assert_eq!(r.diff, "+0.000 (+0.0 %, tolerance 1 %)");
    assert!(!has_negative_zero(&r.diff), "{}", r.diff);
    assert!(has_negative_zero("hit 1 (-0.0 ms") && !has_negative_zero("-0.1 ms, 10-0.5"));
}
