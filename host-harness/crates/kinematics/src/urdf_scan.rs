//! The bounded first pass over a URDF, before `urdf-rs` sees it (issue 27). One iterative walk
//! with `xml-rs` (the parser under `urdf-rs`) refuses what the parsers behind `urdf-rs` cannot
//! survive: an element nested deeper than [`MAX_DEPTH`] (RustyXML's recursive descent overflowed
//! the stack at 20,000 nested elements; xml-rs copies its namespace stack per element, quadratic
//! in the depth: 200,000 ran past 60 s), more than [`MAX_ELEMENTS`] elements, a document type
//! declaring entities, and a second root or a root other than `<robot>` (a URDF is one `<robot>`).
//! The same walk holds every numeric attribute URDF defines to the range table [`RANGES`]
//! (docs/robot.md): a 1e308 kg link or a 1e300 m origin is refused with its line, as a scene key
//! out of range is: `FILE:LINE: link "arm": <mass value>: allowed range [0, 10000] kg (...), got 1e308`.
use crate::error::KinError;
use xml::common::Position;
use xml::reader::{EventReader, ParserConfig, XmlEvent};

/// Deepest element nesting accepted: a URDF nests 5 (robot, link, visual, geometry, mesh); files
/// with `<gazebo>` or `<transmission>` extensions about 8.
pub const MAX_DEPTH: usize = 32;
/// Most elements accepted (the largest real URDFs have a few thousand).
pub const MAX_ELEMENTS: usize = 100_000;

/// A URDF number's allowed range, as a scene key's: the element and attribute, the unit, the
/// bounds, and why.
#[derive(Debug, Clone, Copy)]
pub struct UrdfRange {
    /// The element (`mass`, `inertia`, ...).
    pub element: &'static str,
    /// Its attributes held to this range.
    pub attrs: &'static [&'static str],
    /// The unit, as docs write it.
    pub unit: &'static str,
    /// Smallest allowed.
    pub min: f64,
    /// Largest allowed.
    pub max: f64,
    /// Why these bounds.
    pub source: &'static str,
}

const FOUR_PI: f64 = 4.0 * std::f64::consts::PI;

/// The range table of URDF values (generated into docs/robot.md by its test).
pub const RANGES: &[UrdfRange] = &[
    UrdfRange { element: "mass", attrs: &["value"], unit: "kg", min: 0.0, max: 1e4, source: "the heaviest industrial arm's heaviest link is about 2 t; 0 for a frame" },
    UrdfRange { element: "inertia", attrs: &["ixx", "iyy", "izz"], unit: "kg m^2", min: 0.0, max: 1e4, source: "a 2 t link 2 m long is about 700 kg m^2; the tensor is also checked physical" },
    UrdfRange { element: "inertia", attrs: &["ixy", "ixz", "iyz"], unit: "kg m^2", min: -1e4, max: 1e4, source: "bounded by the diagonal of a physical tensor" },
    UrdfRange { element: "origin", attrs: &["xyz"], unit: "m", min: -100.0, max: 100.0, source: "the longest arms reach 4 m; a frame 100 m away is a typo" },
    UrdfRange { element: "origin", attrs: &["rpy"], unit: "rad", min: -FOUR_PI, max: FOUR_PI, source: "any orientation is within +-pi; two turns allowed for generated files" },
    UrdfRange { element: "axis", attrs: &["xyz"], unit: "1", min: -1e3, max: 1e3, source: "only the direction matters; not all zero" },
    UrdfRange { element: "limit", attrs: &["lower", "upper"], unit: "rad or m", min: -100.0, max: 100.0, source: "16 turns, or the longest linear axis; lower <= upper" },
    UrdfRange { element: "limit", attrs: &["effort"], unit: "N m or N", min: 0.0, max: 1e7, source: "URDF requires >= 0; unused by Flinch" },
    UrdfRange { element: "limit", attrs: &["velocity"], unit: "rad/s or m/s", min: 0.0, max: 1e4, source: "URDF requires >= 0; unused by Flinch" },
    UrdfRange { element: "dynamics", attrs: &["damping", "friction"], unit: "N m s/rad or N s/m", min: 0.0, max: 1e6, source: "as the scene's robot.joint_damping" },
];

/// The range of `attr` of `element`, if URDF defines it as a number.
pub fn range_of(element: &str, attr: &str) -> Option<&'static UrdfRange> {
    RANGES.iter().find(|r| r.element == element && r.attrs.contains(&attr))
}

fn count(element: &str, attr: &str) -> usize {
    if matches!((element, attr), ("origin", _) | ("axis", _)) {
        3
    } else {
        1
    }
}

fn g(x: f64) -> String {
    if x == 0.0 || (1e-3..1e5).contains(&x.abs()) {
        let s = format!("{x}");
        if s.len() > 12 {
            format!("{x:.6}")
        } else {
            s
        }
    } else {
        format!("{x:e}")
    }
}

/// Walks `text` once: structure bounded, one `<robot>` root, every number in its range. `file`
/// names the URDF in the error (`FILE:LINE`).
pub fn scan(text: &str, file: &str) -> Result<(), KinError> {
    if let Some(pos) = text.find("<!ENTITY") {
        let line = 1 + text[..pos].bytes().filter(|&b| b == b'\n').count();
        return Err(KinError::new(&format!("{file}:{line}"), "<!DOCTYPE>", "declares entities; a URDF has none (entity expansion is refused)"));
    }
    let cfg = ParserConfig::new().trim_whitespace(true).cdata_to_characters(true);
    let mut reader = EventReader::new_with_config(text.as_bytes(), cfg);
    let mut depth = 0usize;
    let mut owner = String::from("<robot>");
    let mut elements = 0usize;
    let mut root_closed_at: Option<u64> = None;
    let at = |line: u64| format!("{file}:{line}");
    loop {
        let ev = reader.next();
        let line = reader.position().row + 1;
        match ev {
            Ok(XmlEvent::EndDocument) => {
                return if root_closed_at.is_some() { Ok(()) } else { Err(KinError::new(&at(line), "<robot>", "no root element: a URDF is one <robot> element")) };
            }
            // Malformed XML is left to urdf-rs and the diagnosis that follows it (same messages as before).
            Err(_) => return Ok(()),
            Ok(XmlEvent::StartElement { name, attributes, .. }) => {
                let el = name.local_name;
                if let Some(closed) = root_closed_at {
                    return Err(KinError::new(&at(line), format!("<{el}>"), format!("a second root element after the first closed at line {closed}; a URDF has one <robot>")));
                }
                if depth == 0 && el != "robot" {
                    return Err(KinError::new(&at(line), format!("<{el}>"), "the root element must be <robot>"));
                }
                elements += 1;
                if elements > MAX_ELEMENTS {
                    return Err(KinError::new(&at(line), format!("<{el}>"), format!("more than {MAX_ELEMENTS} elements; a URDF has a few thousand")));
                }
                if depth >= MAX_DEPTH {
                    return Err(KinError::new(&at(line), format!("<{el}>"), format!("element depth {} exceeds {MAX_DEPTH} (a URDF nests 5 deep: robot, link, visual, geometry, mesh)", depth + 1)));
                }
                let attr = |n: &str| attributes.iter().find(|a| a.name.local_name == n).map(|a| a.value.clone());
                if depth == 1 && (el == "link" || el == "joint") {
                    owner = match attr("name") {
                        Some(n) => format!("{el} \"{n}\""),
                        None => format!("<{el}>"),
                    };
                }
                let mut limits = (None, None);
                for a in &attributes {
                    let an = a.name.local_name.as_str();
                    let Some(r) = range_of(&el, an) else { continue };
                    let want = count(&el, an);
                    let parsed: Vec<Option<f64>> = a.value.split_whitespace().map(|p| p.parse::<f64>().ok()).collect();
                    // Text that is not `want` numbers is urdf-rs's to refuse (its diagnosis names the line).
                    if parsed.len() != want || parsed.iter().any(Option::is_none) {
                        continue;
                    }
                    let vals: Vec<f64> = parsed.into_iter().flatten().collect();
                    let what = format!("<{el} {an}>");
                    if vals.iter().any(|x| !x.is_finite()) {
                        let n = if want == 1 { "one finite number".to_string() } else { format!("{want} finite numbers") };
                        return Err(KinError::new(&at(line), owner.clone(), format!("{what}: must be {n}, got \"{}\"", a.value)));
                    }
                    for x in &vals {
                        if *x < r.min || *x > r.max {
                            return Err(KinError::new(&at(line), owner.clone(), format!("{what}: allowed range [{}, {}] {} ({}), got {}", g(r.min), g(r.max), r.unit, r.source, g(*x))));
                        }
                    }
                    if el == "axis" && vals.iter().all(|x| *x == 0.0) {
                        return Err(KinError::new(&at(line), owner.clone(), format!("{what}: is all zero; an axis needs a direction")));
                    }
                    match an {
                        "lower" => limits.0 = Some(vals[0]),
                        "upper" => limits.1 = Some(vals[0]),
                        _ => {}
                    }
                }
                if let (Some(lo), Some(hi)) = limits {
                    if lo > hi {
                        return Err(KinError::new(&at(line), owner.clone(), format!("<limit>: lower = {} is above upper = {}; a URDF limit has lower <= upper", g(lo), g(hi))));
                    }
                }
                depth += 1;
            }
            Ok(XmlEvent::EndElement { .. }) => {
                depth = depth.saturating_sub(1);
                if depth == 1 {
                    owner = String::from("<robot>");
                }
                if depth == 0 {
                    root_closed_at = Some(line);
                }
            }
            Ok(_) => {}
        }
    }
}

/// The range table as docs/robot.md shows it.
pub fn ranges_markdown() -> String {
    let mut s = String::from("| element | attributes | unit | allowed | why |\n|---|---|---|---|---|\n");
    for r in RANGES {
        s.push_str(&format!("| `<{}>` | {} | {} | [{}, {}] | {} |\n", r.element, r.attrs.join(", "), r.unit, g(r.min), g(r.max), r.source));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const TWO_LINK: &str = include_str!("../../../../scenes/robots/two_link.urdf");

    fn err(text: &str) -> String {
        scan(text, "r.urdf").unwrap_err().to_string()
    }

    #[test]
    fn nesting_beyond_the_depth_limit_is_refused_with_its_line() {
        for n in [40usize, 20_000, 200_000] {
            let t = TWO_LINK.replacen("<link name=\"base\"", &format!("<link name=\"base\">{}{}</link><link name=\"base_\"", "<a>".repeat(n), "</a>".repeat(n)), 1);
            let t0 = std::time::Instant::now();
            let e = err(&t);
            assert!(e.contains("element depth 33 exceeds 32"), "{e}");
            assert!(e.starts_with("r.urdf:"), "{e}");
            // Bounded: the walk stops at the limit (was a stack overflow at 20,000 in urdf-rs).
            assert!(t0.elapsed().as_secs() < 5, "{n}: {:?}", t0.elapsed());
        }
    }

    #[test]
    fn a_urdf_has_one_robot_root() {
        let two = format!("{TWO_LINK}\n<robot name=\"second\"></robot>\n");
        let e = err(&two);
        assert!(e.contains("a second root element after the first closed at line"), "{e}");
        let e = err("<?xml version=\"1.0\"?>\n<model name=\"x\"/>\n");
        assert!(e.contains("r.urdf:2: <model>: the root element must be <robot>"), "{e}");
        let e = err("<?xml version=\"1.0\"?>\n<!DOCTYPE r [<!ENTITY a \"aaaa\">]>\n<robot name=\"x\">&a;</robot>\n");
        assert!(e.contains("declares entities"), "{e}");
    }

    #[test]
    fn urdf_values_are_held_to_their_ranges() {
        let cases: &[(&str, &str, &str)] = &[
            ("<mass value=\"", "<mass value=\"1e308\" x=\"", "<mass value>: allowed range [0, 10000] kg"),
            ("<mass value=\"", "<mass value=\"-1\" x=\"", "<mass value>: allowed range"),
            ("ixx=\"", "ixx=\"1e300\" x=\"", "<inertia ixx>: allowed range"),
            ("<origin xyz=\"", "<origin xyz=\"1e200 0 0\" x=\"", "<origin xyz>: allowed range [-100, 100] m"),
            ("rpy=\"", "rpy=\"1e9 0 0\" x=\"", "<origin rpy>: allowed range"),
            ("<axis xyz=\"", "<axis xyz=\"0 0 0\" x=\"", "is all zero"),
            ("<axis xyz=\"", "<axis xyz=\"1e9 0 1\" x=\"", "<axis xyz>: allowed range"),
            ("<mass value=\"", "<mass value=\"nan\" x=\"", "must be one finite number"),
        ];
        for (from, to, want) in cases {
            assert!(TWO_LINK.contains(from), "{from}");
            let e = err(&TWO_LINK.replacen(from, to, 1));
            assert!(e.contains(want), "{to}: {e}");
            assert!(e.starts_with("r.urdf:") && e.contains("link \"") || e.contains("joint \""), "{e}");
        }
        let lim = "<robot name=\"x\"><joint name=\"j\" type=\"revolute\"><limit lower=\"1\" upper=\"-1\" effort=\"1\" velocity=\"1\"/></joint></robot>";
        assert!(err(lim).contains("joint \"j\": <limit>: lower = 1 is above upper = -1"));
        let big = "<robot name=\"x\"><joint name=\"j\" type=\"revolute\"><limit lower=\"-1e300\" upper=\"1e300\" effort=\"1\" velocity=\"1\"/></joint></robot>";
        assert!(err(big).contains("<limit lower>: allowed range [-100, 100] rad or m"));
        let neg = "<robot name=\"x\"><joint name=\"j\" type=\"revolute\"><limit lower=\"-1\" upper=\"1\" effort=\"-1\" velocity=\"1\"/></joint></robot>";
        assert!(err(neg).contains("<limit effort>: allowed range [0, 1e7]"), "{}", err(neg));
    }

    #[test]
    fn docs_show_the_range_table_of_the_code() {
        let doc = std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../docs/robot.md")).unwrap();
        assert!(doc.contains(&ranges_markdown()), "docs/robot.md: paste this table:\n{}", ranges_markdown());
    }

    #[test]
    fn every_shipped_urdf_passes() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../scenes/robots");
        let mut n = 0;
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            if e.path().extension().is_some_and(|x| x == "urdf") {
                let t = std::fs::read_to_string(e.path()).unwrap();
                scan(&t, &e.path().display().to_string()).unwrap();
                n += 1;
            }
        }
        assert!(n >= 2);
    }
}
