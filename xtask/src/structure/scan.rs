//! Reads Rust source the way the import check needs it: tokens without comments, the module tree
//! of a crate from its root (`mod x;`, `#[path]`, inline `mod x { }`), and every module path a file
//! names (`use` trees expanded, and paths in code such as `crate::verdict::line(s)`).
//!
//! Not a Rust parser: tokens are identifiers, `::`, one-character punctuation and string literals;
//! comments, char literals and lifetimes are dropped. That is enough for paths, because a path is
//! a run of identifiers joined by `::` and nothing inside a comment or a string can start one.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    Ident(String),
    /// `::`
    Path,
    Punct(char),
    Str(String),
}

/// A token and the line it is on (1-based).
#[derive(Clone, Debug)]
pub struct Token {
    pub tok: Tok,
    pub line: usize,
}

/// Splits source text into tokens, dropping comments (nested block comments too), char literals
/// and lifetimes; string literals (plain, byte, raw) become one `Str` token.
pub fn tokenize(src: &str) -> Vec<Token> {
    let b: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    let n = b.len();
    while i < n {
        let c = b[i];
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && i + 1 < n && b[i + 1] == '/' {
            while i < n && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && i + 1 < n && b[i + 1] == '*' {
            let mut depth = 0;
            while i < n {
                if b[i] == '/' && i + 1 < n && b[i + 1] == '*' {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && i + 1 < n && b[i + 1] == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if b[i] == '\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
        } else if c == 'r' && i + 1 < n && (b[i + 1] == '"' || (b[i + 1] == '#' && raw_start(&b, i + 1))) || (c == 'b' && i + 2 < n && b[i + 1] == 'r' && (b[i + 2] == '"' || b[i + 2] == '#')) {
            // Raw string: r"..." or r#"..."#, optionally b-prefixed.
            let start_line = line;
            i += if c == 'b' { 2 } else { 1 };
            let mut hashes = 0;
            while i < n && b[i] == '#' {
                hashes += 1;
                i += 1;
            }
            i += 1; // the opening quote
            let mut s = String::new();
            while i < n {
                if b[i] == '"' && (0..hashes).all(|k| i + 1 + k < n && b[i + 1 + k] == '#') {
                    i += 1 + hashes;
                    break;
                }
                if b[i] == '\n' {
                    line += 1;
                }
                s.push(b[i]);
                i += 1;
            }
            out.push(Token { tok: Tok::Str(s), line: start_line });
        } else if c == '"' || (c == 'b' && i + 1 < n && b[i + 1] == '"') {
            let start_line = line;
            i += if c == 'b' { 2 } else { 1 };
            let mut s = String::new();
            while i < n && b[i] != '"' {
                if b[i] == '\\' && i + 1 < n {
                    s.push(b[i + 1]);
                    if b[i + 1] == '\n' {
                        line += 1;
                    }
                    i += 2;
                    continue;
                }
                if b[i] == '\n' {
                    line += 1;
                }
                s.push(b[i]);
                i += 1;
            }
            i += 1;
            out.push(Token { tok: Tok::Str(s), line: start_line });
        } else if c == '\'' {
            // A char literal ('a', '\n', '\u{..}') or a lifetime ('a): skip either.
            if i + 2 < n && b[i + 1] == '\\' {
                i += 2;
                while i < n && b[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if i + 2 < n && b[i + 2] == '\'' {
                i += 3;
            } else {
                i += 1;
                while i < n && (b[i].is_alphanumeric() || b[i] == '_') {
                    i += 1;
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            let s0 = i;
            while i < n && (b[i].is_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            let word: String = b[s0..i].iter().collect();
            let word = word.strip_prefix("r#").map(str::to_string).unwrap_or(word);
            out.push(Token { tok: Tok::Ident(word), line });
        } else if c.is_ascii_digit() {
            while i < n && (b[i].is_alphanumeric() || b[i] == '_' || b[i] == '.') {
                // `1..2` is a range, not a number with two points.
                if b[i] == '.' && i + 1 < n && b[i + 1] == '.' {
                    break;
                }
                i += 1;
            }
        } else if c == ':' && i + 1 < n && b[i + 1] == ':' {
            out.push(Token { tok: Tok::Path, line });
            i += 2;
        } else {
            out.push(Token { tok: Tok::Punct(c), line });
            i += 1;
        }
    }
    out
}

fn raw_start(b: &[char], mut i: usize) -> bool {
    while i < b.len() && b[i] == '#' {
        i += 1;
    }
    i < b.len() && b[i] == '"'
}

/// One module of a crate: its path from the crate root, the file that holds it, and what it
/// declares.
#[derive(Debug, Default)]
pub struct Module {
    /// The file the module's code is in (an inline module's is its parent's file).
    pub file: PathBuf,
    /// Child modules by name.
    pub children: BTreeMap<String, Vec<String>>,
    /// Items defined here (fn, struct, enum, const, static, type, trait, union, macro).
    pub items: Vec<String>,
    /// `use` declarations: the name they bring in (None for a glob) and the path they name,
    /// relative to this module.
    pub uses: Vec<(Option<String>, Vec<String>)>,
}

/// A path a file names, with where it was written.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The module (crate-relative path) the path was written in.
    pub scope: Vec<String>,
    /// The path's segments, as written (`crate`, `super`, `self` kept).
    pub path: Vec<String>,
    pub file: PathBuf,
    pub line: usize,
    /// What wrote it: a path in code, a `use` of one name, or a glob `use`.
    pub kind: RefKind,
}

/// Where a [`Reference`] was written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RefKind {
    Code,
    Use,
    Glob,
}

/// A crate's module tree and every path its files name.
#[derive(Debug, Default)]
pub struct CrateSource {
    pub modules: BTreeMap<Vec<String>, Module>,
    pub references: Vec<Reference>,
    /// Files that could not be read, with the reason.
    pub errors: Vec<String>,
}

/// Reads a crate from its root file (`src/lib.rs`, `src/main.rs`, `src/bin/x.rs`).
pub fn read_crate(root: &Path) -> CrateSource {
    let mut cs = CrateSource::default();
    read_file(&mut cs, root, Vec::new(), ModDir::Root);
    cs
}

/// Where a file's `mod x;` children are looked for.
#[derive(Clone, Copy)]
enum ModDir {
    /// A crate root or a `mod.rs`: next to the file.
    Root,
    /// A file `a.rs`: in the folder `a/`.
    Named,
}

fn read_file(cs: &mut CrateSource, file: &Path, scope: Vec<String>, kind: ModDir) {
    let text = match fs::read_to_string(file) {
        Ok(t) => t,
        Err(e) => {
            cs.errors.push(format!("{}: {e}", file.display()));
            return;
        }
    };
    let dir = match kind {
        ModDir::Root => file.parent().map(Path::to_path_buf).unwrap_or_default(),
        ModDir::Named => file.with_extension(""),
    };
    let toks = tokenize(&text);
    cs.modules.entry(scope.clone()).or_default().file = file.to_path_buf();
    let mut p = Parser { toks: &toks, i: 0, file, cs, pending: Vec::new() };
    p.block(&scope, &dir, file.parent().unwrap_or(Path::new(".")), false);
    let pending = std::mem::take(&mut p.pending);
    for (child_scope, child_file, child_kind) in pending {
        read_file(cs, &child_file, child_scope, child_kind);
    }
}

struct Parser<'a> {
    toks: &'a [Token],
    i: usize,
    file: &'a Path,
    cs: &'a mut CrateSource,
    /// Child module files still to read: (scope, file, kind).
    pending: Vec<(Vec<String>, PathBuf, ModDir)>,
}

const ITEM_KEYWORDS: [&str; 8] = ["fn", "struct", "enum", "const", "static", "type", "trait", "union"];

impl Parser<'_> {
    fn ident(&self, k: usize) -> Option<&str> {
        match self.toks.get(k).map(|t| &t.tok) {
            Some(Tok::Ident(s)) => Some(s),
            _ => None,
        }
    }

    fn is(&self, k: usize, c: char) -> bool {
        matches!(self.toks.get(k).map(|t| &t.tok), Some(Tok::Punct(x)) if *x == c)
    }

    fn is_path(&self, k: usize) -> bool {
        matches!(self.toks.get(k).map(|t| &t.tok), Some(Tok::Path))
    }

    /// Reads tokens up to the end of the current block (`}` when `inner`, else the end of file),
    /// recording modules, items, uses and paths in `scope`. `dir` is where `mod x;` files are, `here`
    /// the directory of the file (for `#[path]`).
    fn block(&mut self, scope: &[String], dir: &Path, here: &Path, inner: bool) {
        let mut depth = 0usize;
        let mut path_attr: Option<String> = None;
        while self.i < self.toks.len() {
            let line = self.toks[self.i].line;
            // #[path = "x.rs"]
            if self.is(self.i, '#') && self.is(self.i + 1, '[') && self.ident(self.i + 2) == Some("path") && self.is(self.i + 3, '=') {
                if let Some(Tok::Str(s)) = self.toks.get(self.i + 4).map(|t| &t.tok) {
                    path_attr = Some(s.clone());
                }
            }
            match &self.toks[self.i].tok {
                Tok::Punct('{') => {
                    depth += 1;
                    self.i += 1;
                }
                Tok::Punct('}') => {
                    self.i += 1;
                    if depth == 0 {
                        if inner {
                            return;
                        }
                    } else {
                        depth -= 1;
                    }
                }
                Tok::Ident(w) if w == "mod" && self.ident(self.i + 1).is_some() && (self.is(self.i + 2, ';') || self.is(self.i + 2, '{')) => {
                    let name = self.ident(self.i + 1).unwrap_or_default().to_string();
                    let mut child = scope.to_vec();
                    child.push(name.clone());
                    self.cs.modules.entry(scope.to_vec()).or_default().children.insert(name.clone(), child.clone());
                    if self.is(self.i + 2, ';') {
                        let (f, kind) = match path_attr.take() {
                            Some(p) => (here.join(p), ModDir::Named),
                            None => {
                                let a = dir.join(format!("{name}.rs"));
                                if a.exists() { (a, ModDir::Named) } else { (dir.join(&name).join("mod.rs"), ModDir::Root) }
                            }
                        };
                        self.pending.push((child, f, kind));
                        self.i += 3;
                    } else {
                        self.i += 3;
                        self.cs.modules.entry(child.clone()).or_default().file = self.file.to_path_buf();
                        let sub = dir.join(&name);
                        self.block(&child, &sub, here, true);
                    }
                }
                Tok::Ident(w) if w == "use" => {
                    self.i += 1;
                    let mut found = Vec::new();
                    self.use_tree(&mut Vec::new(), &mut found);
                    for (alias, path) in found {
                        let kind = if alias.is_none() { RefKind::Glob } else { RefKind::Use };
                        self.cs.references.push(Reference { scope: scope.to_vec(), path: path.clone(), file: self.file.to_path_buf(), line, kind });
                        self.cs.modules.entry(scope.to_vec()).or_default().uses.push((alias, path));
                    }
                }
                Tok::Ident(w) if w == "macro_rules" && self.is(self.i + 1, '!') => {
                    if let Some(name) = self.ident(self.i + 2) {
                        let name = name.to_string();
                        self.cs.modules.entry(scope.to_vec()).or_default().items.push(name);
                    }
                    self.i += 2;
                }
                Tok::Ident(w) if ITEM_KEYWORDS.contains(&w.as_str()) && self.ident(self.i + 1).is_some() => {
                    let name = self.ident(self.i + 1).unwrap_or_default().to_string();
                    if depth == 0 {
                        self.cs.modules.entry(scope.to_vec()).or_default().items.push(name);
                    }
                    self.i += 2;
                }
                Tok::Ident(w) => {
                    // A path in code: `crate::a::b`, `super::x`, `self::y`, or `child::z`.
                    // `pub(in super::super)` names a visibility, not a dependency.
                    let visibility = self.i >= 2 && self.ident(self.i - 1) == Some("in") && self.is(self.i - 2, '(');
                    if self.is_path(self.i + 1) && !(self.i > 0 && self.is_path(self.i - 1)) && !visibility {
                        let first = w.clone();
                        let mut path = vec![first];
                        let mut k = self.i + 1;
                        while self.is_path(k) {
                            match self.ident(k + 1) {
                                Some(s) => {
                                    path.push(s.to_string());
                                    k += 2;
                                }
                                None => break,
                            }
                        }
                        self.cs.references.push(Reference { scope: scope.to_vec(), path, file: self.file.to_path_buf(), line, kind: RefKind::Code });
                        self.i = k;
                    } else {
                        self.i += 1;
                    }
                }
                _ => self.i += 1,
            }
            if !matches!(self.toks.get(self.i.saturating_sub(1)).map(|t| &t.tok), Some(Tok::Punct('#' | '[' | '=' | ']')) | Some(Tok::Ident(_)) | Some(Tok::Str(_))) {
                path_attr = None;
            }
        }
    }

    /// Reads a use tree at `self.i`, up to and including its `;`: each leaf as (alias, path).
    fn use_tree(&mut self, prefix: &mut Vec<String>, out: &mut Vec<(Option<String>, Vec<String>)>) {
        let base = prefix.len();
        loop {
            match self.toks.get(self.i).map(|t| t.tok.clone()) {
                Some(Tok::Ident(s)) if s == "as" => {
                    let alias = self.ident(self.i + 1).map(str::to_string);
                    if let Some(last) = out.last_mut() {
                        last.0 = alias;
                    }
                    self.i += 2;
                }
                Some(Tok::Ident(s)) => {
                    prefix.push(s.clone());
                    self.i += 1;
                    if !self.is_path(self.i) {
                        let mut path = prefix.clone();
                        let alias = if s == "self" {
                            path.pop();
                            path.last().cloned()
                        } else {
                            Some(s)
                        };
                        out.push((alias, path));
                    }
                }
                Some(Tok::Path) => self.i += 1,
                Some(Tok::Punct('*')) => {
                    out.push((None, prefix.clone()));
                    self.i += 1;
                }
                Some(Tok::Punct('{')) => {
                    self.i += 1;
                    let keep = prefix.len();
                    loop {
                        self.use_tree(prefix, out);
                        prefix.truncate(keep);
                        match self.toks.get(self.i).map(|t| &t.tok) {
                            Some(Tok::Punct(',')) => self.i += 1,
                            Some(Tok::Punct('}')) => {
                                self.i += 1;
                                break;
                            }
                            _ => break,
                        }
                        if self.is(self.i, '}') {
                            self.i += 1;
                            break;
                        }
                    }
                }
                Some(Tok::Punct(';')) => {
                    if base == 0 {
                        self.i += 1;
                    }
                    prefix.truncate(base);
                    return;
                }
                Some(Tok::Punct(',' | '}')) | None => {
                    prefix.truncate(base);
                    return;
                }
                Some(_) => self.i += 1,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_strings_and_lifetimes_are_not_paths() {
        let t = tokenize("// crate::a::b\n/* crate::c /* nested */ crate::d */ let s = \"crate::e\"; fn f<'a>(x: &'a str) -> char { 'x' } r#\"crate::g\"#; crate::h::i");
        let idents: Vec<&str> = t.iter().filter_map(|t| if let Tok::Ident(s) = &t.tok { Some(s.as_str()) } else { None }).collect();
        assert_eq!(idents, ["let", "s", "fn", "f", "x", "str", "char", "crate", "h", "i"]);
        assert_eq!(t.last().map(|t| t.line), Some(2));
    }
}
