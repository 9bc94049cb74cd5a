//! The range table of docs/SCENES.md, generated from [`super::key_tables`]: every numeric key of
//! every table, its unit, both ends of its allowed range and where they come from. The test below
//! fails when the doc is stale; `FLINCH_BLESS=1 cargo test -p flinch-harness --lib scene::doc`
//! rewrites it.
use super::check::{num, Bound, Need, Ty};

/// The markers in docs/SCENES.md between which [`range_table`] is kept.
pub const BEGIN: &str = "<!-- ranges: generated from scene::key_tables(), do not edit by hand -->";
/// See [`BEGIN`].
pub const END: &str = "<!-- end of ranges -->";

fn low(b: Bound) -> String {
    match b {
        Bound::Open => "none".into(),
        Bound::Incl(x) => format!(">= {}", num(x)),
        Bound::Excl(x) => format!("> {}", num(x)),
    }
}

fn high(b: Bound) -> String {
    match b {
        Bound::Open => "none".into(),
        Bound::Incl(x) => format!("<= {}", num(x)),
        Bound::Excl(x) => format!("< {}", num(x)),
    }
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// The markdown table: key, where it applies, unit, min, max, default, source.
pub fn range_table() -> String {
    let mut out = String::from("| key | applies to | unit | min | max | default | source of the range |\n|---|---|---|---|---|---|---|\n");
    for t in super::key_tables() {
        for k in t.keys {
            let (unit, lo, hi, source) = match k.ty {
                Ty::Number(s) => (s.unit.to_string(), low(s.lo), high(s.hi), s.source),
                Ty::Integer { lo, hi, source } => ("integer".into(), format!(">= {lo}"), if hi == u32::MAX { "none".into() } else { format!("<= {hi}") }, source),
                _ => continue,
            };
            let key = if t.path.is_empty() { k.name.to_string() } else { format!("{}.{}", t.path, k.name) };
            let point = if super::avoid::POINTS.contains(&k.name) && t.path.starts_with("avoid") { " (each of [x, y])" } else { "" };
            let default = match k.need {
                Need::Required => "required".to_string(),
                Need::Default(x) => num(x),
                Need::Optional(what) => format!("optional: {what}"),
            };
            out.push_str(&format!(
                "| `{key}` | {} | {} | {lo} | {hi}{point} | {} | {} |\n",
                if t.when.is_empty() { "all".to_string() } else { cell(t.when) },
                if unit.is_empty() { "1".into() } else { unit },
                cell(&default),
                cell(source)
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_md_lists_every_range_and_is_current() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../docs/SCENES.md");
        let doc = std::fs::read_to_string(&path).unwrap();
        let (Some(a), Some(b)) = (doc.find(BEGIN), doc.find(END)) else { panic!("docs/SCENES.md lacks the markers {BEGIN} ... {END}") };
        let fresh = format!("{}{BEGIN}\n{}{}", &doc[..a], range_table(), &doc[b..]);
        if std::env::var_os("FLINCH_BLESS").is_some() {
            std::fs::write(&path, &fresh).unwrap();
        } else {
            assert!(doc == fresh, "docs/SCENES.md's range table is stale: FLINCH_BLESS=1 cargo test -p flinch-harness --lib scene::doc");
        }
        // Every numeric key of every table is a row, with its source.
        for t in crate::scene::key_tables() {
            for k in t.keys.iter().filter(|k| k.span().is_some()) {
                let key = if t.path.is_empty() { k.name.to_string() } else { format!("{}.{}", t.path, k.name) };
                assert!(fresh.contains(&format!("| `{key}` |")), "{key}");
            }
        }
    }
}
