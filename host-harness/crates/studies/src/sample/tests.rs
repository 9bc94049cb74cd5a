//! The plan's, the draws' and the tally's unit tests.

use super::{keys::*, plan::*, dist::*, report::*};


#[test]
fn uniform_numbers_are_in_the_open_interval_and_differ() {
    let a: Vec<f64> = (0..1000).map(|i| uniform01(1, i, 0)).collect();
    assert!(a.iter().all(|&u| u > 0.0 && u < 1.0));
    let mean = a.iter().sum::<f64>() / a.len() as f64;
    assert!((mean - 0.5).abs() < 0.03, "{mean}");
    assert_ne!(uniform01(1, 5, 0), uniform01(1, 5, 1));
    assert_ne!(uniform01(1, 5, 0), uniform01(2, 5, 0));
}

#[test]
fn quantiles_invert_cdfs() {
    for d in [Dist::Normal { mean: 2.0, sd: 0.5 }, Dist::LogNormal { mu: -1.0, sigma: 0.3 }, Dist::Uniform { lo: 1.0, hi: 3.0 }, Dist::Triangular { lo: 0.0, mode: 1.0, hi: 4.0 }] {
        for u in [0.01, 0.2, 0.5, 0.77, 0.99] {
            let x = d.quantile(u);
            assert!((d.cdf(x) - u).abs() < 1e-12, "{d:?} at {u}: {}", d.cdf(x));
        }
    }
}

#[test]
fn specs_parse_and_bad_ones_say_what_is_allowed() {
    let v = VarySpec::parse("motion.dead_time=normal:0.016:0.002:0.01:0.03").unwrap();
    assert_eq!(v.bounds, Some((0.01, 0.03)));
    assert_eq!(v.spec(), "motion.dead_time=normal:0.016:0.002:0.01:0.03");
    for (bad, says) in [
        ("motion.speed", "expected KEY=DIST"),
        ("motion.speed=gauss:1:2", "unknown distribution"),
        ("motion.speed=normal:1", "normal:MEAN:SD"),
        ("motion.speed=normal:1:0", "SD must be > 0"),
        ("motion.speed=uniform:2:1", "LO must be below HI"),
        ("motion.speed=triangular:0:5:4", "LO <= MODE <= HI"),
        ("motion.speed=uniform:0:x", "not a finite number"),
        ("motion.speed=lognormal:0:1:2:1", "truncation LO must be below HI"),
    ] {
        let e = VarySpec::parse(bad).unwrap_err().0;
        assert!(e.contains(says), "{bad}: {e}");
    }
}

#[test]
fn columns_carry_units() {
    assert_eq!(column("motion.dead_time", "s"), "motion.dead_time_s");
    assert_eq!(column("decoupler.spring_rate", "N/m"), "decoupler.spring_rate_n_per_m");
    assert_eq!(column("target.stiffness", "N/m^1.5"), "target.stiffness_n_per_m1_5");
    assert_eq!(column("target.chi", "N s/m^2.5"), "target.chi_ns_per_m2_5");
    assert_eq!(column("decoupler.springs", ""), "decoupler.springs");
}

#[test]
fn chunks_tile_the_range() {
    let n = 1001;
    let mut at = 0;
    for k in 1..=7 {
        let (a, b) = chunk_range(n, k, 7);
        assert_eq!(a, at);
        at = b;
    }
    assert_eq!(at, n);
    assert!(parse_chunk("0/3").is_err() && parse_chunk("4/3").is_err() && parse_chunk("x").is_err());
    assert_eq!(parse_chunk("2/3").unwrap(), (2, 3));
}
/// A report read back (`--merge`) has the numbers written, to the last bit: a far tail's
/// probability (the outside probability of a normal draw 25 standard deviations from a bound)
/// once came back one unit in the last place off, and the merged report differed from the
/// whole run's.
#[test]
fn reports_read_back_have_the_numbers_written() {
    for x in [3.9262455345639715e-138_f64, 0.1 + 0.2, 1.0 / 3.0, 5e-324, 1.7976931348623157e308, 2.2250738585072014e-308] {
        let text = serde_json::to_string(&x).unwrap();
        let back: f64 = serde_json::from_str(&text).unwrap();
        assert_eq!(back.to_bits(), x.to_bits(), "{text}");
    }
}

/// docs/schema/sample.json is generated: `FLINCH_BLESS=1 cargo test -p flinch-harness --lib
/// sample::tests::schema` rewrites it.
#[test]
fn schema_in_docs_is_current_and_every_number_has_a_unit() {
    let (text, missing) = schema();
    assert!(missing.is_empty(), "numeric fields of the sample report without a unit (add them to UNITS): {missing:?}");
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../docs/schema/sample.json");
    if std::env::var_os("FLINCH_BLESS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(on_disk == text, "{} is out of date: FLINCH_BLESS=1 cargo test -p flinch-harness --lib sample::tests::schema", path.display());
}
