//! Stopping a run when the user interrupts it (Ctrl-C, `kill`), at a safe
//! point.
//!
//! A signal handler must not tear the process down while the main thread
//! is inside the Vulkan driver or the validation layer: exiting from the
//! handler runs the libraries' exit-time destructors under the running
//! driver, which crashes. So the handler installed by [`install`] only
//! sets a flag. The work polls it with [`check`] at safe points (before
//! the device is created, between the phases of building a frame, before
//! every submitted frame, before outputs are committed) and unwinds as
//! from any error: Vulkan objects are destroyed in order, temporary output
//! files are removed by their drop, and the caller exits with
//! [`EXIT_INTERRUPTED`].
//!
//! Only while a Vulkan context exists ([`Busy`]) does the process wait for
//! a safe point. Otherwise (parsing, CPU-only commands such as `mesh` or
//! `compare`, encoding after the device is gone), and when the work
//! reaches no safe point within [`GRACE`] of the signal (a single very
//! long driver call) or at a second signal, the process ends at once: the
//! child process groups it started are killed and waited for
//! ([`spawn_tracked_group`]), the cleanups registered with
//! [`on_forced_exit`] run (the program registers the removal of its
//! temporary output files and folders), and it exits with `_exit`, which
//! runs no destructors, so it cannot crash either. The cleanups are
//! registered rather than called by name so that this module, which the
//! file writers themselves poll, depends on none of them.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Exit status of an interrupted run: the shell's convention for SIGINT.
pub const EXIT_INTERRUPTED: u8 = 130;

/// How long the work has to reach a safe point after an interrupt before
/// the process is ended without waiting for it.
pub const GRACE: Duration = Duration::from_secs(10);

/// The message printed when the process is ended without reaching a safe
/// point, so a test can tell the two ways apart.
pub const FORCED_MESSAGE: &str = "interrupted; stopped without waiting for the current step";

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// What [`on_forced_exit`] registered, in order.
static FORCED_EXIT_CLEANUPS: std::sync::Mutex<Vec<fn()>> = std::sync::Mutex::new(Vec::new());

/// Registers `cleanup` to run when an interrupt ends the process without
/// unwinding: after the child process groups are stopped, before `_exit`.
/// It runs on the watcher thread while the main thread may be anywhere,
/// so it must take its own locks. Register once, early in `main`.
pub fn on_forced_exit(cleanup: fn()) {
    FORCED_EXIT_CLEANUPS
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .push(cleanup);
}

/// Runs the cleanups [`on_forced_exit`] registered.
#[cfg(target_os = "linux")]
fn run_forced_exit_cleanups() {
    // A copy, so a cleanup that registers another cannot deadlock.
    let cleanups = FORCED_EXIT_CLEANUPS
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .clone();
    for cleanup in cleanups {
        cleanup();
    }
}

/// How many [`Busy`] guards are alive.
static BUSY: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Held while work that must not be cut short is under way (a Vulkan
/// context exists: the driver and the validation layer may be running):
/// an interrupt then waits for a safe point instead of ending the process
/// at once.
#[derive(Debug)]
pub struct Busy(());

impl Busy {
    /// Starts a stretch of such work, until the guard is dropped.
    pub fn start() -> Busy {
        BUSY.fetch_add(1, Ordering::SeqCst);
        Busy(())
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        BUSY.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Process groups of the children running now (see
/// [`spawn_tracked_group`]), stopped before the process ends at once.
static CHILD_GROUPS: std::sync::Mutex<Vec<u32>> = std::sync::Mutex::new(Vec::new());

fn child_groups() -> std::sync::MutexGuard<'static, Vec<u32>> {
    CHILD_GROUPS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Spawns `command`, which must lead a process group of its own, and
/// records the group: if the process then ends at once (a second
/// interrupt, or no safe point within [`GRACE`]), the group is killed and
/// its leader waited for before the temporary files and folders are
/// removed, so nothing writes into a folder being removed and nothing is
/// left running. Spawned under the lock the cleanup takes: no child
/// starts after it. Call [`untrack_group`] once the child has ended,
/// before reaping it.
pub fn spawn_tracked_group(
    command: &mut std::process::Command,
) -> std::io::Result<std::process::Child> {
    let mut groups = child_groups();
    let child = command.spawn()?;
    groups.push(child.id());
    Ok(child)
}

/// Forgets the group of `pid` (the child has ended and is about to be
/// reaped, after which its id may be reused).
pub fn untrack_group(pid: u32) {
    child_groups().retain(|&g| g != pid);
}

/// Kills every recorded child group and waits, at most [`STOP_WAIT`], for
/// each leader to end; keeps the lock, so no child starts after this.
#[cfg(target_os = "linux")]
fn stop_child_groups() {
    let groups = child_groups();
    for &pid in groups.iter() {
        // SAFETY: kill has no memory effects; the group's leader is this
        // process's child and not reaped yet (it is untracked first), so
        // the id is still its group's.
        unsafe { libc::kill(-(pid as libc::pid_t), libc::SIGKILL) };
    }
    let deadline = std::time::Instant::now() + STOP_WAIT;
    for &pid in groups.iter() {
        while std::time::Instant::now() < deadline && !ended(pid) {
            std::thread::sleep(Duration::from_millis(5));
        }
    }
    std::mem::forget(groups);
}

/// How long the process waits for its killed children to end before it
/// removes their temporary folders and exits.
#[cfg(target_os = "linux")]
const STOP_WAIT: Duration = Duration::from_secs(5);

/// Whether the child `pid` has ended (or was reaped by another thread),
/// without reaping it.
#[cfg(target_os = "linux")]
fn ended(pid: u32) -> bool {
    // SAFETY: waitid fills the zeroed siginfo_t it is given; WNOWAIT
    // leaves the child waitable, WNOHANG returns at once.
    unsafe {
        let mut info: libc::siginfo_t = std::mem::zeroed();
        let r = libc::waitid(
            libc::P_PID,
            pid as libc::id_t,
            &mut info,
            libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
        );
        r != 0 || info.si_pid() != 0
    }
}

/// The work was stopped by an interrupt.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("interrupted")]
pub struct Interrupted;

/// Asks the running work to stop at its next safe point (what the signal
/// handler does; also for embedding programs with their own handlers).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// True once an interrupt was requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// A safe point: `Err(Interrupted)` once an interrupt was requested.
pub fn check() -> Result<(), Interrupted> {
    if requested() {
        Err(Interrupted)
    } else {
        Ok(())
    }
}

// The handler is installed on Linux (it uses pipe2 and the errno location
// of glibc and musl); elsewhere the signals keep their default action.

/// The signals that stop a run: those whose default action ends the
/// process and that a user or a process supervisor sends to stop it.
#[cfg(target_os = "linux")]
pub const SIGNALS: [libc::c_int; 6] = [
    libc::SIGINT,
    libc::SIGTERM,
    libc::SIGHUP,
    libc::SIGQUIT,
    libc::SIGUSR1,
    libc::SIGUSR2,
];

/// The write end of the pipe the handler wakes the watcher thread through
/// (-1 before [`install`]).
#[cfg(target_os = "linux")]
static WAKE_FD: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(-1);

#[cfg(target_os = "linux")]
extern "C" fn on_signal(_signal: libc::c_int) {
    // Only async-signal-safe work here: an atomic store and write(2).
    // errno is saved and restored around the write, as the interrupted
    // code may be about to read it.
    // SAFETY: __errno_location returns the calling thread's errno, valid
    // for the thread's lifetime.
    let errno = unsafe { *libc::__errno_location() };
    request();
    let fd = WAKE_FD.load(Ordering::SeqCst);
    if fd >= 0 {
        let byte = 1u8;
        // SAFETY: writes one byte from a live stack variable to a pipe
        // this module owns; a full pipe makes it fail, which is harmless
        // (the watcher is awake already).
        unsafe { libc::write(fd, std::ptr::addr_of!(byte).cast(), 1) };
    }
    // SAFETY: as above.
    unsafe { *libc::__errno_location() = errno };
}

/// Installs the handler for [`SIGNALS`] and starts the thread that ends
/// the process if the work does not stop within [`GRACE`] (or at a second
/// signal). Call it once, early in `main`.
#[cfg(target_os = "linux")]
pub fn install() -> std::io::Result<()> {
    let mut fds = [0 as libc::c_int; 2];
    // SAFETY: pipe2 writes two descriptors into the array it is given.
    if unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC | libc::O_NONBLOCK) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    let (read_fd, write_fd) = (fds[0], fds[1]);
    // The read end blocks (the watcher waits on it); the write end stays
    // non-blocking so the handler can never hang on a full pipe.
    // SAFETY: fcntl on a descriptor just created here.
    unsafe { libc::fcntl(read_fd, libc::F_SETFL, 0) };
    WAKE_FD.store(write_fd, Ordering::SeqCst);
    std::thread::Builder::new()
        .name("interrupt watcher".into())
        .spawn(move || watch(read_fd))?;
    for signal in SIGNALS {
        // SAFETY: a zeroed sigaction is a valid starting point; the handler
        // is an `extern "C" fn(c_int)` that only does async-signal-safe
        // work. SA_RESTART restarts system calls the signal lands in, so
        // the driver's own waits are not cut short by it.
        let result = unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESTART;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(signal, &action, std::ptr::null_mut())
        };
        if result != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(())
}

/// The watcher thread: after the first signal, ends the process at once
/// unless a [`Busy`] guard is alive; then waits [`GRACE`] for the process to
/// end by itself, and a second signal or the end of the grace period ends
/// it at once.
#[cfg(target_os = "linux")]
fn watch(read_fd: libc::c_int) {
    let mut byte = 0u8;
    let mut read = |timeout_ms: libc::c_int| -> bool {
        let mut poll = libc::pollfd {
            fd: read_fd,
            events: libc::POLLIN,
            revents: 0,
        };
        // SAFETY: poll on one valid pollfd; read into a live byte.
        unsafe {
            libc::poll(&mut poll, 1, timeout_ms) > 0
                && libc::read(read_fd, std::ptr::addr_of_mut!(byte).cast(), 1) == 1
        }
    };
    // Wait for the first signal (poll restarts after EINTR by looping).
    while !read(-1) {}
    let forced = BUSY.load(Ordering::SeqCst) > 0;
    if forced {
        let deadline = std::time::Instant::now() + GRACE;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() || read(left.as_millis().clamp(1, i32::MAX as u128) as libc::c_int) {
                break;
            }
        }
    }
    // Children first: once they are gone, nothing writes into the
    // temporary folders. Then the registered cleanups (the removal of the
    // pending files takes their lock, so a commit in progress finishes
    // first and its files are whole or gone).
    stop_child_groups();
    run_forced_exit_cleanups();
    if forced {
        eprintln!("{FORCED_MESSAGE}; no output written");
    } else {
        eprintln!("interrupted; no output written");
    }
    // SAFETY: _exit ends every thread at once without running exit-time
    // destructors, which is the point: the main thread may be inside the
    // driver.
    unsafe { libc::_exit(i32::from(EXIT_INTERRUPTED)) };
}
