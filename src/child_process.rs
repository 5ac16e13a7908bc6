//! Child processes that die with the run that started them (the counting
//! copy under valgrind, the rounds of `bench --against`). It stands on its
//! own, beside `interrupt`, so both the bench and the instruction counting
//! start children without depending on each other.
//!
//! - Each child leads a process group of its own, so whatever it starts in
//!   turn (valgrind's tool, a wrapper script's commands) can be stopped
//!   with it, and a Ctrl-C at the terminal reaches only `bench`, which
//!   stops the children itself.
//! - On Linux the child is also killed by the kernel when `bench` ends
//!   without stopping it (`PR_SET_PDEATHSIG`): killed outright, or ended
//!   by a second interrupt without waiting.
//! - [`run`] waits for the child while polling for an interrupt
//!   ([`crate::interrupt`]) and for its time limit. Either stops the
//!   group: SIGTERM, [`STOP_GRACE`] to end, then SIGKILL. A child that
//!   finished by itself has its group killed too before it is reaped, so
//!   nothing it left running outlives it.
//!
//! While [`run`] waits it holds an [`crate::interrupt::Busy`] guard: an
//! interrupt then waits for the children to be stopped and the caller's
//! temporary folder to be removed, instead of ending the process at once.

use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

/// How long a stopped child has to end after SIGTERM before its process
/// group is killed.
pub const STOP_GRACE: Duration = Duration::from_secs(2);

/// How often [`run`] looks at the child, the interrupt flag and the clock.
const POLL: Duration = Duration::from_millis(20);

/// Why a child did not run to its end.
#[derive(Debug, thiserror::Error)]
pub enum ChildError {
    #[error("cannot start {what}: {error}")]
    Spawn { what: String, error: std::io::Error },
    #[error("{what} did not finish within {} s{hint}; it was stopped", .limit.as_secs_f64())]
    TimedOut {
        what: String,
        limit: Duration,
        /// How to change the limit, e.g. " (--round-timeout)".
        hint: String,
    },
    #[error("interrupted; {what} was stopped")]
    Interrupted { what: String },
    #[error("waiting for {what}: {error}")]
    Wait { what: String, error: std::io::Error },
}

/// A time limit for [`run`] and how the user changes it (for the message).
#[derive(Clone, Debug)]
pub struct Limit {
    pub after: Duration,
    pub hint: String,
}

/// Starts `command` in a process group of its own, tied to this process,
/// and waits for it. `what` names it in errors ("the other build (PATH)").
/// Stops it (and everything in its group) on an interrupt or once `limit`
/// has passed; see the module docs.
pub fn run(
    command: &mut Command,
    what: &str,
    limit: Option<Limit>,
) -> Result<ExitStatus, ChildError> {
    let _busy = crate::interrupt::Busy::start();
    tie_to_this_process(command);
    let mut child =
        crate::interrupt::spawn_tracked_group(command).map_err(|error| ChildError::Spawn {
            what: what.to_string(),
            error,
        })?;
    let started = Instant::now();
    loop {
        match exited(&child) {
            Ok(true) => break,
            Ok(false) => {}
            Err(error) => {
                stop(&mut child);
                return Err(ChildError::Wait {
                    what: what.to_string(),
                    error,
                });
            }
        }
        if crate::interrupt::requested() {
            stop(&mut child);
            return Err(ChildError::Interrupted {
                what: what.to_string(),
            });
        }
        if let Some(limit) = limit.as_ref().filter(|l| started.elapsed() >= l.after) {
            stop(&mut child);
            return Err(ChildError::TimedOut {
                what: what.to_string(),
                limit: limit.after,
                hint: limit.hint.clone(),
            });
        }
        std::thread::sleep(POLL);
    }
    // The leader has ended but is not reaped yet, so its group id cannot
    // have been reused: whatever it left running in the group goes too.
    signal_group(&child, Signal::Kill);
    crate::interrupt::untrack_group(child.id());
    child.wait().map_err(|error| ChildError::Wait {
        what: what.to_string(),
        error,
    })
}

/// Gives the child its own process group and, on Linux, has the kernel
/// kill it when this process ends.
fn tie_to_this_process(command: &mut Command) {
    use std::os::unix::process::CommandExt as _;
    command.process_group(0);
    #[cfg(target_os = "linux")]
    {
        // SAFETY: getpid has no preconditions.
        let parent = unsafe { libc::getpid() };
        // SAFETY: the closure runs in the child between fork and exec and
        // only makes async-signal-safe system calls (prctl, getppid,
        // raise), touching no memory shared with the parent.
        unsafe {
            command.pre_exec(move || {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL, 0, 0, 0) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                // The parent may have ended before the request was made:
                // then nothing would ever send the signal.
                if libc::getppid() != parent {
                    libc::raise(libc::SIGKILL);
                }
                Ok(())
            });
        }
    }
}

/// Whether the child has ended, without reaping it (its process group id
/// stays reserved until [`Child::wait`]).
fn exited(child: &Child) -> std::io::Result<bool> {
    // SAFETY: waitid fills the zeroed siginfo_t it is given; WNOWAIT
    // leaves the child waitable, WNOHANG returns at once.
    unsafe {
        let mut info: libc::siginfo_t = std::mem::zeroed();
        let r = libc::waitid(
            libc::P_PID,
            child.id() as libc::id_t,
            &mut info,
            libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
        );
        if r != 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() == std::io::ErrorKind::Interrupted {
                return Ok(false);
            }
            return Err(e);
        }
        Ok(info.si_pid() != 0)
    }
}

#[derive(Clone, Copy)]
enum Signal {
    Term,
    Kill,
}

/// Sends `signal` to the child's process group (whose id is the child's).
fn signal_group(child: &Child, signal: Signal) {
    let signal = match signal {
        Signal::Term => libc::SIGTERM,
        Signal::Kill => libc::SIGKILL,
    };
    // SAFETY: kill has no memory effects; the group is the child's own
    // (it is not reaped yet, so the id is not reused). An error (the
    // group is gone already) needs no handling.
    unsafe {
        libc::kill(-(child.id() as libc::pid_t), signal);
    }
}

/// Stops the child and its group: SIGTERM, up to [`STOP_GRACE`] for the
/// leader to end, SIGKILL to whatever is left, then reaps the leader.
fn stop(child: &mut Child) {
    signal_group(child, Signal::Term);
    let deadline = Instant::now() + STOP_GRACE;
    while Instant::now() < deadline && !exited(child).unwrap_or(true) {
        std::thread::sleep(POLL);
    }
    signal_group(child, Signal::Kill);
    crate::interrupt::untrack_group(child.id());
    let _ = child.wait();
}

/// The end of the file `path` (at most `limit` bytes of it, from a line
/// start where possible), as text: what a failed child printed, without
/// reading an endless log whole.
pub fn tail_of(path: &std::path::Path, limit: u64) -> String {
    use std::io::{Read as _, Seek as _};
    let Ok(mut file) = std::fs::File::open(path) else {
        return String::new();
    };
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let start = len.saturating_sub(limit);
    if file.seek(std::io::SeekFrom::Start(start)).is_err() {
        return String::new();
    }
    let mut bytes = Vec::new();
    let _ = file.take(limit).read_to_end(&mut bytes);
    let text = String::from_utf8_lossy(&bytes).into_owned();
    if start > 0 {
        // Cut at the first line break, so no line is shown in part.
        match text.split_once('\n') {
            Some((_, rest)) => format!("...\n{rest}"),
            None => text,
        }
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether any process in the system has `marker` in its environment.
    fn alive_with(marker: &str) -> Vec<u32> {
        let needle = format!("AERIAL_CHILD_TEST={marker}");
        std::fs::read_dir("/proc")
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().to_str()?.parse::<u32>().ok())
            .filter(|pid| {
                std::fs::read(format!("/proc/{pid}/environ"))
                    .is_ok_and(|env| env.split(|&b| b == 0).any(|v| v == needle.as_bytes()))
            })
            .collect()
    }

    fn wait_until_gone(marker: &str) -> Vec<u32> {
        // Killed processes vanish once the kernel has torn them down; a
        // generous deadline, which only a failure of the fix reaches.
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            let alive = alive_with(marker);
            if alive.is_empty() || Instant::now() > deadline {
                return alive;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn shell(script: &str, marker: &str) -> Command {
        let mut c = Command::new("sh");
        c.args(["-c", script]).env("AERIAL_CHILD_TEST", marker);
        c
    }

    #[test]
    fn a_child_past_its_limit_is_stopped_with_everything_it_started() {
        let marker = format!("limit-{}", std::process::id());
        // The shell starts two sleepers in the background and waits: none
        // ends by itself within the test.
        let mut c = shell("sleep 300 & sleep 300 & wait", &marker);
        let e = run(
            &mut c,
            "the sleeper",
            Some(Limit {
                after: Duration::from_millis(300),
                hint: " (--limit)".into(),
            }),
        )
        .unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, ChildError::TimedOut { .. }), "{text}");
        assert!(
            text.contains("the sleeper") && text.contains("0.3 s (--limit)"),
            "{text}"
        );
        assert_eq!(wait_until_gone(&marker), Vec::<u32>::new());
    }

    #[test]
    fn what_a_finished_child_left_running_is_killed() {
        let marker = format!("left-{}", std::process::id());
        // The shell ends at once and leaves a sleeper behind in its group.
        let mut c = shell("sleep 300 & exit 3", &marker);
        let status = run(&mut c, "the shell", None).unwrap();
        assert_eq!(status.code(), Some(3));
        assert_eq!(wait_until_gone(&marker), Vec::<u32>::new());
    }

    #[test]
    fn a_missing_program_is_an_error_naming_it() {
        let mut c = Command::new("/nonexistent/aerial-child-test");
        let e = run(&mut c, "the other build (/nonexistent)", None).unwrap_err();
        assert!(
            e.to_string()
                .contains("cannot start the other build (/nonexistent)"),
            "{e}"
        );
    }

    #[test]
    fn the_tail_of_a_long_log_starts_at_a_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("log");
        let text: String = (0..1000).map(|i| format!("line {i}\n")).collect();
        std::fs::write(&path, &text).unwrap();
        let tail = tail_of(&path, 40);
        assert!(tail.starts_with("...\nline "), "{tail}");
        assert!(tail.ends_with("line 999\n"), "{tail}");
        assert!(tail.len() <= 45, "{tail}");
        assert_eq!(tail_of(&path, 1 << 20), text);
        assert_eq!(tail_of(&dir.path().join("none"), 10), "");
    }
}
