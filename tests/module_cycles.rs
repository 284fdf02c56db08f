//! The crate's modules import one another without a cycle, so that lower layers never lean on
//! upper ones (docs/architecture.md). GPU-free: it reads src/ as text.
//!
//! A node is a public module (a file); a module declared private (`mod x;`) is part of its
//! parent, so the glob imports between a folder's private files and its `mod.rs` are one idea
//! talking to itself. An edge is any path the file names: `crate::a::b`, `super::x`, `self::x`,
//! or a path starting with one of its own child modules (`upload::VersionDraw`, `pub use
//! eval::FrameSky`), each taken to the longest module it names. A re-export counts: importing
//! `super::Rgba` from a folder whose `mod.rs` re-exports `eval::*` leans on all it re-exports.
//! Tests (`#[cfg(test)] mod tests` to the end of a file, and `tests.rs` files) are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

type Module = Vec<String>;

/// A module's source without comments, string literals and its tests.
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if !escaped && c == '"' {
                        break;
                    }
                    escaped = !escaped && c == '\\';
                }
                out.push_str("\"\"");
            }
            // A char literal such as '"' must not open a string; lifetimes pass through.
            '\'' => {
                let ahead: String = chars.clone().take(3).collect();
                if ahead.starts_with("\\") || ahead.chars().nth(1) == Some('\'') {
                    for c in chars.by_ref() {
                        if c == '\'' {
                            break;
                        }
                    }
                    out.push_str("' '");
                } else {
                    out.push(c);
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// Every module file under `src` by its path from the crate root, with its code and its child
/// modules (name, public).
fn modules(src: &Path) -> BTreeMap<Module, (String, Vec<(String, bool)>)> {
    fn walk(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).expect("reading src/") {
            let path = entry.expect("an entry").path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let mut files = Vec::new();
    walk(src, &mut files);
    files
        .into_iter()
        // The binary and the crate's test modules in files of their own are not its layers.
        .filter(|p| p.file_name().is_some_and(|n| n != "main.rs" && n != "tests.rs"))
        .map(|p| {
            let rel = p.strip_prefix(src).expect("under src/").with_extension("");
            let mut m: Module = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
            if m.last().is_some_and(|l| l == "mod" || l == "lib") {
                m.pop();
            }
            let code = code_of(&std::fs::read_to_string(&p).expect("reading a module"));
            let children = declared_modules(&code);
            (m, (code, children))
        })
        .collect()
}

/// The modules a file declares (`mod x;`, `pub mod x;`, `pub(crate) mod x;`): name and whether it
/// is public.
fn declared_modules(code: &str) -> Vec<(String, bool)> {
    let mut out = Vec::new();
    for line in code.lines() {
        let line = line.trim();
        let Some(decl) = line.strip_suffix(';') else { continue };
        let (public, rest) = match decl.strip_prefix("pub ").or_else(|| decl.strip_prefix("pub(crate) ")) {
            Some(rest) => (true, rest),
            None => (false, decl),
        };
        if let Some(name) = rest.strip_prefix("mod ") {
            if name.chars().all(|c| c.is_alphanumeric() || c == '_') {
                out.push((name.to_string(), public));
            }
        }
    }
    out
}

/// The paths a module's code names: runs of `ident::ident::...` (with `{` groups opened one
/// level: `self::{a::x, b::y}` names `self::a` and `self::b`).
fn paths(code: &str) -> Vec<Vec<String>> {
    let bytes: Vec<char> = code.chars().collect();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if !ident(bytes[i]) || (i > 0 && (ident(bytes[i - 1]) || bytes[i - 1] == ':')) {
            i += 1;
            continue;
        }
        let mut segs = Vec::new();
        let mut j = i;
        loop {
            let start = j;
            while j < bytes.len() && ident(bytes[j]) {
                j += 1;
            }
            segs.push(bytes[start..j].iter().collect::<String>());
            if j + 2 < bytes.len() && bytes[j] == ':' && bytes[j + 1] == ':' && (ident(bytes[j + 2]) || bytes[j + 2] == '{') {
                j += 2;
                if bytes[j] == '{' {
                    // One level of a use group: its members split at the group's own commas, each
                    // taken to its first segment (`a` of `a::{x, y}` and of `a::x as y`).
                    let (mut depth, mut k, mut member, mut members) = (0, j + 1, String::new(), Vec::new());
                    while k < bytes.len() && !(bytes[k] == '}' && depth == 0) {
                        match bytes[k] {
                            '{' => depth += 1,
                            '}' => depth -= 1,
                            ',' if depth == 0 => members.push(std::mem::take(&mut member)),
                            c if depth == 0 => member.push(c),
                            _ => {}
                        }
                        k += 1;
                    }
                    members.push(member);
                    for m in &members {
                        let first = m.trim().split("::").next().unwrap_or("").trim();
                        if !first.is_empty() {
                            out.push(segs.iter().cloned().chain([first.to_string()]).collect());
                        }
                    }
                    j = k;
                    break;
                }
                continue;
            }
            break;
        }
        if segs.len() > 1 {
            out.push(segs);
        }
        i = j.max(i + 1);
    }
    out
}

#[test]
fn no_module_imports_lead_back_to_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mods = modules(&src);
    // Private modules are part of their parent: the node of a module is its nearest ancestor (or
    // itself) that every step down to declares public.
    let public = |m: &Module| -> bool {
        let Some((name, parent)) = m.split_last() else { return true };
        mods.get(parent).is_some_and(|(_, children)| children.iter().any(|(c, p)| c == name && *p))
    };
    let node = |m: &Module| -> Module {
        let mut n = m.clone();
        let mut at = m.clone();
        while !at.is_empty() {
            if !public(&at) {
                n = at[..at.len() - 1].to_vec();
            }
            at.pop();
        }
        n
    };
    let longest = |path: &[String]| -> Option<Module> { (1..=path.len()).rev().map(|n| path[..n].to_vec()).find(|m| mods.contains_key(m)) };
    let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (m, (code, children)) in &mods {
        let from = node(m);
        for p in paths(code) {
            let target = match p[0].as_str() {
                "crate" => longest(&p[1..]),
                "self" => longest(&m.iter().cloned().chain(p[1..].iter().cloned()).collect::<Vec<_>>()),
                "super" => {
                    let mut base = m[..m.len().saturating_sub(1)].to_vec();
                    let mut rest = &p[1..];
                    while rest.first().is_some_and(|s| s == "super") {
                        base.pop();
                        rest = &rest[1..];
                    }
                    longest(&base.iter().cloned().chain(rest.iter().cloned()).collect::<Vec<_>>()).or(Some(base))
                }
                first if children.iter().any(|(c, _)| c == first) => longest(&m.iter().cloned().chain(p.iter().cloned()).collect::<Vec<_>>()),
                _ => None,
            };
            if let Some(t) = target.map(|t| node(&t)) {
                if t != from {
                    edges.entry(from.clone()).or_default().insert(t);
                }
            }
        }
    }
    // Tarjan's strongly connected components.
    let nodes: Vec<Module> = mods.keys().map(&node).collect::<BTreeSet<_>>().into_iter().collect();
    let index_of: BTreeMap<&Module, usize> = nodes.iter().enumerate().map(|(i, m)| (m, i)).collect();
    let adj: Vec<Vec<usize>> = nodes.iter().map(|m| edges.get(m).map_or(Vec::new(), |s| s.iter().filter_map(|t| index_of.get(t).copied()).collect())).collect();
    let n = nodes.len();
    let (mut index, mut low, mut on, mut stack, mut next, mut sccs) = (vec![usize::MAX; n], vec![0; n], vec![false; n], Vec::new(), 0, Vec::new());
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        // Iterative DFS: (node, next neighbour to visit).
        let mut work = vec![(root, 0usize)];
        while let Some(&mut (v, ref mut k)) = work.last_mut() {
            if *k == 0 && index[v] == usize::MAX {
                index[v] = next;
                low[v] = next;
                next += 1;
                stack.push(v);
                on[v] = true;
            }
            if *k < adj[v].len() {
                let w = adj[v][*k];
                *k += 1;
                if index[w] == usize::MAX {
                    work.push((w, 0));
                } else if on[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            work.pop();
            if let Some(&(parent, _)) = work.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut scc = Vec::new();
                while let Some(w) = stack.pop() {
                    on[w] = false;
                    scc.push(nodes[w].join("::"));
                    if w == v {
                        break;
                    }
                }
                if scc.len() > 1 {
                    scc.sort();
                    sccs.push(scc);
                }
            }
        }
    }
    assert!(sccs.is_empty(), "modules whose imports lead back to them (each set one cycle):\n{sccs:#?}");
    // The scan sees the edges it should: the renderer's use of the pass registry, the plan's of
    // its words.
    let edge = |a: &str, b: &str| edges.get(&a.split("::").map(String::from).collect::<Module>()).is_some_and(|e| e.contains(&b.split("::").map(String::from).collect::<Module>()));
    assert!(edge("render::frame::renderer", "render::passes") && edge("render::plan", "render::plan::items"), "the scanner lost known imports");
}
