//! Where a URDF that `urdf-rs` refuses goes wrong: the file is read again with `xml-rs` (the parser
//! under `urdf-rs`) to name the line and the element, since `urdf-rs`'s own error names neither.
//! Checked: the XML itself, the `name` of every link and joint, a joint's `type`, `parent` and
//! `child`, and every numeric attribute URDF defines (mass, inertia, origin, axis, limit, dynamics).

use xml::common::Position;
use xml::reader::{EventReader, XmlEvent};

/// The numeric attributes of URDF elements, with how many numbers each holds.
fn numeric(element: &str, attr: &str) -> Option<usize> {
    match (element, attr) {
        ("mass", "value") => Some(1),
        ("inertia", "ixx" | "ixy" | "ixz" | "iyy" | "iyz" | "izz") => Some(1),
        ("origin", "xyz" | "rpy") => Some(3),
        ("axis", "xyz") => Some(3),
        ("limit", "lower" | "upper" | "effort" | "velocity") => Some(1),
        ("dynamics", "damping" | "friction") => Some(1),
        _ => None,
    }
}

/// The first problem found, as (element, what is wrong) with its line; None when this pass finds
/// nothing (the caller then reports `urdf-rs`'s message as it is).
pub fn diagnose(text: &str) -> Option<(String, String)> {
    let mut reader = EventReader::new(text.as_bytes());
    // The enclosing <link> or <joint>, for naming.
    let mut owner: Option<String> = None;
    loop {
        let ev = reader.next();
        let line = reader.position().row + 1;
        let at = |el: String| format!("{el} (line {line})");
        match ev {
            Ok(XmlEvent::EndDocument) => return None,
            Err(e) => {
                let p = e.position();
                return Some(("<robot>".into(), format!("line {}, column {}: not well-formed XML: {}", p.row + 1, p.column + 1, e.msg())));
            }
            Ok(XmlEvent::StartElement { name, attributes, .. }) => {
                let el = name.local_name.as_str();
                let attr = |n: &str| attributes.iter().find(|a| a.name.local_name == n).map(|a| a.value.clone());
                if el == "link" || el == "joint" {
                    let Some(n) = attr("name") else {
                        return Some((at(format!("<{el}>")), format!("a <{el}> without a name (after {})", owner.as_deref().unwrap_or("the start"))));
                    };
                    owner = Some(format!("{el} \"{n}\""));
                    if el == "joint" {
                        match attr("type").as_deref() {
                            None => return Some((at(format!("joint \"{n}\"")), "has no type (revolute, continuous, prismatic, fixed, floating or planar)".into())),
                            Some("revolute" | "continuous" | "prismatic" | "fixed" | "floating" | "planar") => {}
                            Some(t) => return Some((at(format!("joint \"{n}\"")), format!("type \"{t}\" is not a URDF joint type (revolute, continuous, prismatic, fixed, floating or planar)"))),
                        }
                    }
                    continue;
                }
                let whose = at(owner.clone().unwrap_or_else(|| "<robot>".into()));
                if (el == "parent" || el == "child") && attr("link").is_none() {
                    return Some((whose, format!("<{el}> has no link attribute")));
                }
                for a in &attributes {
                    let Some(count) = numeric(el, &a.name.local_name) else { continue };
                    let parts: Vec<&str> = a.value.split_whitespace().collect();
                    let bad = parts.iter().find(|p| p.parse::<f64>().map_or(true, |x| !x.is_finite()));
                    if parts.len() != count || bad.is_some() {
                        let want = if count == 1 { "one finite number".to_string() } else { format!("{count} finite numbers") };
                        return Some((whose, format!("<{el} {}=\"{}\">: must be {want}", a.name.local_name, a.value)));
                    }
                }
            }
            Ok(XmlEvent::EndElement { name }) if name.local_name == "link" || name.local_name == "joint" => owner = None,
            Ok(_) => {}
        }
    }
}
