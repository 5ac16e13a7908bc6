//! No function in `src/` or the build script (`build/`) is over [`MAX_LINES`] lines, counted from the line
//! of its `fn` to the line of its closing brace: a longer one is split into
//! named steps. Free functions, methods and nested functions all count;
//! `#[cfg(test)]` items and files named `tests.rs` do not. Generated code
//! (the shaders `include!`d from `OUT_DIR`) is not under `src/`, so it is
//! never read. Needs no GPU.
//!
//! The scanner is deliberately small: it skips comments, string, byte,
//! raw-string and char literals (telling a char literal from a lifetime),
//! so a brace or a `fn` inside them is never counted, and matches braces.

use std::fs;
use std::path::{Path, PathBuf};

const MAX_LINES: usize = 120;

/// One function found in a file.
#[derive(Debug, PartialEq)]
struct Function {
    name: String,
    /// 1-based line of the `fn` keyword.
    line: usize,
    /// Lines from the `fn` line to the closing brace's, both included.
    lines: usize,
}

/// The source with every comment and literal blanked out (newlines kept,
/// so line numbers hold), leaving only code for the brace and `fn` search.
fn code_only(source: &str) -> Vec<char> {
    let chars: Vec<char> = source.chars().collect();
    let mut code = Vec::with_capacity(chars.len());
    let mut i = 0;
    // Blanks `chars[from..to]` into `code`, keeping its newlines.
    let blank = |code: &mut Vec<char>, from: usize, to: usize| {
        for &c in &chars[from..to.min(chars.len())] {
            code.push(if c == '\n' { '\n' } else { ' ' });
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        let end = if c == '/' && next == Some('/') {
            chars[i..]
                .iter()
                .position(|&c| c == '\n')
                .map_or(chars.len(), |n| i + n)
        } else if c == '/' && next == Some('*') {
            block_comment_end(&chars, i)
        } else if let Some(end) = raw_string_end(&chars, i) {
            end
        } else if c == '"' || (c == 'b' && next == Some('"') && !ident_before(&chars, i)) {
            quoted_end(&chars, if c == 'b' { i + 1 } else { i }, '"')
        } else if c == '\'' {
            char_literal_end(&chars, i).unwrap_or(i + 1)
        } else {
            code.push(c);
            i += 1;
            continue;
        };
        blank(&mut code, i, end);
        i = end;
    }
    code
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

fn ident_before(chars: &[char], i: usize) -> bool {
    i > 0 && is_ident(chars[i - 1])
}

/// The index past a (nested) block comment starting at `start`.
fn block_comment_end(chars: &[char], start: usize) -> usize {
    let mut depth = 0;
    let mut i = start;
    while i + 1 < chars.len() {
        match (chars[i], chars[i + 1]) {
            ('/', '*') => {
                depth += 1;
                i += 2;
            }
            ('*', '/') => {
                depth -= 1;
                i += 2;
                if depth == 0 {
                    return i;
                }
            }
            _ => i += 1,
        }
    }
    chars.len()
}

/// The index past a literal opened by `quote` at `start`, honouring escapes.
fn quoted_end(chars: &[char], start: usize, quote: char) -> usize {
    let mut i = start + 1;
    while i < chars.len() {
        match chars[i] {
            '\\' => i += 2,
            c if c == quote => return i + 1,
            _ => i += 1,
        }
    }
    chars.len()
}

/// The index past a raw string (`r"…"`, `r#"…"#`, `br#"…"#`) starting at
/// `start`, or `None` if none starts there.
fn raw_string_end(chars: &[char], start: usize) -> Option<usize> {
    if ident_before(chars, start) {
        return None;
    }
    let mut i = start;
    if chars.get(i) == Some(&'b') {
        i += 1;
    }
    if chars.get(i) != Some(&'r') {
        return None;
    }
    i += 1;
    let hashes = chars[i..].iter().take_while(|&&c| c == '#').count();
    i += hashes;
    if chars.get(i) != Some(&'"') {
        return None;
    }
    i += 1;
    while i < chars.len() {
        if chars[i] == '"'
            && chars[i + 1..]
                .iter()
                .take(hashes)
                .filter(|&&c| c == '#')
                .count()
                == hashes
        {
            return Some(i + 1 + hashes);
        }
        i += 1;
    }
    Some(chars.len())
}

/// The index past a char literal at `start` (`'a'`, `'\n'`, `'\u{..}'`), or
/// `None` for a lifetime or label (`'a`, `'static`).
fn char_literal_end(chars: &[char], start: usize) -> Option<usize> {
    match chars.get(start + 1)? {
        '\\' => Some(quoted_end(chars, start, '\'')),
        _ if chars.get(start + 2) == Some(&'\'') => Some(start + 3),
        _ => None,
    }
}

/// The index of the brace closing the one at `open` in blanked code.
fn matching_brace(code: &[char], open: usize) -> usize {
    let mut depth = 0;
    for (i, &c) in code.iter().enumerate().skip(open) {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return i;
                }
            }
            _ => {}
        }
    }
    code.len() - 1
}

/// The word (identifier or keyword) starting at `i`, if one starts there.
fn word_at(code: &[char], i: usize) -> Option<String> {
    if ident_before(code, i) || !code.get(i).copied().is_some_and(is_ident) {
        return None;
    }
    Some(code[i..].iter().take_while(|&&c| is_ident(c)).collect())
}

/// The index of the first `{` or `;` from `i` on: where the item beginning
/// at `i` opens its body, or ends without one.
fn item_body(code: &[char], i: usize) -> Option<usize> {
    (i..code.len()).find(|&j| code[j] == '{' || code[j] == ';')
}

/// Every function of a file's source, outside `#[cfg(test)]` items.
fn functions(source: &str) -> Vec<Function> {
    let code = code_only(source);
    let line_of = |index: usize| code[..index].iter().filter(|&&c| c == '\n').count() + 1;
    let mut found = Vec::new();
    let mut i = 0;
    while i < code.len() {
        let rest: String = code[i..(i + 12).min(code.len())].iter().collect();
        if rest.starts_with("#[cfg(test)]") {
            // The item it guards (a test module, a test-only function) is
            // skipped whole.
            match item_body(&code, i + 12) {
                Some(j) if code[j] == '{' => i = matching_brace(&code, j) + 1,
                Some(j) => i = j + 1,
                None => break,
            }
            continue;
        }
        if word_at(&code, i).as_deref() == Some("fn") {
            let after: usize = i
                + 2
                + code[i + 2..]
                    .iter()
                    .take_while(|c| c.is_whitespace())
                    .count();
            // `fn(u32) -> u32` is a pointer type, `fn $name` a macro's.
            if let Some(name) = word_at(&code, after) {
                if let Some(open) = item_body(&code, after).filter(|&j| code[j] == '{') {
                    let line = line_of(i);
                    found.push(Function {
                        name,
                        line,
                        lines: line_of(matching_brace(&code, open)) - line + 1,
                    });
                }
            }
            i += 2;
            continue;
        }
        i += 1;
    }
    found
}

/// Every `.rs` file under `dir`, but files named `tests.rs`.
fn sources(dir: &Path, files: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("readable source directory") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            sources(&path, files);
        } else if path.extension().is_some_and(|ext| ext == "rs")
            && path.file_name().is_some_and(|name| name != "tests.rs")
        {
            files.push(path);
        }
    }
}

#[test]
fn no_function_is_over_the_limit() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for folder in ["src", "build"] {
        sources(&root.join(folder), &mut files);
    }
    files.sort();
    let mut too_long = Vec::new();
    for path in &files {
        let shown = path
            .strip_prefix(&root)
            .unwrap()
            .to_string_lossy()
            .replace('\\', "/");
        let source = fs::read_to_string(path).expect("readable source");
        for f in functions(&source) {
            if f.lines > MAX_LINES {
                too_long.push(format!(
                    "{shown}:{} fn {} ({} lines)",
                    f.line, f.name, f.lines
                ));
            }
        }
    }
    assert!(
        too_long.is_empty(),
        "functions over {MAX_LINES} lines; split them into named steps:\n{}",
        too_long.join("\n")
    );
}

#[test]
fn the_scanner_skips_literals_comments_and_test_modules() {
    let source = r##"
fn a() {
    let s = "}"; let c = '}'; let r = r#"}"#;
    // }
    /* } /* } */ } */
    fn nested<'a>(x: &'a str) -> &'a str {
        x
    }
}
type F = fn(u32) -> u32;
trait T { fn declared(&self); }
#[cfg(test)]
mod tests {
    fn hidden() {}
}
fn b() {}
"##;
    let found = functions(source);
    let summary: Vec<(&str, usize, usize)> = found
        .iter()
        .map(|f| (f.name.as_str(), f.line, f.lines))
        .collect();
    assert_eq!(summary, [("a", 2, 8), ("nested", 6, 3), ("b", 16, 1)]);
}
