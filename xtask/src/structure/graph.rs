//! The module graph of one crate, from what `scan.rs` read: each path a file names is resolved to
//! the module that defines its item (following `use` aliases and re-exports, globs included), an
//! edge joins the two files, and the strongly connected components of more than one file are the
//! import circles (Tarjan's algorithm). Importing a module (`use crate::scene;`) is not an edge by
//! itself, each path used through it is; a glob import (`use super::*;`) is one.

use super::scan::{CrateSource, Module, RefKind};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

/// One edge of a circle: `from` names `written` on `line`, which is defined in `to`.
#[derive(Debug, Clone)]
pub struct Edge {
    pub from: PathBuf,
    pub line: usize,
    pub written: String,
    pub to: PathBuf,
}

/// A strongly connected component of the file graph, and the edges inside it.
#[derive(Debug)]
pub struct Cycle {
    pub files: Vec<PathBuf>,
    pub edges: Vec<Edge>,
}

/// How deep aliases and globs are followed before giving up (a `use` circle, which rustc refuses).
const DEPTH: usize = 24;

fn module<'a>(cs: &'a CrateSource, m: &[String]) -> Option<&'a Module> {
    cs.modules.get(m)
}

/// The module where `path`, written in `scope`, ends; `complete` when every segment named a module.
/// `None` when the path is not into this crate (std, another crate, a local type).
fn resolve(cs: &CrateSource, scope: &[String], path: &[String], depth: usize) -> Option<(Vec<String>, bool)> {
    if depth == 0 || path.is_empty() {
        return None;
    }
    let mut m: Vec<String>;
    let mut i = 0;
    match path[0].as_str() {
        "crate" => {
            m = Vec::new();
            i = 1;
        }
        "self" => {
            m = scope.to_vec();
            i = 1;
        }
        "super" => {
            m = scope.to_vec();
            while i < path.len() && path[i] == "super" {
                m.pop();
                i += 1;
            }
        }
        first => {
            let here = module(cs, scope)?;
            if let Some(child) = here.children.get(first) {
                m = child.clone();
                i = 1;
            } else if let Some((_, target)) = here.uses.iter().find(|(a, _)| a.as_deref() == Some(first)) {
                if target.first().map(String::as_str) == Some(first) && target.len() == 1 {
                    return None; // `use foo;` of an external crate
                }
                let (t, complete) = resolve(cs, scope, target, depth - 1)?;
                if !complete {
                    return Some((t, false));
                }
                m = t;
                i = 1;
            } else {
                return None;
            }
        }
    }
    walk(cs, m, &path[i..], depth)
}

fn walk(cs: &CrateSource, mut m: Vec<String>, rest: &[String], depth: usize) -> Option<(Vec<String>, bool)> {
    for (k, seg) in rest.iter().enumerate() {
        if seg == "super" {
            m.pop();
            continue;
        }
        let Some(here) = module(cs, &m) else { return Some((m, false)) };
        if let Some(child) = here.children.get(seg) {
            m = child.clone();
            continue;
        }
        if here.items.iter().any(|x| x == seg) {
            return Some((m, false));
        }
        if let Some((_, target)) = here.uses.iter().find(|(a, _)| a.as_deref() == Some(seg.as_str())) {
            return match resolve(cs, &m, target, depth - 1) {
                Some((t, true)) => walk(cs, t, &rest[k + 1..], depth - 1),
                Some(found) => Some(found),
                None => Some((m, false)),
            };
        }
        for (_, glob) in here.uses.iter().filter(|(a, _)| a.is_none()) {
            if let Some((g, true)) = resolve(cs, &m, glob, depth - 1) {
                if let Some(gm) = module(cs, &g) {
                    let has = gm.children.contains_key(seg) || gm.items.iter().any(|x| x == seg) || gm.uses.iter().any(|(a, _)| a.as_deref() == Some(seg.as_str()));
                    if has {
                        return walk(cs, g, &rest[k..], depth - 1);
                    }
                }
            }
        }
        return Some((m, false));
    }
    Some((m, true))
}

/// Every circle of the crate's file graph.
pub fn cycles(cs: &CrateSource) -> Vec<Cycle> {
    let mut edges: BTreeMap<PathBuf, Vec<Edge>> = BTreeMap::new();
    for r in &cs.references {
        let Some((target, complete)) = resolve(cs, &r.scope, &r.path, DEPTH) else { continue };
        // `use a::b;` of a module depends on nothing by itself: each path through it (`b::x`) is
        // an edge to where `x` is defined. A glob brings names in unseen, so it is an edge.
        if complete && r.kind == RefKind::Use {
            continue;
        }
        let Some(to) = module(cs, &target).map(|m| m.file.clone()) else { continue };
        if to == r.file || to.as_os_str().is_empty() {
            continue;
        }
        edges.entry(r.file.clone()).or_default().push(Edge { from: r.file.clone(), line: r.line, written: r.path.join("::"), to });
    }
    let nodes: BTreeSet<PathBuf> = cs.modules.values().map(|m| m.file.clone()).collect();
    let succ: BTreeMap<&PathBuf, BTreeSet<&PathBuf>> = edges.iter().map(|(f, es)| (f, es.iter().map(|e| &e.to).collect())).collect();
    let sccs = tarjan(&nodes, &succ);
    sccs.into_iter()
        .filter(|c| c.len() > 1)
        .map(|files| {
            let set: BTreeSet<&PathBuf> = files.iter().collect();
            let mut inside: Vec<Edge> = files.iter().flat_map(|f| edges.get(f).into_iter().flatten()).filter(|e| set.contains(&e.to)).cloned().collect();
            inside.sort_by(|a, b| (&a.from, &a.to, a.line).cmp(&(&b.from, &b.to, b.line)));
            inside.dedup_by(|a, b| a.from == b.from && a.line == b.line && a.to == b.to);
            let mut files = files;
            files.sort();
            Cycle { files, edges: inside }
        })
        .collect()
}

/// Strongly connected components (Tarjan, iterative).
fn tarjan(nodes: &BTreeSet<PathBuf>, succ: &BTreeMap<&PathBuf, BTreeSet<&PathBuf>>) -> Vec<Vec<PathBuf>> {
    let list: Vec<&PathBuf> = nodes.iter().collect();
    let index_of: BTreeMap<&PathBuf, usize> = list.iter().enumerate().map(|(i, p)| (*p, i)).collect();
    let adj: Vec<Vec<usize>> = list.iter().map(|p| succ.get(p).into_iter().flatten().filter_map(|q| index_of.get(q).copied()).collect()).collect();
    let n = list.len();
    let (mut index, mut low, mut on) = (vec![usize::MAX; n], vec![0; n], vec![false; n]);
    let (mut stack, mut out, mut next) = (Vec::new(), Vec::new(), 0);
    for start in 0..n {
        if index[start] != usize::MAX {
            continue;
        }
        let mut call: Vec<(usize, usize)> = vec![(start, 0)];
        index[start] = next;
        low[start] = next;
        next += 1;
        stack.push(start);
        on[start] = true;
        while let Some(&mut (v, ref mut k)) = call.last_mut() {
            if *k < adj[v].len() {
                let w = adj[v][*k];
                *k += 1;
                if index[w] == usize::MAX {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on[w] = true;
                    call.push((w, 0));
                } else if on[w] {
                    low[v] = low[v].min(index[w]);
                }
            } else {
                call.pop();
                if let Some(&(u, _)) = call.last() {
                    low[u] = low[u].min(low[v]);
                }
                if low[v] == index[v] {
                    let mut comp = Vec::new();
                    while let Some(w) = stack.pop() {
                        on[w] = false;
                        comp.push(list[w].clone());
                        if w == v {
                            break;
                        }
                    }
                    out.push(comp);
                }
            }
        }
    }
    out
}
