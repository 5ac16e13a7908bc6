//! The documentation's links hold: every relative link in `README.md` and
//! `docs/*.md` points at a file that exists, and every `#anchor` names a
//! heading of its target (GitHub's heading ids). The README stays a short
//! entry point. Needs no GPU.

use std::collections::HashSet;
use std::fs;
use std::path::{Path, PathBuf};

const README_MAX_LINES: usize = 350;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A path as the repository names it.
fn shown(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// `README.md` and every `docs/*.md`.
fn documents() -> Vec<PathBuf> {
    let mut docs = vec![root().join("README.md")];
    let mut pages: Vec<PathBuf> = fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|entry| entry.expect("docs/ entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "md"))
        .collect();
    pages.sort();
    docs.extend(pages);
    docs
}

/// Lines outside fenced code blocks (```), with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut in_fence = false;
    let mut lines = Vec::new();
    for (index, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if !in_fence {
            lines.push((index + 1, line));
        }
    }
    lines
}

/// GitHub's id for a heading's text: lowercase; letters, digits, `-`, `_`
/// and spaces kept, other punctuation dropped; spaces become hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every heading id of a markdown file; a repeated id gets `-1`, `-2`, ...
fn anchors(text: &str) -> HashSet<String> {
    let mut ids = HashSet::new();
    for (_, line) in prose_lines(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if hashes == 0 || hashes > 6 || !line[hashes..].starts_with(' ') {
            continue;
        }
        // Inline code and emphasis markers are not part of the id.
        let text: String = line[hashes..].chars().filter(|&c| c != '`').collect();
        let base = slug(&text);
        let mut id = base.clone();
        let mut n = 0;
        while ids.contains(&id) {
            n += 1;
            id = format!("{base}-{n}");
        }
        ids.insert(id);
    }
    ids
}

/// The targets of inline links `[text](target)` outside code, with line
/// numbers. Inline code spans are skipped.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (number, line) in prose_lines(text) {
        let mut in_code = false;
        let chars: Vec<char> = line.chars().collect();
        let mut i = 0;
        while i < chars.len() {
            match chars[i] {
                '`' => in_code = !in_code,
                ']' if !in_code && chars.get(i + 1) == Some(&'(') => {
                    if let Some(end) = chars[i + 2..].iter().position(|&c| c == ')') {
                        let target: String = chars[i + 2..i + 2 + end].iter().collect();
                        found.push((number, target));
                        i += end + 2;
                    }
                }
                _ => {}
            }
            i += 1;
        }
    }
    found
}

/// Whether a link leaves the repository (and so is not checked here).
fn external(target: &str) -> bool {
    target.contains("://") || target.starts_with("mailto:")
}

/// What is wrong with one link of `doc`, if anything.
fn check_link(doc: &Path, target: &str) -> Option<String> {
    if target.starts_with('/') {
        return Some("absolute path; use a relative link".into());
    }
    let (path, anchor) = match target.split_once('#') {
        Some((path, anchor)) => (path, Some(anchor)),
        None => (target, None),
    };
    let file = if path.is_empty() {
        doc.to_path_buf()
    } else {
        doc.parent().expect("a document's folder").join(path)
    };
    if !file.exists() {
        return Some(format!("{} does not exist", shown(&file)));
    }
    let anchor = anchor?;
    if file.extension().is_none_or(|ext| ext != "md") {
        return Some("anchor into a file that is not markdown".into());
    }
    let text = fs::read_to_string(&file).expect("a readable markdown file");
    if anchors(&text).contains(anchor) {
        None
    } else {
        Some(format!("no heading with id '{anchor}' in {}", shown(&file)))
    }
}

#[test]
fn every_relative_link_and_anchor_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = fs::read_to_string(&doc).expect("a readable document");
        for (line, target) in links(&text) {
            if external(&target) {
                continue;
            }
            checked += 1;
            if let Some(problem) = check_link(&doc, &target) {
                broken.push(format!("{}:{line}: ({target}): {problem}", shown(&doc)));
            }
        }
    }
    assert!(checked > 0, "no relative links found at all");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn readme_is_short() {
    let text = fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = text.lines().count();
    assert!(
        lines <= README_MAX_LINES,
        "README.md has {lines} lines; keep it to {README_MAX_LINES} and move detail to docs/"
    );
}

#[test]
fn readme_keeps_the_ci_test_command() {
    let text = fs::read_to_string(root().join("README.md")).expect("README.md");
    assert!(
        text.lines()
            .any(|line| line == "./scripts/setup.sh && cargo test"),
        "README.md lost the line CI runs: ./scripts/setup.sh && cargo test"
    );
}

#[test]
fn slugs_follow_github() {
    assert_eq!(slug("Quick start"), "quick-start");
    assert_eq!(
        slug("OBJ models and normal maps"),
        "obj-models-and-normal-maps"
    );
    assert_eq!(slug("Error against run time"), "error-against-run-time");
    assert_eq!(slug("What's in `docs/`?"), "whats-in-docs");
    assert_eq!(
        slug("Time against error (1280×720)"),
        "time-against-error-1280720"
    );
    let ids = anchors("# A\n## Measured\n```\n# not a heading\n```\n## Measured\n### Measured\n");
    for id in ["a", "measured", "measured-1", "measured-2"] {
        assert!(ids.contains(id), "{id} missing from {ids:?}");
    }
    assert!(!ids.contains("not-a-heading"));
    let found = links("see [x](a.md#b) and `[y](c.md)`\n```\n[z](d.md)\n```\n");
    assert_eq!(found, vec![(1, "a.md#b".to_string())]);
}
