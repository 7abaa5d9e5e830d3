//! The workspace's structure, checked: inside every crate, the files import each other without a cycle.
//!
//! A file depends on another when it names an item defined there: through `use crate::…`, `super::…`,
//! `self::…` or a child module, or a path like that written in its code (`crate::a::f()`, `child::f()`). A re-export (`pub use`) is a
//! facade, not a dependency: an import is followed through it to the file that defines the item. Tests
//! (`#[cfg(test)] mod …` blocks and `tests.rs` files) and binaries (`src/bin/`) are left out; a crate's
//! `main.rs` beside a `lib.rs` is a binary too.
//!
//! `cargo test -p heist_tests --test structure -- --nocapture` prints every crate's files and their
//! dependencies counted, and any cycle found with the imports that make it.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

/// A module's path inside its crate (`["net", "tokens"]`); the crate root is empty.
type ModPath = Vec<String>;

/// What the checker needs of one module file.
#[derive(Default)]
struct Module {
    file: PathBuf,
    /// Names of the items it defines.
    defs: HashSet<String>,
    /// Names it re-exports (`pub use`), with the path each stands for.
    reexports: HashMap<String, Vec<String>>,
    /// Modules whose items it re-exports all (`pub use x::*`).
    globs: Vec<Vec<String>>,
    /// Every path it names into its own crate (not counting re-exports), as written.
    uses: Vec<Vec<String>>,
}

/// Every crate of the workspace: a folder with a `Cargo.toml` and a `src/`.
fn crates(root: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        if dir.join("Cargo.toml").is_file() && dir.join("src").is_dir() {
            found.push(dir.clone());
        }
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() && !matches!(name.as_str(), "target" | "fuzz" | "node_modules") && !name.starts_with('.') {
                stack.push(path);
            }
        }
    }
    found.sort();
    found
}

/// The crate's module files by module path.
fn module_files(src: &Path) -> BTreeMap<ModPath, PathBuf> {
    let has_lib = src.join("lib.rs").is_file();
    let mut mods = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let Some(rel) = path.strip_prefix(src).ok().and_then(|r| r.to_str()) else { continue };
            let Some(stem) = rel.strip_suffix(".rs") else { continue };
            let mut parts: Vec<String> = stem.split('/').map(str::to_owned).collect();
            let last = parts.last().map(String::as_str).unwrap_or_default();
            if parts[0] == "bin" || last == "tests" || (stem == "main" && has_lib) {
                continue;
            }
            if matches!(last, "mod" | "lib" | "main") {
                parts.pop();
            }
            mods.insert(parts, path);
        }
    }
    mods
}

/// The code of a file with comments removed and string and char literals emptied.
fn strip(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let ident = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    while i < b.len() {
        let c = b[i];
        if b[i..].starts_with(b"//") {
            i = text[i..].find('\n').map_or(b.len(), |j| i + j);
        } else if b[i..].starts_with(b"/*") {
            let (mut depth, mut j) = (1, i + 2);
            while j < b.len() && depth > 0 {
                if b[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if b[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            i = j;
        } else if c == b'r' && (i == 0 || !ident(b[i - 1])) && {
            let hashes = b[i + 1..].iter().take_while(|&&h| h == b'#').count();
            b.get(i + 1 + hashes) == Some(&b'"')
        } {
            let hashes = b[i + 1..].iter().take_while(|&&h| h == b'#').count();
            let end = format!("\"{}", "#".repeat(hashes));
            let from = i + 2 + hashes;
            i = text[from..].find(&end).map_or(b.len(), |j| from + j + end.len());
            out.push_str("\"\"");
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == b'\'' && b.get(i + 1) == Some(&b'\\') {
            i = text[i + 2..].find('\'').map_or(b.len(), |j| i + 2 + j + 1);
            out.push_str("' '");
        } else if c == b'\'' && b.get(i + 2) == Some(&b'\'') {
            i += 3;
            out.push_str("' '");
        } else {
            let len = text[i..].chars().next().map_or(1, char::len_utf8);
            out.push_str(&text[i..i + len]);
            i += len;
        }
    }
    out
}

/// The code outside test modules.
fn without_tests(code: &str) -> &str {
    let mut from = 0;
    while let Some(at) = code[from..].find("#[cfg(test)]").map(|j| from + j) {
        let rest = code[at + "#[cfg(test)]".len()..].trim_start();
        let rest = rest.strip_prefix("pub ").unwrap_or(rest).trim_start();
        if let Some(after) = rest.strip_prefix("mod ") {
            let name_end = after.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(after.len());
            if after[name_end..].trim_start().starts_with('{') {
                return &code[..at];
            }
        }
        from = at + 1;
    }
    code
}

/// The identifiers and punctuation of `code`, in order.
fn tokens(code: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < code.len() {
        let rest = &code[i..];
        let c = rest.chars().next().unwrap_or(' ');
        if c.is_alphanumeric() || c == '_' {
            let len = rest.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(rest.len());
            out.push(&rest[..len]);
            i += len;
        } else if rest.starts_with("::") {
            out.push("::");
            i += 2;
        } else {
            if !c.is_whitespace() {
                out.push(&rest[..c.len_utf8()]);
            }
            i += c.len_utf8();
        }
    }
    out
}

/// `a::{b, c::{d, e as f}}` as paths: `[a, b]`, `[a, c, d]`, `[a, c, e as f]` (an alias stays in its
/// last segment, as `e as f`).
fn expand(tree: &[&str]) -> Vec<Vec<String>> {
    let Some(open) = tree.iter().position(|t| *t == "{") else {
        let mut path: Vec<String> = Vec::new();
        let mut k = 0;
        while k < tree.len() {
            match tree[k] {
                "::" => {}
                "as" if k + 1 < tree.len() => {
                    if let Some(last) = path.last_mut() {
                        *last = format!("{last} as {}", tree[k + 1]);
                    }
                    k += 1;
                }
                t => path.push(t.to_owned()),
            }
            k += 1;
        }
        return if path.is_empty() { Vec::new() } else { vec![path] };
    };
    let prefix = &tree[..open];
    let close = tree.iter().rposition(|t| *t == "}").unwrap_or(tree.len());
    let body = &tree[open + 1..close.max(open + 1)];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (k, t) in body.iter().enumerate() {
        match *t {
            "{" => depth += 1,
            "}" => depth -= 1,
            "," if depth == 0 => {
                parts.push(&body[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&body[start..]);
    let mut out = Vec::new();
    for part in parts.into_iter().filter(|p| !p.is_empty()) {
        let joined: Vec<&str> = prefix.iter().copied().chain(part.iter().copied()).collect();
        out.extend(expand(&joined));
    }
    out
}

const DEF_KEYWORDS: [&str; 9] = ["struct", "enum", "fn", "const", "static", "trait", "type", "union", "mod"];
const PREFIXES: [&str; 3] = ["crate", "super", "self"];

impl Module {
    fn read(file: &Path, children: &HashSet<String>) -> Self {
        let text = std::fs::read_to_string(file).unwrap_or_default();
        let stripped = strip(&text);
        let toks = tokens(without_tests(&stripped));
        let mut m = Module { file: file.to_path_buf(), ..Default::default() };
        let mut k = 0;
        while k < toks.len() {
            let t = toks[k];
            if (DEF_KEYWORDS.contains(&t) || t == "macro_rules") && k + 1 < toks.len() {
                let name = if t == "macro_rules" { toks.get(k + 2) } else { toks.get(k + 1) };
                if let Some(name) = name {
                    m.defs.insert((*name).to_owned());
                }
            }
            if t == "use" {
                let public = is_visibility(&toks[..k]);
                let end = toks[k..].iter().position(|t| *t == ";").map_or(toks.len(), |j| k + j);
                for path in expand(&toks[k + 1..end]) {
                    m.add_use(path, public, children);
                }
                k = end;
            } else if (PREFIXES.contains(&t) || children.contains(t))
                && toks.get(k + 1) == Some(&"::")
                && (k == 0 || toks[k - 1] != "::")
                && !(k > 0 && toks[k - 1] == "use")
            {
                // `crate::a::b`, `super::b`, or a child module's path written in the code (`arc::f()`).
                let mut path =
                    if PREFIXES.contains(&t) { vec![t.to_owned()] } else { vec!["self".to_owned(), t.to_owned()] };
                let mut j = k + 1;
                while toks.get(j) == Some(&"::") && toks.get(j + 1).is_some_and(|s| is_ident(s)) {
                    path.push(toks[j + 1].to_owned());
                    j += 2;
                }
                m.uses.push(path);
                k = j;
                continue;
            }
            k += 1;
        }
        // A name it re-exports and also uses itself is a dependency too (`pub use child::T;` then `T` in
        // its own code): counted when the name appears outside `use` statements.
        let mut in_use = false;
        let mut named: HashSet<&str> = HashSet::new();
        for (k, t) in toks.iter().enumerate() {
            match *t {
                "use" => in_use = true,
                ";" => in_use = false,
                t if !in_use && (k == 0 || toks[k - 1] != "mod") => {
                    named.insert(t);
                }
                _ => {}
            }
        }
        let used: Vec<Vec<String>> =
            m.reexports.iter().filter(|(name, _)| named.contains(name.as_str())).map(|(_, p)| p.clone()).collect();
        m.uses.extend(used);
        m
    }

    fn add_use(&mut self, mut path: Vec<String>, public: bool, children: &HashSet<String>) {
        let Some(first) = path.first().cloned() else { return };
        if !PREFIXES.contains(&first.as_str()) {
            if !children.contains(&first) {
                return; // another crate
            }
            path.insert(0, "self".to_owned());
        }
        let last = path.pop().unwrap_or_default();
        let (item, name) = match last.split_once(" as ") {
            Some((item, alias)) => (item.to_owned(), alias.to_owned()),
            None => (last.clone(), last),
        };
        if item == "*" {
            if public {
                self.globs.push(path.clone());
            } else {
                self.uses.push(path);
            }
            return;
        }
        path.push(item);
        if public {
            self.reexports.insert(name, path);
        } else {
            self.uses.push(path);
        }
    }
}

fn is_ident(s: &str) -> bool {
    s.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// Whether the tokens before a `use` end with a visibility (`pub`, `pub(crate)`, `pub(super)`).
fn is_visibility(before: &[&str]) -> bool {
    matches!(before, [.., "pub"] | [.., "pub", "(", _, ")"])
}

/// One crate's modules and the resolution of its paths to the modules defining what they name.
struct Crate {
    mods: BTreeMap<ModPath, Module>,
}

impl Crate {
    fn read(src: &Path) -> Self {
        let files = module_files(src);
        let mut mods = BTreeMap::new();
        for (path, file) in &files {
            let children: HashSet<String> = files
                .keys()
                .filter(|p| p.len() == path.len() + 1 && p.starts_with(path))
                .map(|p| p[path.len()].clone())
                .collect();
            mods.insert(path.clone(), Module::read(file, &children));
        }
        Crate { mods }
    }

    /// Where a path starts (its `crate`, `self` and `super` segments applied) and what is left of it.
    fn base<'p>(&self, here: &[String], path: &'p [String]) -> (ModPath, &'p [String]) {
        let mut base = here.to_vec();
        let mut rest = path;
        match rest.first().map(String::as_str) {
            Some("crate") => {
                base.clear();
                rest = &rest[1..];
            }
            Some("self") => rest = &rest[1..],
            _ => {}
        }
        while rest.first().map(String::as_str) == Some("super") {
            base.pop();
            rest = &rest[1..];
        }
        (base, rest)
    }

    /// The module a path leads to, if it is a module path.
    fn module(&self, here: &[String], path: &[String]) -> Option<ModPath> {
        let (mut cur, rest) = self.base(here, path);
        for seg in rest {
            cur.push(seg.clone());
            if !self.mods.contains_key(&cur) {
                return None;
            }
        }
        self.mods.contains_key(&cur).then_some(cur)
    }

    /// The module defining what a path names, following re-exports.
    fn resolve(&self, here: &[String], path: &[String], depth: u32) -> Option<ModPath> {
        if depth > 16 {
            return None;
        }
        let (mut cur, rest) = self.base(here, path);
        let module = self.mods.get(&cur)?;
        let mut module = module;
        for seg in rest {
            let mut child = cur.clone();
            child.push(seg.clone());
            if let Some(m) = self.mods.get(&child) {
                cur = child;
                module = m;
                continue;
            }
            if module.defs.contains(seg) {
                return Some(cur);
            }
            if let Some(target) = module.reexports.get(seg) {
                return self.resolve(&cur, target, depth + 1).or(Some(cur));
            }
            for glob in &module.globs {
                if let Some(from) = self.module(&cur, glob) {
                    let m = &self.mods[&from];
                    if m.defs.contains(seg) || m.reexports.contains_key(seg) {
                        return self.resolve(&from, &["self".to_owned(), seg.clone()], depth + 1).or(Some(from));
                    }
                }
            }
            return Some(cur);
        }
        Some(cur)
    }

    /// Each module's dependencies: the modules defining what it names.
    fn edges(&self) -> BTreeMap<ModPath, BTreeMap<ModPath, String>> {
        let mut edges = BTreeMap::new();
        for (path, module) in &self.mods {
            let mut to: BTreeMap<ModPath, String> = BTreeMap::new();
            for used in &module.uses {
                if let Some(target) = self.resolve(path, used, 0)
                    && &target != path
                {
                    to.entry(target).or_insert_with(|| used.join("::"));
                }
            }
            edges.insert(path.clone(), to);
        }
        edges
    }
}

/// The strongly connected components of more than one module (Tarjan's algorithm).
fn cycles(edges: &BTreeMap<ModPath, BTreeMap<ModPath, String>>) -> Vec<Vec<ModPath>> {
    struct Walk<'a> {
        edges: &'a BTreeMap<ModPath, BTreeMap<ModPath, String>>,
        index: HashMap<&'a ModPath, usize>,
        low: HashMap<&'a ModPath, usize>,
        stack: Vec<&'a ModPath>,
        on_stack: HashSet<&'a ModPath>,
        found: Vec<Vec<ModPath>>,
    }
    impl<'a> Walk<'a> {
        fn visit(&mut self, v: &'a ModPath) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.edges[v].keys() {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let low = self.low[v].min(self.low[w]);
                    self.low.insert(v, low);
                } else if self.on_stack.contains(w) {
                    let low = self.low[v].min(self.index[w]);
                    self.low.insert(v, low);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    component.push(w.clone());
                    if w == v {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.found.push(component);
                }
            }
        }
    }
    let mut walk = Walk {
        edges,
        index: HashMap::new(),
        low: HashMap::new(),
        stack: Vec::new(),
        on_stack: HashSet::new(),
        found: Vec::new(),
    };
    for v in edges.keys() {
        if !walk.index.contains_key(v) {
            walk.visit(v);
        }
    }
    walk.found
}

fn name(path: &[String]) -> String {
    if path.is_empty() { "(root)".to_owned() } else { path.join("/") }
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("the tests crate sits in the workspace").to_path_buf()
}

#[test]
fn no_files_of_a_crate_import_each_other_in_a_cycle() {
    let root = workspace_root();
    let mut report = Vec::new();
    let mut checked = 0;
    for dir in crates(&root) {
        let krate = Crate::read(&dir.join("src"));
        let edges = krate.edges();
        let crate_name = dir.strip_prefix(&root).unwrap_or(&dir).display().to_string();
        let deps: usize = edges.values().map(BTreeMap::len).sum();
        println!("{crate_name}: {} files, {deps} file dependencies", krate.mods.len());
        checked += krate.mods.len();
        for cycle in cycles(&edges) {
            let members: BTreeSet<&ModPath> = cycle.iter().collect();
            let mut line = format!(
                "{crate_name}: {} files import each other: {}",
                cycle.len(),
                cycle.iter().map(|p| name(p)).collect::<Vec<_>>().join(", ")
            );
            for from in &cycle {
                for (to, via) in &edges[from] {
                    if members.contains(to) {
                        line.push_str(&format!("\n    {} -> {} ({via})", krate.mods[from].file.display(), name(to)));
                    }
                }
            }
            report.push(line);
        }
    }
    assert!(checked > 100, "only {checked} files found under {}", root.display());
    assert!(
        report.is_empty(),
        "import cycles between files (break each by moving what both need below both):\n{}",
        report.join("\n")
    );
}

/// The checker itself: a cycle through a re-export is found, a re-export alone is no dependency, and
/// comments and strings name nothing.
#[test]
fn the_checker_follows_re_exports_and_ignores_comments_and_strings() {
    let dir = std::env::temp_dir().join(format!("structure-check-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).expect("temp dir");
    let write = |p: &str, text: &str| std::fs::write(src.join(p), text).expect("write");
    write("lib.rs", "mod a;\nmod b;\npub use a::Thing;\n// use crate::c::X;\nconst S: &str = \"crate::b::Y\";\n");
    write("a/mod.rs", "mod inner;\npub use inner::Thing;\nfn f() { let _ = crate::b::other(); }\n");
    write("a/inner.rs", "pub struct Thing;\n");
    write("b.rs", "use crate::Thing;\npub fn other() {}\n");
    let krate = Crate::read(&src);
    let edges = krate.edges();
    let key = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert!(edges[&key(&[])].is_empty(), "a re-export and a comment are no dependencies: {:?}", edges[&key(&[])]);
    assert_eq!(edges[&key(&["b"])].keys().collect::<Vec<_>>(), [&key(&["a", "inner"])], "followed to the definition");
    assert!(cycles(&edges).is_empty());
    write("a/inner.rs", "pub struct Thing;\nfn g() { super::super::b::other(); }\n");
    let cycle = cycles(&Crate::read(&src).edges());
    assert_eq!(cycle, [vec![key(&["a", "inner"]), key(&["b"])]], "b -> a/inner -> b");
    let _ = std::fs::remove_dir_all(&dir);
}
