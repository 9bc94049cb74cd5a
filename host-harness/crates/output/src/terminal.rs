//! Text for a terminal: a scene's `name`, a file name, a key echoed in a message can carry
//! characters that a terminal obeys instead of showing (ESC sequences that recolour, clear or
//! retitle; the 8-bit CSI U+009B; BEL; a carriage return that overwrites the line) or that reorder
//! what is shown (the bidirectional overrides: `\u202eSAFE` reads as "EFAS"). Every human output
//! ([`crate::output::print`], [`crate::output::note`], so every `error:` line) goes through
//! [`escape`]: each such character is shown as `\uXXXX`, visibly, never deleted (a reader sees that
//! something was there). Newline and tab are kept. The form is JSON's own escape, so a JSON document
//! printed through it still parses, to the very same strings.
use std::borrow::Cow;

/// True for a character a terminal acts on or that reorders text.
pub fn is_hazard(c: char) -> bool {
    matches!(c,
        '\u{0}'..='\u{8}' | '\u{b}'..='\u{1f}' | '\u{7f}'..='\u{9f}'   // C0 but \t \n, DEL, C1
        | '\u{200e}' | '\u{200f}' | '\u{061c}'                          // LRM, RLM, ALM
        | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}'             // embeddings, overrides, isolates
        | '\u{2028}' | '\u{2029}')                                       // line and paragraph separators
}

/// `text` with every hazard written `\uXXXX`; borrowed when there is none.
pub fn escape(text: &str) -> Cow<'_, str> {
    if !text.chars().any(is_hazard) {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        if is_hazard(c) {
            out.push_str(&format!("\\u{:04x}", c as u32));
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_and_bidi_overrides_are_shown_not_obeyed() {
        let evil = "evil \u{1b}[31mRED\u{1b}[0m \u{202e}SAFE\u{202c} \u{7} bell \u{9b}2J\r\n\tok";
        let e = escape(evil);
        assert!(!e.chars().any(is_hazard), "{e}");
        assert_eq!(e, "evil \\u001b[31mRED\\u001b[0m \\u202eSAFE\\u202c \\u0007 bell \\u009b2J\\u000d\n\tok");
        assert!(matches!(escape("plain text, ünïcode, 日本"), Cow::Borrowed(_)));
    }

    #[test]
    fn a_json_string_escaped_parses_back_to_the_same_text() {
        let name = "a\u{202e}b\u{9b}c\u{2066}d";
        let doc = serde_json::to_string(&name).unwrap();
        let shown = escape(&doc);
        assert!(!shown.chars().any(is_hazard));
        let back: String = serde_json::from_str(&shown).unwrap();
        assert_eq!(back, name);
    }
}
