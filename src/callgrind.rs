//! Instruction counts per pass: the CPU instructions a CPU Vulkan driver
//! (lavapipe, llvmpipe) executes for each pass of a frame, on every thread
//! it uses, counted by valgrind's callgrind tool.
//!
//! Time on a shared host wobbles by ±20 %; the instructions the driver
//! executes for the same frame do not (they repeat to about 1e-4 whatever
//! else the machine runs). How they are taken:
//!
//! - `aerial bench --metric instructions` starts a second copy of itself
//!   under `valgrind --tool=callgrind --instr-atstart=no`, with the same
//!   scenes and settings ([`spawn_counting_run`]). Setup (device, pipelines,
//!   the driver's shader compilation) and the warm-up frames run without
//!   instrumentation, so they cost little.
//! - In that copy, each measured frame is submitted once per *prefix*: the
//!   frame recording only its first k passes, k = 0..=P, each waited for.
//!   Around each submission the counters are zeroed and dumped through
//!   callgrind's client requests ([`Callgrind::count`]); pass k's count is
//!   prefix k+1 minus prefix k. A CPU driver bins draws and may rasterise
//!   them only when the render pass ends, so a pass cannot be counted
//!   alone; the difference of two prefixes counts it wherever it ran.
//! - Prefix 0 (the render pass begun and ended with no pass's commands,
//!   the submission and the fence) is reported as the frame's fixed cost.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// Dumps made by this process so far: callgrind numbers its dump files
/// from 1 in the order of the requests.
static DUMPS: AtomicU32 = AtomicU32::new(0);

/// The environment variable carrying callgrind's output file to the
/// counting copy.
pub const CALLGRIND_OUT_ENV: &str = "AERIAL_CALLGRIND_OUT";

/// Why instructions could not be counted.
#[derive(Debug, thiserror::Error)]
pub enum CountError {
    #[error("--metric instructions needs valgrind (package valgrind; run scripts/setup.sh): {0}")]
    NoValgrind(std::io::Error),
    #[error("--metric instructions: the counting run under valgrind failed ({status}){stderr}")]
    ChildFailed { status: String, stderr: String },
    #[error(
        "--metric instructions counts the instructions a CPU driver executes; {device} is not a \
         CPU device (use --metric time or --metric work on it)"
    )]
    NotCpuDevice { device: String },
    #[error(
        "--metric instructions: this build cannot make valgrind client requests on this \
         platform (x86_64 Linux only)"
    )]
    UnsupportedPlatform,
    #[error("--metric instructions: not running under callgrind ({CALLGRIND_OUT_ENV} is set, but valgrind does not answer)")]
    NotUnderValgrind,
    #[error("callgrind dump {}: {reason}", .path.display())]
    Dump { path: PathBuf, reason: String },
    #[error("interrupted; the counting run under valgrind was stopped")]
    Interrupted,
}

/// A valgrind client request: a no-op sequence of instructions that
/// valgrind recognises. Natively it returns `default`.
#[cfg(all(target_arch = "x86_64", target_os = "linux"))]
fn client_request(default: usize, request: usize, arg1: usize) -> usize {
    let args: [usize; 6] = [request, arg1, 0, 0, 0, 0];
    let mut result = default;
    // SAFETY: the four rotations of rdi by 3+13+61+51 = 128 bits leave it
    // unchanged, and exchanging rbx with itself does nothing: natively the
    // sequence has no effect but on the flags (declared clobbered). Under
    // valgrind it reads the six words at rax (alive for the whole block)
    // and writes its answer into rdx.
    unsafe {
        std::arch::asm!(
            "rol rdi, 3",
            "rol rdi, 13",
            "rol rdi, 61",
            "rol rdi, 51",
            "xchg rbx, rbx",
            in("rax") args.as_ptr(),
            inout("rdx") result,
            out("rdi") _,
            options(nostack),
        );
    }
    result
}

#[cfg(not(all(target_arch = "x86_64", target_os = "linux")))]
fn client_request(default: usize, _request: usize, _arg1: usize) -> usize {
    default
}

/// Request codes, from valgrind's public headers (`valgrind.h`,
/// `callgrind.h`): the core's base 0x1001, callgrind's tool base 'C','T'.
const RUNNING_ON_VALGRIND: usize = 0x1001;
const CALLGRIND_BASE: usize = ((b'C' as usize) << 24) | ((b'T' as usize) << 16);
const ZERO_STATS: usize = CALLGRIND_BASE + 1;
const DUMP_STATS_AT: usize = CALLGRIND_BASE + 3;
const START_INSTRUMENTATION: usize = CALLGRIND_BASE + 4;

/// Whether this process runs under valgrind.
pub fn running_on_valgrind() -> bool {
    client_request(0, RUNNING_ON_VALGRIND, 0) > 0
}

/// The counter of the copy running under callgrind: zeroes, dumps and
/// reads back callgrind's counts around each submission.
#[derive(Debug)]
pub struct Callgrind {
    /// `--callgrind-out-file` given to valgrind; dump n goes to `out.n`.
    out: PathBuf,
}

impl Callgrind {
    /// The counter, when this process was started by
    /// [`spawn_counting_run`]; `Ok(None)` in a normal run.
    pub fn from_env() -> Result<Option<Callgrind>, CountError> {
        let Some(out) = std::env::var_os(CALLGRIND_OUT_ENV) else {
            return Ok(None);
        };
        if cfg!(not(all(target_arch = "x86_64", target_os = "linux"))) {
            return Err(CountError::UnsupportedPlatform);
        }
        if !running_on_valgrind() {
            return Err(CountError::NotUnderValgrind);
        }
        Ok(Some(Callgrind {
            out: PathBuf::from(out),
        }))
    }

    /// Turns instrumentation on (valgrind runs the setup without it, which
    /// is several times faster).
    pub fn start(&self) {
        client_request(0, START_INSTRUMENTATION, 0);
    }

    /// The instructions every thread of the process executed while `work`
    /// ran (on lavapipe: the submitting thread, the queue thread and the
    /// rasteriser threads).
    pub fn count<T, E>(&self, work: impl FnOnce() -> Result<T, E>) -> Result<(T, u64), E>
    where
        E: From<CountError>,
    {
        client_request(0, ZERO_STATS, 0);
        let value = work()?;
        let reason = c"aerial pass prefix";
        client_request(0, DUMP_STATS_AT, reason.as_ptr() as usize);
        let dump = DUMPS.fetch_add(1, Ordering::SeqCst) + 1;
        let mut name = self.out.clone().into_os_string();
        name.push(format!(".{dump}"));
        let path = PathBuf::from(name);
        let count = read_dump_total(&path)?;
        // The dumps are only read once; a long run would fill the disk.
        let _ = std::fs::remove_file(&path);
        Ok((value, count))
    }
}

/// The instruction total (`Ir`) of one callgrind dump file.
fn read_dump_total(path: &Path) -> Result<u64, CountError> {
    let text =
        crate::safe_files::read_text(path, MAX_DUMP_BYTES).map_err(|e| CountError::Dump {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    parse_dump_total(&text).ok_or_else(|| CountError::Dump {
        path: path.to_path_buf(),
        reason: "no 'summary:' or 'totals:' line with an Ir count".to_string(),
    })
}

/// The largest callgrind dump read: one dump of a frame's submission, with
/// per-function costs only (`--dump-line=no --dump-instr=no`), is a few
/// hundred kilobytes.
const MAX_DUMP_BYTES: u64 = 256 << 20;

/// The first event (`Ir`, the only one callgrind collects without cache
/// simulation) of the `totals:` line (the sum over the dump's functions),
/// or of `summary:` when there is none. The summary also holds costs of
/// calls still open at the dump, which moved by up to 0.3 % between dumps
/// of identical submissions where the totals moved by 0.003 %.
pub fn parse_dump_total(text: &str) -> Option<u64> {
    let first_event = |prefix: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|n| n.parse::<u64>().ok())
    };
    if !text
        .lines()
        .any(|l| l.trim() == "events: Ir" || l.starts_with("events: Ir "))
    {
        return None;
    }
    first_event("totals:").or_else(|| first_event("summary:"))
}

/// Runs this binary again under callgrind with `args` (a `bench` command
/// line that writes its report with `--json`), callgrind's files in `dir`.
/// llvmpipe rasterises on the submitting thread (`LP_NUM_THREADS=0`)
/// unless `LP_NUM_THREADS` is set: with rasteriser threads, which thread
/// takes which tile, and when the threads wake, varies from run to run,
/// and so does the work around it (measured at 160x90: a pass of 10⁶
/// instructions moved by up to 0.9 % between runs with 2 threads, by
/// 0.07 % with none). It also makes counts from hosts with different core
/// counts compare.
///
/// valgrind runs as a child of this process that dies with it (see
/// [`crate::child_process`]): an interrupt stops it and returns
/// [`CountError::Interrupted`], and it is killed if this process ends
/// without stopping it. Its temporary files (`TMPDIR`) and its error
/// output go into `dir`, so removing `dir` leaves nothing behind; its
/// debugger pipes are off (`--vgdb=no`).
pub fn spawn_counting_run(args: &[std::ffi::OsString], dir: &Path) -> Result<(), CountError> {
    use crate::child_process::{self as child, ChildError};
    let exe = std::env::current_exe().map_err(CountError::NoValgrind)?;
    let out = dir.join("callgrind.out");
    let log = dir.join("valgrind.log");
    let stderr = std::fs::File::create(&log).map_err(CountError::NoValgrind)?;
    let mut command = std::process::Command::new("valgrind");
    command
        .arg("--tool=callgrind")
        .arg("--instr-atstart=no")
        .arg(format!("--callgrind-out-file={}", out.display()))
        .arg("--dump-line=no")
        .arg("--dump-instr=no")
        .arg("--vgdb=no")
        .arg("-q")
        .arg(exe)
        .args(args)
        .env(CALLGRIND_OUT_ENV, &out)
        .env("TMPDIR", dir)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(stderr);
    if std::env::var_os("LP_NUM_THREADS").is_none() {
        command.env("LP_NUM_THREADS", "0");
    }
    let status =
        child::run(&mut command, "the counting run under valgrind", None).map_err(|e| match e {
            ChildError::Spawn { error, .. } => CountError::NoValgrind(error),
            ChildError::Interrupted { .. } => CountError::Interrupted,
            e => CountError::ChildFailed {
                status: e.to_string(),
                stderr: String::new(),
            },
        })?;
    if !status.success() {
        // What valgrind and the copy printed, without the temporary
        // folder's name (it is gone once this returns).
        let text = child::tail_of(&log, 16 << 10)
            .replace(&dir.display().to_string(), "(temporary folder)");
        let text = text.trim();
        return Err(CountError::ChildFailed {
            status: status.to_string(),
            stderr: if text.is_empty() {
                String::new()
            } else {
                format!(":\n{text}")
            },
        });
    }
    Ok(())
}

/// Pass k's count from the counts of prefixes 0..=P of one frame: prefix
/// k+1 minus prefix k. The driver's work for a pass never makes a longer
/// prefix cheaper by more than noise; a negative difference is kept as 0.
pub fn pass_counts(prefixes: &[u64]) -> Vec<u64> {
    prefixes
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dump_total_is_its_totals_ir() {
        let dump = "# callgrind format\nversion: 1\ncreator: callgrind-3.19.0\n\
                    desc: Trigger: Client Request: aerial\n\nevents: Ir\n\
                    summary: 123456789\n\nfn=(1) main\n3 10\ntotals: 99\n";
        assert_eq!(parse_dump_total(dump), Some(99));
    }

    #[test]
    fn summary_is_used_without_totals() {
        assert_eq!(
            parse_dump_total("events: Ir\nsummary: 5\nfn=x\n1 5\n"),
            Some(5)
        );
    }

    #[test]
    fn a_dump_without_instruction_events_is_refused() {
        assert_eq!(parse_dump_total("events: Ir Dr\nsummary: 1 2\n"), Some(1));
        assert_eq!(parse_dump_total("events: Dr\nsummary: 1\n"), None);
        assert_eq!(parse_dump_total("events: Ir\n"), None);
        assert_eq!(parse_dump_total(""), None);
    }

    #[test]
    fn pass_counts_are_differences_of_prefixes() {
        assert_eq!(pass_counts(&[100, 150, 150, 400]), vec![50, 0, 250]);
        assert_eq!(pass_counts(&[100]), Vec::<u64>::new());
        assert_eq!(pass_counts(&[100, 90]), vec![0]);
    }

    #[test]
    fn client_requests_answer_their_default_natively() {
        // The test run is not under valgrind: the sequence does nothing and
        // the request's default comes back unchanged.
        assert_eq!(client_request(7, RUNNING_ON_VALGRIND, 0), 7);
        assert!(!running_on_valgrind());
    }
}
