//! `--set KEY=VALUE`: a scene key changed on the command line, applied to the scene's TOML text
//! (tables created as needed) before the whole text goes through the scene validator, so an
//! override is checked exactly like the file. A problem at an overridden key is reported as
//! `--set motion.speed=9: motion.speed: allowed range ...`; every other problem keeps the file's
//! own line (lines are mapped back through the edit).
//!
//! VALUE is a TOML value (`0.5`, `"hand"`, `true`, `[1, 2]`, `{ stiffness = 1e4 }`); a bare word
//! that is not TOML is taken as a string (`--set target.region=face`).

use crate::scene::{self, Scene, SceneError};
use std::path::Path;
use toml_edit::{DocumentMut, Item, Value};

/// One override from the command line.
#[derive(Debug, Clone)]
pub struct Set {
    /// The dotted key, e.g. `motion.speed`.
    pub key: String,
    /// The value as given (what messages quote).
    pub raw: String,
    /// The value, parsed.
    pub value: Value,
}

impl Set {
    /// Parses `KEY=VALUE` (what clap hands the `--set` option).
    pub fn parse(arg: &str) -> Result<Set, String> {
        let Some((key, raw)) = arg.split_once('=') else {
            return Err(format!("expected KEY=VALUE (e.g. motion.speed=0.5), got `{arg}`"));
        };
        let key = key.trim();
        let valid_seg = |s: &str| !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !key.split('.').all(valid_seg) {
            return Err(format!("`{key}` is not a dotted scene key (e.g. motion.speed, decoupler.front_stop.damping)"));
        }
        let raw = raw.trim();
        if raw.is_empty() {
            return Err(format!("{key}: no value after `=` (e.g. {key}=0.5; a string: {key}=\"text\")"));
        }
        let value = match format!("v = {raw}").parse::<DocumentMut>() {
            Ok(d) => d.get("v").and_then(Item::as_value).cloned().ok_or_else(|| format!("{key}: `{raw}` is not a single value"))?,
            // A bare word (`face`, `hunt-crossley`) is a string; anything with TOML punctuation
            // that fails to parse is a typo worth naming.
            Err(e) if raw.contains(['[', '{', '"', '\'', '=']) => return Err(format!("{key}: `{raw}` is not a TOML value: {}", e.message().trim().replace('\n', "; "))),
            Err(_) => Value::from(raw),
        };
        Ok(Set { key: key.to_string(), raw: raw.to_string(), value })
    }

    /// `--set key=value`, as messages name the override.
    pub fn shown(&self) -> String {
        format!("--set {}={}", self.key, self.raw)
    }
}

/// A scene with overrides: what was read, what was simulated.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The name messages use for the file (`hand.toml`, `body_hand (shipped)`, `<stdin>`).
    pub file: String,
    /// The text as read.
    pub original: String,
    /// The text after the overrides (equal to `original` without any).
    pub text: String,
    /// The validated scene of `text`.
    pub scene: Scene,
}

/// Sets `key` to `value` in `doc`, creating missing tables; refuses a path that runs into a value.
fn set_in(doc: &mut DocumentMut, key: &str, value: &Value) -> Result<(), String> {
    let segs: Vec<&str> = key.split('.').collect();
    let mut item: &mut Item = doc.as_item_mut();
    for (i, seg) in segs.iter().enumerate() {
        let last = i + 1 == segs.len();
        if let Some(Value::Array(a)) = item.as_value_mut() {
            let n = seg.parse::<usize>().ok().filter(|&n| last && n < a.len()).ok_or_else(|| format!("{key}: `{seg}` is not an element of the array here (it has {} elements, counted from 0)", a.len()))?;
            let mut v = value.clone();
            *v.decor_mut() = a.get(n).map(|o| o.decor().clone()).unwrap_or_default();
            a.replace(n, v);
            return Ok(());
        }
        let inline = item.is_inline_table();
        let Some(table) = item.as_table_like_mut() else {
            let at = segs[..i].join(".");
            return Err(format!("{key}: `{at}` holds a value, not a table, so `{key}` cannot be set"));
        };
        if last {
            let mut v = value.clone();
            if let Some(old) = table.get(seg).and_then(Item::as_value) {
                *v.decor_mut() = old.decor().clone();
            }
            // A whole table replaced by an inline table, or a value: the validator judges it.
            table.insert(seg, Item::Value(v));
            return Ok(());
        }
        if table.get(seg).is_none() {
            let fresh = if inline { Item::Value(Value::InlineTable(Default::default())) } else { Item::Table(Default::default()) };
            table.insert(seg, fresh);
        }
        item = table.get_mut(seg).expect("inserted above");
    }
    Ok(())
}

/// For each line of `new`, the line of `old` it came from (1-based), `None` for a line the edit
/// made: the longest common subsequence of the two texts' lines.
fn line_map(old: &str, new: &str) -> Vec<Option<usize>> {
    let a: Vec<&str> = old.lines().collect();
    let b: Vec<&str> = new.lines().collect();
    let (n, m) = (a.len(), b.len());
    // Scenes are a few hundred lines: the quadratic table is small.
    let mut l = vec![vec![0u32; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            l[i][j] = if a[i] == b[j] { l[i + 1][j + 1] + 1 } else { l[i + 1][j].max(l[i][j + 1]) };
        }
    }
    let mut map = vec![None; m];
    let (mut i, mut j) = (0, 0);
    while i < n && j < m {
        if a[i] == b[j] {
            map[j] = Some(i + 1);
            i += 1;
            j += 1;
        } else if l[i + 1][j] >= l[i][j + 1] {
            i += 1;
        } else {
            j += 1;
        }
    }
    map
}

/// True when the issue at `issue_key` is about the override of `set_key` (the key itself, a key
/// inside a table it sets, or the table it sets a key in when that table is new).
fn concerns(issue_key: &str, set_key: &str) -> bool {
    issue_key == set_key || issue_key.starts_with(&format!("{set_key}.")) || (!issue_key.is_empty() && set_key.starts_with(&format!("{issue_key}.")))
}

/// The refusal of a text with overrides, each problem named as the user wrote it.
fn explain(e: &SceneError, original: &str, text: &str, sets: &[Set]) -> String {
    let map = line_map(original, text);
    let mut lines = Vec::new();
    for issue in &e.issues {
        if let Some(s) = sets.iter().rev().find(|s| concerns(&issue.key, &s.key)) {
            lines.push(format!("{}: {}: {}", s.shown(), issue.key, issue.message));
            continue;
        }
        let at = match issue.line {
            Some(l) => match map.get(l - 1).copied().flatten() {
                Some(o) => format!("{}:{o}", e.file),
                None => format!("{} (with {})", e.file, sets.iter().map(Set::shown).collect::<Vec<_>>().join(" ")),
            },
            None => e.file.clone(),
        };
        if issue.key.is_empty() {
            lines.push(format!("{at}: {}", issue.message));
        } else {
            lines.push(format!("{at}: {}: {}", issue.key, issue.message));
        }
    }
    lines.join("\n")
}

/// Applies `sets` to a scene's text (later sets win) and validates the result. Without sets the
/// text is validated as it is and the error is the validator's own.
pub fn apply(file: &str, original: String, sets: &[Set]) -> Result<Loaded, String> {
    if let Some(e) = other_command(file, &original) {
        return Err(e);
    }
    if sets.is_empty() {
        let scene = scene::parse(&original, file).map_err(|e| e.to_string())?;
        return Ok(Loaded { file: file.to_string(), text: original.clone(), original, scene });
    }
    for (i, s) in sets.iter().enumerate() {
        if let Some(t) = sets[..i].iter().find(|t| concerns(&t.key, &s.key) && t.key != s.key) {
            return Err(format!("{}: overlaps {} (one sets a table the other sets a key in); give one", s.shown(), t.shown()));
        }
    }
    // A file that is not TOML is refused as the file, before any override.
    let mut doc: DocumentMut = original.parse().map_err(|_| scene::parse(&original, file).err().map_or_else(|| format!("{file}: not valid TOML"), |e| e.to_string()))?;
    for s in sets {
        set_in(&mut doc, &s.key, &s.value).map_err(|e| format!("{}: {e}", s.shown()))?;
    }
    let text = doc.to_string();
    match scene::parse(&text, file) {
        Ok(scene) => Ok(Loaded { file: file.to_string(), original, text, scene }),
        Err(e) => Err(explain(&e, &original, &text, sets)),
    }
}

/// One line for an avoidance scene given to an impact command (`flinch run avoid_operator_hand`
/// listed seven missing keys): it names the command that reads it.
fn other_command(file: &str, text: &str) -> Option<String> {
    let doc: DocumentMut = text.parse().ok()?;
    let is_avoid = doc.contains_key("avoid") && !doc.contains_key("motion") && !doc.contains_key("decoupler");
    let arg = file.trim_end_matches(" (shipped)");
    is_avoid.then(|| format!("{file}: an avoidance scene (it has an [avoid] table and no impact tables): run it with `flinch avoid {arg}`"))
}

/// Reads a scene argument ([`crate::shipped::read`]) and applies `sets` ([`apply`]).
pub fn load(arg: &Path, sets: &[Set]) -> Result<Loaded, String> {
    let (file, text) = crate::shipped::read(arg).map_err(|e| e.0)?;
    apply(&file, text, sets)
}

/// Refuses a key that is both set and varied (`--vary`, `sample KEY=DIST`, `report --sweep`): the
/// run would not be what either says.
pub fn refuse_overlap(sets: &[Set], varied: &[&str], how: &str) -> Result<(), String> {
    for s in sets {
        if let Some(v) = varied.iter().find(|v| concerns(v, &s.key)) {
            return Err(format!("{}: {v} is also given to {how}; give it in one place", s.shown()));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hand() -> (String, String) {
        ("body_hand (shipped)".to_string(), crate::shipped::get("body_hand").unwrap().to_string())
    }

    #[test]
    fn values_are_toml_or_a_bare_string() {
        assert_eq!(Set::parse("motion.speed=0.5").unwrap().value.as_float(), Some(0.5));
        assert_eq!(Set::parse("target.region=face").unwrap().value.as_str(), Some("face"));
        assert_eq!(Set::parse("target.region=\"face\"").unwrap().value.as_str(), Some("face"));
        assert!(Set::parse("motion.start_at_speed=true").unwrap().value.as_bool().unwrap());
        assert!(Set::parse("decoupler.front_stop={ stiffness = 1e4, damping = 3 }").unwrap().value.is_inline_table());
        assert!(Set::parse("motion.speed").unwrap_err().contains("KEY=VALUE"));
        assert!(Set::parse("motion.speed=").unwrap_err().contains("no value"));
        assert!(Set::parse("a..b=1").unwrap_err().contains("dotted"));
        assert!(Set::parse("x=[1, 2").unwrap_err().contains("not a TOML value"));
    }

    #[test]
    fn a_set_key_changes_the_scene_and_a_bad_one_is_named_as_the_override() {
        let (file, text) = hand();
        let l = apply(&file, text.clone(), &[Set::parse("motion.speed=0.5").unwrap()]).unwrap();
        assert_eq!(l.scene.motion.speed, 0.5);
        let e = apply(&file, text.clone(), &[Set::parse("motion.speed=9").unwrap()]).unwrap_err();
        assert!(e.starts_with("--set motion.speed=9: motion.speed: allowed range"), "{e}");
        let e = apply(&file, text.clone(), &[Set::parse("motion.sped=1").unwrap()]).unwrap_err();
        assert!(e.starts_with("--set motion.sped=1: motion.sped: unknown key"), "{e}");
        assert!(e.contains("did you mean `speed`"), "{e}");
        let e = apply(&file, text.clone(), &[Set::parse("motion.speed.x=1").unwrap()]).unwrap_err();
        assert!(e.contains("holds a value"), "{e}");
        let e = apply(&file, text, &[Set::parse("motion=1").unwrap(), Set::parse("motion.speed=1").unwrap()]).unwrap_err();
        assert!(e.contains("overlaps"), "{e}");
    }

    #[test]
    fn other_problems_keep_the_files_line() {
        // Line 3 is bad in the file; an override inserts a new key above it.
        let text = "name = \"x\"\n[motion]\nspeed = -1\n";
        let e = apply("f.toml", text.into(), &[Set::parse("motion.accel=2").unwrap()]).unwrap_err();
        assert!(e.contains("f.toml:3: motion.speed"), "{e}");
        assert!(!e.contains("--set motion.speed"), "{e}");
        let m = line_map("a\nb\nc\n", "a\nx\nb\nc\n");
        assert_eq!(m, vec![Some(1), None, Some(2), Some(3)]);
    }

    /// Issue 26 item 7: `flinch run avoid_operator_hand` gave seven lines of missing keys.
    #[test]
    fn a_scene_for_another_command_gets_one_line_naming_it() {
        let text = crate::shipped::get("avoid_operator_hand").unwrap().to_string();
        let e = apply("avoid_operator_hand (shipped)", text, &[]).unwrap_err();
        assert_eq!(e.lines().count(), 1, "{e}");
        assert!(e.ends_with("run it with `flinch avoid avoid_operator_hand`"), "{e}");
    }

    #[test]
    fn a_key_set_and_varied_is_refused() {
        let s = [Set::parse("motion.speed=0.5").unwrap()];
        assert!(refuse_overlap(&s, &["motion.speed"], "--vary").unwrap_err().contains("--vary"));
        assert!(refuse_overlap(&s, &["tool.mass"], "--vary").is_ok());
    }
}
