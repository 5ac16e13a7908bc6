//! Scripts: what a person would do at the window, frame by frame, so the
//! viewer can run without one (tests, demos, measurements).
//!
//! One action a line, `FRAME ACTION [ARG]`, run when frame FRAME (counted
//! from 0, the first frame shown) is about to be drawn; blank lines and
//! lines starting with `#` are skipped:
//!
//! ```text
//! 0   screenshot before.png   # the scene's own view
//! 0   press W
//! 30  release W               # 30 frames of moving forward
//! 30  mouse 40 0              # look right, as a drag of 40 pixels
//! 31  resize 320 180
//! 32  screenshot after.png
//! 33  quit
//! ```
//!
//! Input actions (`press`, `release`, `mouse`, `resize`) take effect before
//! the frame is drawn, `screenshot` after (it saves that frame), and `quit`
//! last. While a script runs, every frame advances time by the same step,
//! so a script always gives the same images.

use super::input::Key;
use std::path::{Path, PathBuf};

/// One action of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum ScriptAction {
    Press(Key),
    Release(Key),
    /// Look around as a mouse drag of (dx, dy) pixels would.
    Mouse(f64, f64),
    /// Ask the window system for a window of this inner size.
    Resize(u32, u32),
    /// Write the frame as PNG (at PATH) and EXR (PATH with `.exr`).
    Screenshot(PathBuf),
    Quit,
}

/// A parsed script: (frame, action) in file order, stably sorted by frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    pub steps: Vec<(u64, ScriptAction)>,
}

/// A script that cannot be read or has a bad line: the error names the
/// file, the line and why.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    #[error("cannot read script {path}: {reason}")]
    Read { path: PathBuf, reason: String },
    #[error("{path}:{line}: {reason}")]
    Line {
        path: PathBuf,
        line: usize,
        reason: String,
    },
}

/// The longest script read: far beyond any hand-written or generated one.
const MAX_SCRIPT_BYTES: u64 = 16 << 20;

/// The largest window a script may ask for (the renderer's output limit).
const MAX_SIDE: u32 = crate::scene::MAX_OUTPUT_SIZE;

impl Script {
    /// Reads and parses the script at `path`; a relative screenshot path
    /// is relative to the current directory, as on the command line.
    pub fn load(path: &Path) -> Result<Script, ScriptError> {
        let text = crate::safe_files::read_text(path, MAX_SCRIPT_BYTES).map_err(|e| {
            let hint = match e {
                crate::safe_files::TextReadError::TooLong(_) => {
                    "; a script is a few lines per frame"
                }
                _ => "",
            };
            ScriptError::Read {
                path: path.to_path_buf(),
                reason: format!("{e}{hint}"),
            }
        })?;
        Script::parse(&text, path)
    }

    /// Parses script text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Script, ScriptError> {
        let mut steps = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let step = parse_line(line).map_err(|reason| ScriptError::Line {
                path: path.to_path_buf(),
                line: i + 1,
                reason,
            })?;
            steps.push(step);
        }
        // Stable: actions of one frame keep their order in the file.
        steps.sort_by_key(|(frame, _)| *frame);
        Ok(Script { steps })
    }

    /// The actions of `frame`, in order.
    pub fn at(&self, frame: u64) -> impl Iterator<Item = &ScriptAction> {
        self.steps
            .iter()
            .filter(move |(f, _)| *f == frame)
            .map(|(_, a)| a)
    }

    /// The last frame with an action (`None` for an empty script).
    pub fn last_frame(&self) -> Option<u64> {
        self.steps.last().map(|(f, _)| *f)
    }
}

/// Drops a trailing `# comment` (a `#` after whitespace).
fn strip_comment(line: &str) -> &str {
    match line.find(" #").or_else(|| line.find("\t#")) {
        Some(i) => line[..i].trim_end(),
        None => line,
    }
}

fn parse_line(line: &str) -> Result<(u64, ScriptAction), String> {
    let line = strip_comment(line);
    let mut words = line.split_whitespace();
    let frame_text = words.next().unwrap_or_default();
    let frame: u64 = frame_text.parse().map_err(|_| {
        format!("'{frame_text}' is not a frame number (expected FRAME ACTION [ARG], FRAME counted from 0)")
    })?;
    let action = words
        .next()
        .ok_or_else(|| "missing action after the frame number (press, release, mouse, resize, screenshot or quit)".to_string())?;
    let args: Vec<&str> = words.collect();
    let count = |n: usize, usage: &str| {
        if args.len() == n {
            Ok(())
        } else {
            Err(format!(
                "'{action}' takes {usage}, got {} argument(s)",
                args.len()
            ))
        }
    };
    let number = |text: &str, what: &str| -> Result<f64, String> {
        text.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("{what} '{text}' is not a finite number"))
    };
    let side = |text: &str, what: &str| -> Result<u32, String> {
        text.parse::<u32>()
            .ok()
            .filter(|v| (1..=MAX_SIDE).contains(v))
            .ok_or_else(|| format!("{what} '{text}' is not a whole number in 1..={MAX_SIDE}"))
    };
    let action = match action {
        "press" | "release" => {
            count(1, "one KEY")?;
            let key = Key::parse(args[0])?;
            if action == "press" {
                ScriptAction::Press(key)
            } else {
                ScriptAction::Release(key)
            }
        }
        "mouse" => {
            count(2, "DX DY (pixels)")?;
            ScriptAction::Mouse(number(args[0], "DX")?, number(args[1], "DY")?)
        }
        "resize" => {
            count(2, "WIDTH HEIGHT")?;
            ScriptAction::Resize(side(args[0], "WIDTH")?, side(args[1], "HEIGHT")?)
        }
        "screenshot" => {
            if args.is_empty() {
                return Err("'screenshot' takes a PATH (the PNG; the EXR goes next to it)".into());
            }
            // The rest of the line, so a path may hold spaces.
            ScriptAction::Screenshot(PathBuf::from(args.join(" ")))
        }
        "quit" => {
            count(0, "no argument")?;
            ScriptAction::Quit
        }
        other => {
            return Err(format!(
            "unknown action '{other}' (expected press, release, mouse, resize, screenshot or quit)"
        ))
        }
    };
    Ok((frame, action))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::input::NamedKey;

    fn parse(text: &str) -> Result<Script, ScriptError> {
        Script::parse(text, Path::new("s.txt"))
    }

    #[test]
    fn every_action_parses_and_frames_are_sorted_stably() {
        let script = parse(
            "# a comment\n\
             5 quit\n\
             0 press w\n\
             \n\
             0 press ArrowUp   # trailing comment\n\
             3 mouse -12.5 4\n\
             2 resize 320 180\n\
             4 screenshot out dir/a b.png\n\
             1 release W\n",
        )
        .unwrap();
        assert_eq!(
            script.steps,
            vec![
                (0, ScriptAction::Press(Key::Char('W'))),
                (0, ScriptAction::Press(Key::Named(NamedKey::ArrowUp))),
                (1, ScriptAction::Release(Key::Char('W'))),
                (2, ScriptAction::Resize(320, 180)),
                (3, ScriptAction::Mouse(-12.5, 4.0)),
                (
                    4,
                    ScriptAction::Screenshot(PathBuf::from("out dir/a b.png"))
                ),
                (5, ScriptAction::Quit),
            ]
        );
        assert_eq!(script.last_frame(), Some(5));
        assert_eq!(script.at(0).count(), 2);
    }

    #[test]
    fn bad_lines_name_file_line_and_reason() {
        for (text, line, reason) in [
            ("x press W", 1, "'x' is not a frame number"),
            ("0 press W\n-1 quit", 2, "'-1' is not a frame number"),
            ("\n\n3", 3, "missing action"),
            ("0 jump", 1, "unknown action 'jump'"),
            ("0 press", 1, "'press' takes one KEY, got 0"),
            ("0 press W S", 1, "'press' takes one KEY, got 2"),
            ("0 press Arrowup", 1, "unknown key 'Arrowup'"),
            ("0 mouse 1", 1, "'mouse' takes DX DY"),
            ("0 mouse 1 nan", 1, "DY 'nan' is not a finite number"),
            ("0 resize 0 10", 1, "WIDTH '0' is not a whole number"),
            (
                "0 resize 10 99999",
                1,
                "HEIGHT '99999' is not a whole number",
            ),
            ("0 screenshot", 1, "'screenshot' takes a PATH"),
            ("0 quit now", 1, "'quit' takes no argument"),
        ] {
            let err = parse(text).unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("s.txt:{line}: ")) && err.contains(reason),
                "{text:?}: {err}"
            );
        }
    }

    #[test]
    fn a_missing_file_is_named() {
        let err = Script::load(Path::new("/nonexistent/script.txt"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("/nonexistent/script.txt"), "{err}");
    }
}
