//! The pipeline cache on disk: a render writes it under the user's cache
//! folder, the next render reads it, a corrupt file is ignored with a
//! warning and the same image, an unwritable folder costs a warning only,
//! and `--no-pipeline-cache` / `AERIAL_PIPELINE_CACHE=off` touch nothing.
//! Every render runs under the validation layer.

use crate::common;
use std::path::{Path, PathBuf};
use std::process::Output;

/// `aerial render` of the default scene at 64×36 under validation into
/// `out`, with the cache folder `XDG_CACHE_HOME=cache_home`, the override
/// variable unset, and the cache's reads and writes logged.
fn render(cache_home: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut command = common::aerial();
    command
        .args(["render", "--validate", "--width", "64", "--height", "36"])
        .args(extra)
        .arg("--out")
        .arg(out)
        .env("XDG_CACHE_HOME", cache_home)
        .env_remove("AERIAL_PIPELINE_CACHE")
        .env("RUST_LOG", "aerial::vk::pipeline_cache=info");
    common::succeed(&mut command)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Every file under `folder`, recursively, sorted. (The driver and the
/// validation layer keep caches of their own beside ours, in other
/// folders of the same `XDG_CACHE_HOME`.)
fn files_under(folder: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    if let Ok(entries) = std::fs::read_dir(folder) {
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                found.extend(files_under(&path));
            } else {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// The one cache file a render left in `cache_home`.
fn the_cache_file(cache_home: &Path) -> PathBuf {
    let files = files_under(&cache_home.join("aerial"));
    assert_eq!(files.len(), 1, "expected one cache file: {files:?}");
    let file = files[0].clone();
    assert_eq!(file.parent(), Some(cache_home.join("aerial").as_path()));
    let name = file.file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        name.starts_with("pipelines-") && name.ends_with(".bin"),
        "{name}"
    );
    file
}

fn same_image(a: &Path, b: &Path) {
    assert!(
        std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
        "{} and {} differ",
        a.display(),
        b.display()
    );
}

#[test]
fn a_render_writes_the_cache_and_the_next_render_reads_it() {
    let dir = common::Scratch::new();
    let home = dir.path("cache");
    let first = render(&home, &dir.path("first.png"), &[]);
    let file = the_cache_file(&home);
    let size = std::fs::metadata(&file).unwrap().len();
    assert!(
        stderr(&first).contains(&format!("wrote {} bytes to {}", size - 48, file.display())),
        "{}",
        stderr(&first)
    );
    assert!(!stderr(&first).contains("warning"), "{}", stderr(&first));
    let written = std::fs::metadata(&file).unwrap().modified().unwrap();

    // The second run reads the whole file's data, and (nothing new having
    // been compiled) leaves it as it was.
    let second = render(&home, &dir.path("second.png"), &[]);
    assert!(
        stderr(&second).contains(&format!("read {} bytes from {}", size - 48, file.display())),
        "{}",
        stderr(&second)
    );
    assert!(!stderr(&second).contains("warning"), "{}", stderr(&second));
    assert_eq!(the_cache_file(&home), file);
    assert_eq!(
        std::fs::metadata(&file).unwrap().modified().unwrap(),
        written
    );
    same_image(&dir.path("first.png"), &dir.path("second.png"));
}

#[test]
fn a_corrupt_cache_file_is_ignored_with_a_warning_and_the_same_image() {
    let dir = common::Scratch::new();
    let home = dir.path("cache");
    render(&home, &dir.path("clean.png"), &[]);
    let file = the_cache_file(&home);
    let good = std::fs::read(&file).unwrap();

    let cases: [(&str, Vec<u8>, &str); 3] = [
        ("truncated", good[..good.len() - 1].to_vec(), "truncated"),
        (
            "altered",
            {
                let mut bytes = good.clone();
                *bytes.last_mut().unwrap() ^= 0x55;
                bytes
            },
            "checksum",
        ),
        (
            "foreign",
            b"not a pipeline cache at all".to_vec(),
            "no header",
        ),
    ];
    for (case, bytes, reason) in cases {
        std::fs::write(&file, &bytes).unwrap();
        let out = dir.path(&format!("{case}.png"));
        let run = render(&home, &out, &[]);
        let text = stderr(&run);
        let warnings: Vec<&str> = text.lines().filter(|l| l.starts_with("warning:")).collect();
        assert_eq!(warnings.len(), 1, "{case}: {text}");
        assert!(
            warnings[0].contains(&file.display().to_string()) && warnings[0].contains(reason),
            "{case}: {}",
            warnings[0]
        );
        same_image(&dir.path("clean.png"), &out);
        // The run saved a good cache again in its place.
        assert_eq!(std::fs::read(&file).unwrap(), good, "{case}");
    }
}

#[test]
fn no_pipeline_cache_and_the_off_override_neither_read_nor_write() {
    let dir = common::Scratch::new();
    let home = dir.path("cache");
    render(&home, &dir.path("flag.png"), &["--no-pipeline-cache"]);
    assert!(!home.join("aerial").exists());

    let mut command = common::aerial();
    command
        .args(["render", "--validate", "--width", "64", "--height", "36"])
        .arg("--out")
        .arg(dir.path("off.png"))
        .env("XDG_CACHE_HOME", &home)
        .env("AERIAL_PIPELINE_CACHE", "off");
    common::succeed(&mut command);
    assert!(!home.join("aerial").exists());
    same_image(&dir.path("flag.png"), &dir.path("off.png"));

    // Nor is a file already there read (it would be warned about).
    let folder = home.join("aerial");
    std::fs::create_dir_all(&folder).unwrap();
    let stray = folder.join("pipelines-stray.bin");
    std::fs::write(&stray, b"junk").unwrap();
    let run = render(&home, &dir.path("again.png"), &["--no-pipeline-cache"]);
    assert!(!stderr(&run).contains("warning"), "{}", stderr(&run));
    assert_eq!(files_under(&folder), vec![stray]);
}

#[test]
fn the_override_names_the_file_and_an_unwritable_folder_only_warns() {
    let dir = common::Scratch::new();
    let file = dir.path("my.cache");
    let mut command = common::aerial();
    command
        .args(["render", "--validate", "--width", "64", "--height", "36"])
        .arg("--out")
        .arg(dir.path("a.png"))
        .env("AERIAL_PIPELINE_CACHE", &file);
    common::succeed(&mut command);
    assert!(std::fs::metadata(&file).unwrap().len() > 48);

    // A cache folder that cannot be made (its parent is a file): the
    // render succeeds with one warning naming it.
    let blocker = dir.path("blocker");
    std::fs::write(&blocker, b"a file, not a folder").unwrap();
    let run = render(&blocker, &dir.path("b.png"), &[]);
    let text = stderr(&run);
    assert_eq!(text.matches("warning:").count(), 1, "{text}");
    assert!(
        text.contains("pipeline cache not saved") && text.contains(&blocker.display().to_string()),
        "{text}"
    );
    same_image(&dir.path("a.png"), &dir.path("b.png"));
}
