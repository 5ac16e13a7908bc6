//! The library's top-level modules (`scene`, `render`, `image_io`, `mesh`,
//! `vk`, ...) stand in layers: no module imports one that imports it back,
//! directly or through a longer circle. Every file under `src/` that the
//! library compiles is read as text (the binary's `main.rs` and `cli/` sit
//! on top of everything and are left out), its comments dropped, and every
//! `crate::NAME` path in its code counts as an import of module `NAME`,
//! grouped ones (`use crate::{scene::Scene, vk}`) included. Needs no GPU.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Who imports whom: importer -> imported -> the files that do it.
type Imports = BTreeMap<String, BTreeMap<String, BTreeSet<String>>>;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file under `dir`, in a stable order.
fn rust_files(dir: &Path, found: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a readable folder entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            rust_files(&path, found);
        } else if path.extension().is_some_and(|ext| ext == "rs") {
            found.push(path);
        }
    }
}

/// `text` without its comments (line, doc and block comments): a name in
/// a comment or a doc link is no import. String literals are kept whole,
/// so a `//` inside one does not cut the line.
fn without_comments(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut in_string = false;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if in_string {
            out.push(c);
            if c == '\\' {
                if let Some(n) = next {
                    out.push(n);
                    i += 1;
                }
            } else if c == '"' {
                in_string = false;
            }
            i += 1;
        } else if c == 'r' && matches!(next, Some('#' | '"')) && !(i > 0 && is_ident(chars[i - 1]))
        {
            // A raw string (r"..." or r#"..."#) ends only at a quote
            // followed by as many hashes as it opened with.
            let hashes = chars[i + 1..].iter().take_while(|&&c| c == '#').count();
            if chars.get(i + 1 + hashes) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            let start = i;
            i += 2 + hashes;
            while i < chars.len() {
                if chars[i] == '"'
                    && chars[i + 1..].iter().take_while(|&&c| c == '#').count() >= hashes
                {
                    i += 1 + hashes;
                    break;
                }
                i += 1;
            }
            out.extend(&chars[start..i.min(chars.len())]);
        } else if c == '"' {
            in_string = true;
            out.push(c);
            i += 1;
        } else if c == '\'' && next == Some('"') && chars.get(i + 2) == Some(&'\'') {
            // The character literal '"' opens no string.
            out.push_str("'\"'");
            i += 3;
        } else if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The first segment of each path inside the group that starts at
/// `group` (just after `{`): `a::b, c, d::{e, f}` gives a, c and d.
fn group_heads(group: &str) -> Vec<String> {
    let mut heads = Vec::new();
    let mut depth = 0;
    let mut at_item_start = true;
    let mut chars = group.char_indices().peekable();
    while let Some((at, c)) = chars.next() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => at_item_start = true,
            c if is_ident(c) && at_item_start && depth == 0 => {
                let name: String = group[at..].chars().take_while(|&c| is_ident(c)).collect();
                for _ in 1..name.chars().count() {
                    chars.next();
                }
                heads.push(name);
                at_item_start = false;
            }
            _ => {}
        }
    }
    heads
}

/// The top-level modules a file's code names through `crate::`.
fn imported_modules(code: &str) -> BTreeSet<String> {
    let mut modules = BTreeSet::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        // `$crate::` and `my_crate::` are other paths.
        let before = rest[..at].chars().next_back();
        let after = &rest[at + "crate::".len()..];
        rest = after;
        if before.is_some_and(|c| is_ident(c) || c == '$') {
            continue;
        }
        if let Some(group) = after.strip_prefix('{') {
            modules.extend(group_heads(group));
        } else {
            let name: String = after.chars().take_while(|&c| is_ident(c)).collect();
            if !name.is_empty() {
                modules.insert(name);
            }
        }
    }
    modules
}

/// The library's top-level module a file under `src/` belongs to, or
/// `None` for the crate root and the binary (`main.rs`, `cli/`).
fn module_of(relative: &Path) -> Option<String> {
    let first = relative.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    match name {
        "lib" | "main" | "cli" => None,
        _ => Some(name.to_owned()),
    }
}

fn imports() -> Imports {
    let root = src();
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    let mut imports = Imports::new();
    for path in files {
        let relative = path.strip_prefix(&root).unwrap().to_path_buf();
        let Some(module) = module_of(&relative) else {
            continue;
        };
        let text = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        for imported in imported_modules(&without_comments(&text)) {
            if imported != module {
                imports
                    .entry(module.clone())
                    .or_default()
                    .entry(imported)
                    .or_default()
                    .insert(format!("src/{}", relative.display()));
            }
        }
    }
    imports
}

/// Every module `from` reaches through one import or more.
fn reachable(imports: &Imports, from: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.to_owned()];
    while let Some(module) = stack.pop() {
        for next in imports.get(&module).into_iter().flat_map(|m| m.keys()) {
            if seen.insert(next.clone()) {
                stack.push(next.clone());
            }
        }
    }
    seen
}

/// The circles of `imports`: each a set of modules that all reach one
/// another, with the imports between them ("a -> b (files)").
fn circles(imports: &Imports) -> Vec<(BTreeSet<String>, Vec<String>)> {
    let reach: BTreeMap<&String, BTreeSet<String>> = imports
        .keys()
        .map(|module| (module, reachable(imports, module)))
        .collect();
    let mut circles: Vec<(BTreeSet<String>, Vec<String>)> = Vec::new();
    for (module, reached) in &reach {
        if !reached.contains(*module) || circles.iter().any(|(c, _)| c.contains(*module)) {
            continue;
        }
        let members: BTreeSet<String> = reached
            .iter()
            .filter(|other| reach.get(other).is_some_and(|r| r.contains(*module)))
            .cloned()
            .collect();
        let mut edges = Vec::new();
        for from in &members {
            for (to, files) in &imports[from] {
                if members.contains(to) {
                    let files: Vec<&str> = files.iter().map(String::as_str).collect();
                    edges.push(format!("{from} -> {to} ({})", files.join(", ")));
                }
            }
        }
        circles.push((members, edges));
    }
    circles
}

#[test]
fn no_module_imports_one_that_imports_it_back() {
    let imports = imports();
    // The reader itself: the layers it finds are the ones the crate has.
    assert!(
        imports.get("render").is_some_and(|m| m.contains_key("vk")),
        "render's imports of vk were not found: {imports:?}"
    );
    let circles = circles(&imports);
    let report: Vec<String> = circles
        .iter()
        .map(|(members, edges)| {
            let names: Vec<&str> = members.iter().map(String::as_str).collect();
            format!(
                "{} import each other:\n    {}",
                names.join(", "),
                edges.join("\n    ")
            )
        })
        .collect();
    assert!(
        circles.is_empty(),
        "top-level modules in a circle (move what the lower one needs down, \
         or pass it in):\n{}",
        report.join("\n")
    );
}

#[test]
fn imports_are_read_from_code_and_groups_not_comments() {
    let code = without_comments(
        "use crate::{scene::Scene, vk::{self, Context}, budget};\n\
         // crate::render in a comment\n\
         /// [`crate::report`] in a doc link\n\
         let s = \"// not a comment\"; crate::mesh::Mesh::default();\n\
         let t = r#\"a \"quote\" // in a raw string\"#; crate::files::read_text;\n\
         /* crate::sweep */ $crate::viewer",
    );
    let found: Vec<String> = imported_modules(&code).into_iter().collect();
    assert_eq!(found, ["budget", "files", "mesh", "scene", "vk"]);
    let mut imports = Imports::new();
    for (from, to) in [("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")] {
        imports
            .entry(from.into())
            .or_default()
            .entry(to.into())
            .or_default()
            .insert(format!("src/{from}.rs"));
    }
    let found = circles(&imports);
    assert_eq!(found.len(), 1);
    assert_eq!(
        found[0].0,
        BTreeSet::from(["a".into(), "b".into(), "c".into()])
    );
}
