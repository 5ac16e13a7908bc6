//! Files handled safely: the one way this crate writes an output file
//! (into a uniquely named temporary file in the destination's folder,
//! renamed over the destination only once it is complete), and the one way
//! it reads an input (bounded in size, and recorded so that no output ever
//! replaces it).
//!
//! - Concurrent writers to the same path each get their own temporary file,
//!   so the destination is always one whole file, never a mix.
//! - A failed or interrupted write leaves no temporary file behind: the
//!   temporary file is removed on drop (an interrupted run unwinds and
//!   drops it, see [`crate::interrupt`]), and [`remove_pending`] removes
//!   the ones still open when the process must end without unwinding
//!   (`main` registers it with [`crate::interrupt::on_forced_exit`]).
//! - Only regular files are replaced. A destination that is a device, FIFO,
//!   socket or folder is refused; a symbolic link is written through (its
//!   target is replaced, the link stays).
//! - A run that writes several files prepares all of them first and commits
//!   them together with [`commit_all`], so a failure leaves none of them.
//! - No output is ever one of the run's inputs: [`protect_inputs`] records
//!   them, and once [`protect_inputs_as_read`] is on, every file read
//!   through this crate's readers is recorded as it is read.
//! - Messages name the path the caller gave, never the temporary file.

use std::collections::HashSet;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The destination cannot be written by this program's rules (not a
    /// regular file, no such folder, ...).
    #[error("cannot write {}: {reason}", path.display())]
    Refused { path: PathBuf, reason: String },
    /// The operating system refused. The error is part of the message, not
    /// a chained source, so reporters that walk the chain print it once.
    #[error("cannot write {}: {error}", path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
}

/// The error of a file not committed because of an interrupt (see
/// [`crate::interrupt`]): an I/O error of kind `Interrupted`.
fn interrupted(path: &Path) -> FileError {
    FileError::Io {
        path: path.to_path_buf(),
        error: std::io::Error::new(
            std::io::ErrorKind::Interrupted,
            crate::interrupt::Interrupted,
        ),
    }
}

/// Temporary files currently being written, for [`remove_pending`].
static PENDING: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

fn pending() -> std::sync::MutexGuard<'static, Option<HashSet<PathBuf>>> {
    // A panic while holding the lock leaves a consistent set; keep using it.
    PENDING.lock().unwrap_or_else(|p| p.into_inner())
}

/// Removes every temporary file still being written, and every
/// [`TempFolder`] still in use. For a process that ends without unwinding
/// (it exits right after); holding the lock also waits for a rename in
/// progress, so a file is either complete under its final name or gone.
pub fn remove_pending() {
    let mut guard = pending();
    if let Some(set) = guard.as_mut() {
        for path in set.drain() {
            let _ = std::fs::remove_file(path);
        }
    }
    // Leave the lock held until the process exits: no commit may start
    // after the cleanup. (The guard is forgotten, never unlocked.)
    std::mem::forget(guard);
    let folders = pending_folders();
    for path in folders.iter() {
        remove_folder(path);
    }
    // Likewise: no folder is made, or half removed by its drop, after this.
    std::mem::forget(folders);
}

/// Temporary folders in use, for [`remove_pending`].
static PENDING_FOLDERS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending_folders() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING_FOLDERS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Removes `path` and everything in it. A process that wrote into it may
/// have been killed a moment ago and its last files may still appear, so
/// the removal is repeated (a few times, briefly) until the folder is gone.
fn remove_folder(path: &Path) {
    for _ in 0..50 {
        match std::fs::remove_dir_all(path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound && path.exists() => {
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
            _ => return,
        }
    }
}

/// A temporary folder (in `TMPDIR`) for files a command makes and reads
/// itself, such as a child process's report. It is removed with its
/// contents when dropped, and by [`remove_pending`] when the process ends
/// without unwinding (a second interrupt), so neither way of stopping
/// leaves it behind.
#[derive(Debug)]
pub struct TempFolder {
    path: PathBuf,
}

impl TempFolder {
    /// Makes the folder. Registered under the same lock the cleanup takes,
    /// so none is made once the cleanup has run.
    pub fn new() -> std::io::Result<TempFolder> {
        let mut folders = pending_folders();
        let path = tempfile::tempdir()?.keep();
        folders.push(path.clone());
        Ok(TempFolder { path })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for TempFolder {
    fn drop(&mut self) {
        // Removed under the lock: the cleanup of a process ending at once
        // finds the folder either still whole and registered, or gone.
        let mut folders = pending_folders();
        remove_folder(&self.path);
        folders.retain(|p| *p != self.path);
    }
}

/// What makes two paths the same file: the device and inode on Unix, so a
/// symbolic link or a hard link to a file is that file; elsewhere the
/// canonical path (symbolic links only).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct FileId(#[cfg(unix)] (u64, u64), #[cfg(not(unix))] PathBuf);

impl FileId {
    /// The identity of the existing file at `path` (through symbolic
    /// links); `None` when there is none.
    fn of(path: &Path) -> Option<FileId> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt as _;
            std::fs::metadata(path)
                .ok()
                .map(|m| FileId((m.dev(), m.ino())))
        }
        #[cfg(not(unix))]
        {
            std::fs::canonicalize(path).ok().map(FileId)
        }
    }
}

/// The inputs of the running command, by identity, with the path they
/// were given as (for messages). See [`protect_inputs`].
static INPUTS: Mutex<Vec<(FileId, PathBuf)>> = Mutex::new(Vec::new());

/// Whether every file read through this crate is recorded as an input
/// (see [`protect_inputs_as_read`]).
static PROTECT_READS: AtomicBool = AtomicBool::new(false);

/// True when the input recorded as `given` with identity `id` is still
/// that file. An input removed since it was read is no longer one, and
/// its inode number may be reused by a new file (a long-running program
/// reads and removes many files), which must not be taken for it.
fn still_input(id: &FileId, given: &Path) -> bool {
    FileId::of(given).as_ref() == Some(id)
}

/// Records `paths` as inputs of the running command (its scene, models,
/// MTL libraries, textures, height maps, scripts, baselines, images to
/// compare...): from then on no output may be one of them.
/// [`check_destination`], and so every write through this module, refuses
/// a destination that is the same file as an input, whatever the path
/// names it by (symbolic links, hard links, `./` and `..`, a link to its
/// folder). Paths that do not exist are skipped: they cannot be
/// overwritten by accident.
///
/// Commands protect their inputs once they are parsed and then check
/// their outputs, so the refusal comes before any work; the same check
/// when each file is committed catches any output checked too early, and
/// with [`protect_inputs_as_read`] any input found only while loading.
pub fn protect_inputs<P: AsRef<Path>>(paths: impl IntoIterator<Item = P>) {
    let mut inputs = INPUTS.lock().unwrap_or_else(|p| p.into_inner());
    for path in paths {
        let path = path.as_ref();
        if let Some(id) = FileId::of(path) {
            if !inputs
                .iter()
                .any(|(known, given)| *known == id && still_input(known, given))
            {
                inputs.push((id, path.to_path_buf()));
            }
        }
    }
}

/// From now on, every file this process reads through the crate's readers
/// (scene files and scripts, OBJ models with their MTL libraries and the
/// textures those name, images) is recorded as an input the moment it is
/// read, as if given to [`protect_inputs`]. Then an input a command learns
/// of only while loading (a library named inside a model, a texture named
/// inside a library) can never be replaced by one of its outputs, whether
/// or not the command lists it. Every command turns it on first; a program
/// that means to write over files it has read (a test regenerating its
/// references) leaves it off.
pub fn protect_inputs_as_read() {
    PROTECT_READS.store(true, Ordering::SeqCst);
}

/// What the crate's readers call with each file they read: recorded as an
/// input when [`protect_inputs_as_read`] is on, otherwise nothing.
pub fn note_inputs<P: AsRef<Path>>(paths: impl IntoIterator<Item = P>) {
    if PROTECT_READS.load(Ordering::SeqCst) {
        protect_inputs(paths);
    }
}

/// The protected input that `path` (an existing file) is, if any.
fn protected_input(path: &Path) -> Option<PathBuf> {
    let id = FileId::of(path)?;
    let inputs = INPUTS.lock().unwrap_or_else(|p| p.into_inner());
    inputs
        .iter()
        .find(|(known, given)| *known == id && still_input(known, given))
        .map(|(_, given)| given.clone())
}

/// Checks that `path` can be an output: it names a file (not a folder:
/// no trailing `/`) in an existing folder where this process can create
/// files, is not a folder, device, FIFO, pipe or socket, and is not one of
/// the command's inputs ([`protect_inputs`]). Returns the path to replace
/// (the target when `path` is a symbolic link). Call it before long work,
/// so a bad output path fails in seconds, not after the render.
///
/// A file is created in the folder and removed again, the way the output
/// will be written: what permission bits cannot tell (a read-only mount,
/// `/proc` or `/sys`) is found here.
pub fn check_destination(path: &Path) -> Result<PathBuf, FileError> {
    destination(path, true)
}

/// [`check_destination`], creating the trial file in the folder only when
/// `probe` (the commit's own check needs none: its file is there).
fn destination(path: &Path, probe: bool) -> Result<PathBuf, FileError> {
    let refuse = |reason: String| FileError::Refused {
        path: path.to_path_buf(),
        reason,
    };
    if let Some(reason) = not_a_file_name(path) {
        return Err(refuse(reason));
    }
    let mut dest = path.to_path_buf();
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        if meta.file_type().is_symlink() {
            dest = std::fs::canonicalize(path).map_err(|e| match anonymous_link(path) {
                Some(target) => refuse(format!(
                    "it is a pipe or socket ({target}), not a file; outputs are written to a \
                     temporary file and renamed into place, so name a file"
                )),
                None => refuse(format!("symbolic link to a missing target ({e})")),
            })?;
        }
        let meta = std::fs::metadata(&dest).map_err(|error| FileError::Io {
            path: path.to_path_buf(),
            error,
        })?;
        if meta.is_dir() {
            return Err(refuse("it is a folder".into()));
        }
        if !meta.is_file() {
            return Err(refuse(format!(
                "it exists and is not a regular file ({}); refusing to replace it",
                kind_of(&meta)
            )));
        }
        if let Some(input) = protected_input(&dest) {
            let reason = if input == path {
                "it is an input of this command; writing it would destroy the input".to_string()
            } else {
                format!(
                    "it is the same file as the input {}; writing it would destroy the input",
                    input.display()
                )
            };
            return Err(refuse(reason));
        }
    }
    check_writable(&dest).map_err(refuse)?;
    let dir = parent(&dest);
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(refuse(format!("{} is not a folder", dir.display()))),
        Err(e) => return Err(refuse(format!("folder {}: {e}", dir.display()))),
    }
    if probe {
        probe_folder(dir).map_err(|e| {
            refuse(format!(
                "cannot create a file in folder {}: {e}",
                dir.display()
            ))
        })?;
    }
    Ok(dest)
}

/// Why `path` cannot name an output file, if it cannot: it names no file
/// (`/`, `..`), or it ends in `/` or `/.`, which names a folder (the
/// system refuses to create a file there, but only when the file is
/// finally renamed into place, after the work).
fn not_a_file_name(path: &Path) -> Option<String> {
    use std::os::unix::ffi::OsStrExt as _;
    let bytes = path.as_os_str().as_bytes();
    if let Some(end) = ["/", "/."]
        .into_iter()
        .find(|end| bytes.ends_with(end.as_bytes()))
    {
        return Some(format!(
            "the path ends in \"{end}\", so it names a folder, not a file; an output is a \
             file: name it without the trailing \"{end}\""
        ));
    }
    if path.file_name().is_none() {
        return Some("the path does not name a file".into());
    }
    None
}

/// Creates a temporary file in `dir` and removes it again: whether an
/// output can be written there, as far as creating it goes.
fn probe_folder(dir: &Path) -> std::io::Result<()> {
    // Under the lock of the pending files: an interrupt that ends the
    // process waits until the trial file is gone.
    let _guard = pending();
    let file = tempfile::Builder::new()
        .prefix(".aerial-probe.")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(without_temporary_name)?;
    file.close().map_err(without_temporary_name)
}

/// `error` without the name of the temporary file it may carry (the
/// `tempfile` crate appends `at path "..."`): messages name the output
/// the user gave, never the hidden file it is written through.
fn without_temporary_name(error: std::io::Error) -> std::io::Error {
    if let Some(code) = error.raw_os_error() {
        return std::io::Error::from_raw_os_error(code);
    }
    let text = error.to_string();
    match text.find(" at path ") {
        Some(at) => std::io::Error::new(error.kind(), text[..at].to_string()),
        None => error,
    }
}

/// Free space needed by outputs about to be written, checked before the
/// work: each `(path, bytes)` is an output and an upper bound of its
/// size. Outputs on one file system are added up. Refuses, naming the
/// output, the space it needs and the space there is, when a file system
/// has less room than its outputs need (space kept for the superuser does
/// not count, as this process may not be able to use it).
pub fn check_room(outputs: &[(&Path, u64)]) -> Result<(), FileError> {
    use std::os::unix::ffi::OsStrExt as _;
    let mut by_device: Vec<(u64, u64, &Path)> = Vec::new();
    for &(path, bytes) in outputs {
        let dest = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        let dir = parent(&dest);
        let Ok(c) = std::ffi::CString::new(dir.as_os_str().as_bytes()) else {
            continue;
        };
        // SAFETY: statvfs(3) fills the zeroed struct for the NUL-terminated
        // path; it is read only when the call succeeds.
        let mut fs: libc::statvfs = unsafe { std::mem::zeroed() };
        if unsafe { libc::statvfs(c.as_ptr(), &mut fs) } != 0 || fs.f_blocks == 0 {
            // Unknown (or a file system without blocks, such as /proc):
            // nothing to say here.
            continue;
        }
        #[allow(clippy::unnecessary_cast)] // the field types differ between systems
        let free = (fs.f_bavail as u64).saturating_mul(fs.f_frsize as u64);
        let device = {
            use std::os::unix::fs::MetadataExt as _;
            std::fs::metadata(dir).map_or(0, |m| m.dev())
        };
        let total = match by_device.iter_mut().find(|(d, _, _)| *d == device) {
            Some(entry) => {
                entry.1 = entry.1.saturating_add(bytes);
                entry.1
            }
            None => {
                by_device.push((device, bytes, path));
                bytes
            }
        };
        if total > free {
            let together = if total > bytes {
                format!(
                    " (with the other outputs on that file system, {})",
                    crate::budget::Bytes(total)
                )
            } else {
                String::new()
            };
            return Err(FileError::Refused {
                path: path.to_path_buf(),
                reason: format!(
                    "the file system of {} has {} free, and this output may take up to {}{together}",
                    dir.display(),
                    crate::budget::Bytes(free),
                    crate::budget::Bytes(bytes),
                ),
            });
        }
    }
    Ok(())
}

/// The file formats this crate writes images in. The name of an output
/// must say its format: a PNG is named `*.png`, an OpenEXR `*.exr` (any
/// case), so no file holds data its name misrepresents.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Exr,
}

impl Format {
    /// The extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Exr => "exr",
        }
    }

    fn name(self) -> &'static str {
        match self {
            Format::Png => "PNG",
            Format::Exr => "OpenEXR",
        }
    }
}

/// Checks that the name of `path` ends in `format`'s extension.
pub fn check_format(path: &Path, format: Format) -> Result<(), FileError> {
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned());
    if ext
        .as_deref()
        .is_some_and(|e| e.eq_ignore_ascii_case(format.extension()))
    {
        return Ok(());
    }
    let named = match ext {
        Some(e) => format!("the name ends in .{e}"),
        None => "the name has no extension".to_string(),
    };
    Err(FileError::Refused {
        path: path.to_path_buf(),
        reason: format!(
            "{named}, but this output is written as {}; name it *.{}",
            format.name(),
            format.extension()
        ),
    })
}

/// [`check_destination`] and [`check_format`]: what a command checks for
/// each image output before its work.
pub fn check_output(path: &Path, format: Format) -> Result<PathBuf, FileError> {
    // The destination first: that an output is an input is the more
    // important news.
    let dest = check_destination(path)?;
    check_format(path, format)?;
    Ok(dest)
}

/// Checks that `dir` is a folder or can be created as one (its nearest
/// existing ancestor is a folder), without creating anything.
pub fn check_output_dir(dir: &Path) -> Result<(), FileError> {
    let refuse = |reason: String| FileError::Refused {
        path: dir.to_path_buf(),
        reason,
    };
    check_writable(dir).map_err(refuse)?;
    let mut probe = dir;
    loop {
        match std::fs::metadata(probe) {
            // The folder, or the one it will be created in: a file must be
            // creatable there (not so in /proc or on a read-only mount).
            Ok(m) if m.is_dir() => {
                return probe_folder(probe).map_err(|e| {
                    refuse(format!(
                        "cannot create a file in folder {}: {e}",
                        probe.display()
                    ))
                })
            }
            Ok(_) if probe == dir => return Err(refuse("it exists and is not a folder".into())),
            Ok(_) => {
                return Err(refuse(format!(
                    "{} is not a folder, so the folder cannot be created",
                    probe.display()
                )))
            }
            // A symbolic link to nothing: the folder cannot be made there
            // (creating it fails, after the work).
            Err(_) if std::fs::symlink_metadata(probe).is_ok() => {
                let target = std::fs::read_link(probe)
                    .map_or_else(|_| "?".into(), |t| t.display().to_string());
                return Err(refuse(format!(
                    "{} is a symbolic link to a missing target ({target}), so the folder \
                     cannot be created; make the folder it names or remove the link",
                    probe.display()
                )));
            }
            Err(_) => match probe.parent() {
                Some(p) if !p.as_os_str().is_empty() => probe = p,
                // A relative path whose first component is missing: it is
                // created in the current folder.
                _ => {
                    return probe_folder(Path::new(".")).map_err(|e| {
                        refuse(format!("cannot create a file in the current folder: {e}"))
                    })
                }
            },
        }
    }
}

/// The longest path the kernel accepts (`PATH_MAX`, with its NUL).
const PATH_MAX: usize = 4095;

/// Whether `path` (a file or folder to be created or replaced) can be
/// written, as far as can be known before the work: every name within the
/// file system's limit (`NAME_MAX`, usually 255 bytes), the whole path
/// within `PATH_MAX`, and the nearest existing folder on the way writable
/// by this process (permissions, a read-only mount) and not on a full
/// file system.
pub fn check_writable(path: &Path) -> Result<(), String> {
    use std::os::unix::ffi::OsStrExt as _;
    let length = path.as_os_str().len();
    if length > PATH_MAX {
        return Err(format!(
            "the path is {length} bytes long; the system allows at most {PATH_MAX}"
        ));
    }
    let mut existing = parent(path);
    while std::fs::metadata(existing).is_err() {
        existing = parent(existing);
        if existing == Path::new(".") {
            break;
        }
    }
    let c = std::ffi::CString::new(existing.as_os_str().as_bytes())
        .map_err(|_| "the path contains a NUL byte".to_string())?;
    // SAFETY: pathconf(3) reads the NUL-terminated path and returns a
    // number; -1 (no limit or an error) is handled below.
    let name_max = unsafe { libc::pathconf(c.as_ptr(), libc::_PC_NAME_MAX) };
    let name_max = if name_max > 0 { name_max as usize } else { 255 };
    if let Some(name) = path
        .components()
        .map(|c| c.as_os_str())
        .find(|n| n.len() > name_max)
    {
        let shown: String = name.to_string_lossy().chars().take(24).collect();
        return Err(format!(
            "the name \"{shown}...\" is {} bytes long; this file system allows at most {name_max}",
            name.len()
        ));
    }
    // SAFETY: access(2) only reads the NUL-terminated path.
    if unsafe { libc::access(c.as_ptr(), libc::W_OK | libc::X_OK) } != 0 {
        let e = std::io::Error::last_os_error();
        return Err(format!(
            "folder {} is not writable: {e}",
            existing.display()
        ));
    }
    // SAFETY: statvfs(3) fills the zeroed struct for the NUL-terminated
    // path; it is read only when the call succeeds.
    let mut fs: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statvfs(c.as_ptr(), &mut fs) } == 0 && fs.f_bavail == 0 && fs.f_blocks > 0 {
        return Err(format!("the file system of {} is full", existing.display()));
    }
    Ok(())
}

fn parent(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// An output file being written under a temporary name. Dropping it
/// without [`PendingFile::commit`] removes the temporary file.
pub struct PendingFile {
    /// The path the caller asked for (used in messages).
    path: PathBuf,
    /// The file to replace (differs from `path` through a symbolic link).
    dest: PathBuf,
    tmp: Option<tempfile::NamedTempFile>,
}

impl PendingFile {
    /// Creates the temporary file for `path` (see [`check_destination`]).
    pub fn create(path: &Path) -> Result<PendingFile, FileError> {
        let dest = check_destination(path)?;
        let name = dest.file_name().unwrap_or_default().to_string_lossy();
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        #[cfg(unix)]
        {
            // The file gets the usual mode after the umask rather than
            // tempfile's owner-only default: it becomes a normal output.
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        // Registered under the lock, so an interrupt between creating and
        // registering cannot leave the file behind.
        let mut guard = pending();
        let tmp = builder
            .tempfile_in(parent(&dest))
            .map_err(|error| FileError::Io {
                path: path.to_path_buf(),
                error: without_temporary_name(error),
            })?;
        guard
            .get_or_insert_with(HashSet::new)
            .insert(tmp.path().to_path_buf());
        Ok(PendingFile {
            path: path.to_path_buf(),
            dest,
            tmp: Some(tmp),
        })
    }

    /// The path the caller asked for.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The temporary file to write into (`&File` is `Write` and `Seek`).
    pub fn file(&self) -> &File {
        self.tmp.as_ref().expect("present until commit").as_file()
    }

    /// An I/O error on this file, for callers' encoders.
    pub fn io_error(&self, error: std::io::Error) -> FileError {
        FileError::Io {
            path: self.path.clone(),
            error: without_temporary_name(error),
        }
    }

    /// Flushes the data to disk and renames the file into place. The
    /// destination is checked again, since it may have changed meanwhile.
    pub fn commit(self) -> Result<PathBuf, FileError> {
        self.commit_as(Listed::Yes)
    }

    /// [`PendingFile::commit`], listing the file among [`written`] or not.
    fn commit_as(self, listed: Listed) -> Result<PathBuf, FileError> {
        // A safe point: after an interrupt nothing more is committed.
        crate::interrupt::check().map_err(|_| interrupted(&self.path))?;
        let ready = self.prepare()?;
        ready.persist(&mut pending(), listed)
    }

    /// Everything before the rename: data flushed to disk (so a crash
    /// cannot leave a complete name pointing at incomplete data), the
    /// destination checked again, its permissions kept.
    fn prepare(mut self) -> Result<Ready, FileError> {
        let tmp = self.tmp.take().expect("present until commit");
        let io = |error| FileError::Io {
            path: self.path.clone(),
            error,
        };
        tmp.as_file().sync_all().map_err(io)?;
        let dest = destination(&self.path, false)?;
        if let Ok(meta) = std::fs::metadata(&dest) {
            // Replacing a file keeps its permissions.
            let _ = tmp.as_file().set_permissions(meta.permissions());
        }
        Ok(Ready {
            path: self.path.clone(),
            dest,
            tmp: Some(tmp),
        })
    }
}

/// A [`PendingFile`] ready to be renamed into place.
struct Ready {
    path: PathBuf,
    dest: PathBuf,
    tmp: Option<tempfile::NamedTempFile>,
}

impl Ready {
    /// Renames the file into place; `pending` is the locked set of
    /// temporary files, so an interrupt cannot run in the middle.
    fn persist(
        mut self,
        pending: &mut Option<HashSet<PathBuf>>,
        listed: Listed,
    ) -> Result<PathBuf, FileError> {
        let tmp = self.tmp.take().expect("present until persisted");
        let tmp_path = tmp.path().to_path_buf();
        let result = tmp.persist(&self.dest);
        if let Some(set) = pending.as_mut() {
            set.remove(&tmp_path);
        }
        // On failure `PersistError` hands the file back; dropping it removes it.
        result.map_err(|e| FileError::Io {
            path: self.path.clone(),
            error: without_temporary_name(e.error),
        })?;
        if listed == Listed::Yes {
            WRITTEN
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(self.path.clone());
        }
        Ok(self.path.clone())
    }
}

/// Whether a committed file is one of the command's outputs, listed by
/// [`written`], or state the program keeps for itself (a cache).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Listed {
    Yes,
    No,
}

/// Every output renamed into place by this process, in order.
static WRITTEN: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The outputs this process has written so far (complete files, renamed
/// into place), as named by the command: what a run stopped by an
/// interrupt or an error still leaves behind.
pub fn written() -> Vec<PathBuf> {
    WRITTEN.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Removes a temporary file that was never committed, and takes it off
/// the list an interrupt cleans up.
fn discard_pending(tmp: Option<tempfile::NamedTempFile>) {
    if let Some(tmp) = tmp {
        let mut guard = pending();
        if let Some(set) = guard.as_mut() {
            set.remove(tmp.path());
        }
        // NamedTempFile's own drop removes the file.
        drop(tmp);
    }
}

impl Drop for Ready {
    fn drop(&mut self) {
        discard_pending(self.tmp.take());
    }
}

impl Drop for PendingFile {
    fn drop(&mut self) {
        discard_pending(self.tmp.take());
        let _ = &self.dest;
    }
}

/// Commits every file, in order. If one fails, the ones already renamed
/// into place are removed again, so a failed run leaves none of its
/// outputs (a file they replaced is gone too: the run said it would
/// replace it). All the renames happen under the lock the interrupt
/// handler takes, so an interrupt leaves either none of the files or all
/// of them, never some. Returns the paths written.
pub fn commit_all(files: Vec<PendingFile>) -> Result<Vec<PathBuf>, FileError> {
    // A safe point: after an interrupt nothing more is committed.
    if let (Err(_), Some(first)) = (crate::interrupt::check(), files.first()) {
        return Err(interrupted(&first.path));
    }
    // The slow part (flushing to disk) before taking the lock.
    let ready = files
        .into_iter()
        .map(PendingFile::prepare)
        .collect::<Result<Vec<_>, _>>()?;
    let mut done = Vec::with_capacity(ready.len());
    let mut ready = ready.into_iter();
    let mut guard = pending();
    for file in ready.by_ref() {
        match file.persist(&mut guard, Listed::Yes) {
            Ok(path) => done.push(path),
            Err(e) => {
                for path in &done {
                    let _ = std::fs::remove_file(path);
                }
                // Unlock before the files not yet renamed are dropped:
                // dropping one takes the lock to unregister it.
                drop(guard);
                return Err(e);
            }
        }
    }
    Ok(done)
}

/// Writes `bytes` to `path` through a [`PendingFile`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<PathBuf, FileError> {
    write_bytes_as(path, bytes, Listed::Yes)
}

/// Writes `bytes` to `path` like [`write_bytes`], for a file the program
/// keeps for itself (a cache) rather than an output of the command: it is
/// not listed by [`written`], so an interrupted run does not name it among
/// what it wrote.
pub fn write_cache_bytes(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_bytes_as(path, bytes, Listed::No).map(|_| ())
}

fn write_bytes_as(path: &Path, bytes: &[u8], listed: Listed) -> Result<PathBuf, FileError> {
    use std::io::Write as _;
    let file = PendingFile::create(path)?;
    let mut w = std::io::BufWriter::new(file.file());
    w.write_all(bytes)
        .and_then(|()| w.flush())
        .map_err(|e| file.io_error(e))?;
    drop(w);
    file.commit_as(listed)
}

/// What a path that exists but is not a regular file is, for messages:
/// "a folder", "a FIFO (named pipe)", "a device", "a socket".
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    let t = meta.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// The end of the chain of symbolic links at `path` when it is an
/// anonymous pipe or socket, which no path can open again: `/dev/stdout`
/// links to `/proc/self/fd/1`, which links to `pipe:[N]` when the output
/// goes into a pipe (so do the `/dev/fd/N` of a shell's process
/// substitution).
fn anonymous_link(path: &Path) -> Option<String> {
    let mut link = path.to_path_buf();
    // The kernel's own limit on links followed in one lookup.
    for _ in 0..40 {
        let target = std::fs::read_link(&link).ok()?;
        let text = target.to_string_lossy();
        if ["pipe:", "socket:", "anon_inode:"]
            .iter()
            .any(|kind| text.starts_with(kind))
        {
            return Some(text.into_owned());
        }
        link = if target.is_absolute() {
            target
        } else {
            parent(&link).join(target)
        };
    }
    None
}

/// Why `path` cannot be read as an input file, or `None` when it is a
/// regular file (or a link to one): "file not found", "a symbolic link to
/// a missing target", or "not a regular file (a folder)" and its kind. The
/// message ends with the path.
pub fn input_file_problem(path: &Path) -> Option<String> {
    let Ok(link) = std::fs::symlink_metadata(path) else {
        return Some(format!("file not found: {}", path.display()));
    };
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => None,
        Ok(meta) => Some(format!(
            "not a regular file ({}): {}",
            kind_of(&meta),
            path.display()
        )),
        Err(_) if link.file_type().is_symlink() => Some(match anonymous_link(path) {
            Some(target) => format!(
                "a pipe or socket ({target}), not a regular file: {}",
                path.display()
            ),
            None => format!("a symbolic link to a missing target: {}", path.display()),
        }),
        Err(e) => Some(format!("cannot read {}: {e}", path.display())),
    }
}

/// Reads at most `limit` bytes of `path`: the file, or `Err(None)` when it
/// is longer (an endless device such as `/dev/zero` included). The file is
/// an input from then on (see [`note_inputs`]).
pub fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, Option<std::io::Error>> {
    let file = File::open(path).map_err(Some)?;
    note_inputs([path]);
    read_at_most(file, limit)
}

/// Reads at most `limit` bytes of an open `file`: its contents, or
/// `Err(None)` when it is longer. Unlike [`read_limited`] the file does not
/// become an input (a cache the run writes back reads through this).
pub fn read_at_most(file: File, limit: u64) -> Result<Vec<u8>, Option<std::io::Error>> {
    use std::io::Read as _;
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(Some)?;
    if bytes.len() as u64 > limit {
        return Err(None);
    }
    Ok(bytes)
}

/// Why a text input (a scene file, a view script) could not be read.
#[derive(Debug, thiserror::Error)]
pub enum TextReadError {
    #[error("{0}")]
    Io(std::io::Error),
    #[error("longer than {} (reading stopped there)", crate::budget::Bytes(*.0))]
    TooLong(u64),
    #[error("not UTF-8 text: byte 0x{byte:02x} at byte offset {offset} (line {line})")]
    NotUtf8 {
        byte: u8,
        offset: usize,
        line: usize,
    },
}

/// The text of `path`, read up to `limit` bytes (so an endless input is
/// refused instead of filling memory) and checked to be UTF-8, naming the
/// first bad byte's offset and line.
pub fn read_text(path: &Path, limit: u64) -> Result<String, TextReadError> {
    let bytes = read_limited(path, limit).map_err(|e| match e {
        Some(e) => TextReadError::Io(e),
        None => TextReadError::TooLong(limit),
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        TextReadError::NotUtf8 {
            byte: bytes[offset],
            offset,
            line: 1 + bytes[..offset].iter().filter(|&&b| b == b'\n').count(),
        }
    })
}

/// True when `a` and `b` name the same file (or would, once created):
/// the same device and inode when both exist (so a hard link counts),
/// otherwise the same resolved path.
pub fn same_file(a: &Path, b: &Path) -> bool {
    if let (Some(x), Some(y)) = (FileId::of(a), FileId::of(b)) {
        return x == y;
    }
    let resolve = |p: &Path| {
        std::fs::canonicalize(p).unwrap_or_else(|_| {
            let dir = std::fs::canonicalize(parent(p)).unwrap_or_else(|_| parent(p).into());
            dir.join(p.file_name().unwrap_or_default())
        })
    };
    resolve(a) == resolve(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("aerial-files-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn files_refuse_non_regular_destinations_and_missing_folders() {
        let d = dir("refuse");
        let msg = write_bytes(&d, b"x").unwrap_err().to_string();
        assert!(msg.contains("folder"), "{msg}");
        let msg = write_bytes(Path::new("/dev/null"), b"x")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("not a regular file"), "{msg}");
        let msg = write_bytes(&d.join("nodir/x"), b"x")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("nodir"), "{msg}");
        assert!(check_output_dir(&d.join("a/b")).is_ok());
        std::fs::write(d.join("f"), b"").unwrap();
        assert!(check_output_dir(&d.join("f")).is_err());
        assert!(check_output_dir(&d.join("f/sub")).is_err());
        std::os::unix::fs::symlink(d.join("gone"), d.join("dangling")).unwrap();
        for out in [d.join("dangling"), d.join("dangling/sub")] {
            let msg = check_output_dir(&out).unwrap_err().to_string();
            assert!(msg.contains("missing target"), "{msg}");
        }
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn files_refuse_an_output_that_is_a_protected_input_by_any_name() {
        let d = dir("inputs");
        std::fs::write(d.join("in.toml"), b"input").unwrap();
        std::fs::write(d.join("other.png"), b"other").unwrap();
        std::os::unix::fs::symlink(d.join("in.toml"), d.join("link.png")).unwrap();
        std::fs::hard_link(d.join("in.toml"), d.join("hard.png")).unwrap();
        // Not protected yet: any of them may be written.
        assert!(check_destination(&d.join("hard.png")).is_ok());
        protect_inputs([d.join("in.toml"), d.join("missing.toml")]);
        for name in ["in.toml", "link.png", "hard.png", "./in.toml"] {
            let path = d.join(name);
            let msg = write_bytes(&path, b"x").unwrap_err().to_string();
            assert!(msg.contains("input"), "{name}: {msg}");
        }
        let msg = check_destination(&d.join("link.png"))
            .unwrap_err()
            .to_string();
        assert!(msg.contains("same file as the input"), "{msg}");
        assert_eq!(std::fs::read(d.join("in.toml")).unwrap(), b"input");
        // Other files, and names that do not exist yet, are outputs as before.
        write_bytes(&d.join("other.png"), b"new").unwrap();
        write_bytes(&d.join("missing.toml"), b"new").unwrap();
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn files_match_inputs_only_while_their_path_leads_to_them() {
        let d = dir("stale");
        std::fs::write(d.join("in.obj"), b"input").unwrap();
        std::fs::hard_link(d.join("in.obj"), d.join("hard.json")).unwrap();
        assert!(same_file(&d.join("in.obj"), &d.join("hard.json")));
        assert!(same_file(&d.join("x.png"), &d.join("./x.png")));
        assert!(!same_file(&d.join("in.obj"), &d.join("x.png")));
        protect_inputs([d.join("in.obj")]);
        assert!(check_destination(&d.join("hard.json")).is_err());
        // The input is removed: its inode may be reused by a new file,
        // which is no input. The hard link is the only name left.
        std::fs::remove_file(d.join("in.obj")).unwrap();
        std::fs::rename(d.join("hard.json"), d.join("new.json")).unwrap();
        assert!(check_destination(&d.join("new.json")).is_ok());
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn files_refuse_names_of_folders_and_hide_temporary_names() {
        for name in ["o.png/", "o.png/.", "a/b//", "/"] {
            let msg = check_destination(Path::new(name)).unwrap_err().to_string();
            assert!(msg.contains(name), "{name}: {msg}");
        }
        assert!(not_a_file_name(Path::new("./o.png")).is_none());
        let tagged = std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "No such file or directory (os error 2) at path \"/proc/.o.png.x1.tmp\"",
        );
        let plain = without_temporary_name(tagged).to_string();
        assert_eq!(plain, "No such file or directory (os error 2)");
    }

    #[test]
    fn files_check_the_extension_of_each_format_in_any_case() {
        for (name, format, ok) in [
            ("a.png", Format::Png, true),
            ("a.PNG", Format::Png, true),
            ("a.Exr", Format::Exr, true),
            ("a.exr", Format::Png, false),
            ("a.jpg", Format::Png, false),
            ("a", Format::Png, false),
            ("a.png.tmp", Format::Png, false),
            ("a.png", Format::Exr, false),
        ] {
            let result = check_format(Path::new(name), format);
            assert_eq!(result.is_ok(), ok, "{name} as {format:?}: {result:?}");
        }
        let msg = check_format(Path::new("o.jpg"), Format::Png)
            .unwrap_err()
            .to_string();
        assert!(msg.contains(".jpg") && msg.contains("*.png"), "{msg}");
    }

    #[test]
    fn files_commit_all_or_nothing_and_leave_no_temporaries() {
        let d = dir("commit");
        let a = PendingFile::create(&d.join("a")).unwrap();
        std::io::Write::write_all(&mut a.file(), b"a").unwrap();
        let b = PendingFile::create(&d.join("b")).unwrap();
        // Make b's rename fail: its destination becomes a folder.
        std::fs::create_dir(d.join("b")).unwrap();
        assert!(commit_all(vec![a, b]).is_err());
        assert_eq!(entries(&d), ["b"]);
        // Dropped without commit: nothing left.
        drop(PendingFile::create(&d.join("c")).unwrap());
        assert_eq!(entries(&d), ["b"]);
        write_bytes(&d.join("c"), b"c").unwrap();
        assert_eq!(std::fs::read(d.join("c")).unwrap(), b"c");
        assert_eq!(entries(&d), ["b", "c"]);
        std::fs::remove_dir_all(&d).ok();
    }
}
