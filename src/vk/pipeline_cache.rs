//! The device's pipeline cache: one `VkPipelineCache` per [`super::Context`],
//! given to every graphics and compute pipeline it creates, and kept in a
//! file between runs so that a driver which stores its compiled pipelines
//! there need not compile them again.
//!
//! The file is named after what makes its contents valid: the device
//! (vendor and device id), the driver (its version and the device's
//! `pipelineCacheUUID`) and the build of aerial (its commit; a build from
//! a changed tree adds a hash of the executable's size and modification
//! time, so a rebuilt binary never reads what an older one left). It
//! holds a short header of its own (magic, length, SHA-256 of the data)
//! before the driver's data, so a truncated or altered file is recognised
//! before the driver sees it; the driver's own header (vendor, device,
//! UUID) is checked too. A file that fails a check is ignored with one
//! warning naming it; an unwritable folder costs one warning and the run
//! goes on without saving. The file is written at the end of the run,
//! atomically (see [`crate::safe_files`]), and only when the driver's data
//! differs from what was read.

use super::VkError;
use ash::vk;
use sha2::{Digest, Sha256};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The environment variable that overrides where the pipeline cache is
/// kept: a file, a folder, or `off`.
pub const PIPELINE_CACHE_ENV: &str = "AERIAL_PIPELINE_CACHE";

/// Where a context keeps its pipeline cache between runs.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum PipelineCacheStore {
    /// In memory only, for the context's lifetime: the library's default,
    /// and what `--no-pipeline-cache` and `AERIAL_PIPELINE_CACHE=off` ask.
    #[default]
    Memory,
    /// In a file of this folder named after the device, driver and build.
    Folder(PathBuf),
    /// In exactly this file, whatever device or build wrote it (its
    /// header is still checked against the device).
    File(PathBuf),
}

impl PipelineCacheStore {
    /// Where the command line keeps the cache: nowhere on disk when
    /// `disabled` (`--no-pipeline-cache`); otherwise as
    /// `AERIAL_PIPELINE_CACHE` says (`off`, a folder, or a file; a path
    /// ending in `/` or naming an existing folder is a folder); otherwise
    /// the folder `aerial` in the user's cache folder (`$XDG_CACHE_HOME`,
    /// else `~/.cache`).
    pub fn for_command_line(disabled: bool) -> PipelineCacheStore {
        if disabled {
            return PipelineCacheStore::Memory;
        }
        match std::env::var_os(PIPELINE_CACHE_ENV) {
            Some(value) if value == "off" => PipelineCacheStore::Memory,
            Some(value) if !value.is_empty() => {
                let path = PathBuf::from(&value);
                if value.to_string_lossy().ends_with('/') || path.is_dir() {
                    PipelineCacheStore::Folder(path)
                } else {
                    PipelineCacheStore::File(path)
                }
            }
            _ => match user_cache_folder() {
                Some(folder) => PipelineCacheStore::Folder(folder.join("aerial")),
                None => {
                    warn_once(format!(
                        "no pipeline cache on disk: neither XDG_CACHE_HOME nor HOME is set \
                         (set {PIPELINE_CACHE_ENV} to a folder to keep one)"
                    ));
                    PipelineCacheStore::Memory
                }
            },
        }
    }
}

/// `$XDG_CACHE_HOME`, else `$HOME/.cache`; relative values are ignored, as
/// the XDG base directory specification asks.
fn user_cache_folder() -> Option<PathBuf> {
    let absolute = |name: &str| {
        std::env::var_os(name)
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
    };
    absolute("XDG_CACHE_HOME").or_else(|| absolute("HOME").map(|h| h.join(".cache")))
}

/// The largest file read as a pipeline cache; anything longer is not one
/// of ours (drivers' caches of this renderer's few dozen pipelines are
/// far smaller).
const MAX_FILE_BYTES: u64 = 256 << 20;

/// The start of every cache file this module writes.
const MAGIC: &[u8; 8] = b"AERLPC01";

/// Our header: magic, data length (u64 little-endian), SHA-256 of the data.
const OUR_HEADER_BYTES: usize = 8 + 8 + 32;

/// `VkPipelineCacheHeaderVersionOne`: size, version, vendor, device, UUID.
const DRIVER_HEADER_BYTES: usize = 16 + vk::UUID_SIZE;

/// How many cache files a folder keeps: saving one removes the oldest
/// beyond this, so builds that come and go do not fill the disk.
const FILES_KEPT: usize = 8;

/// What a pipeline cache's data must start with to belong to a device.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct CacheIdentity {
    pub vendor_id: u32,
    pub device_id: u32,
    pub driver_version: u32,
    pub uuid: [u8; vk::UUID_SIZE],
}

impl CacheIdentity {
    pub fn of(props: &vk::PhysicalDeviceProperties) -> CacheIdentity {
        CacheIdentity {
            vendor_id: props.vendor_id,
            device_id: props.device_id,
            driver_version: props.driver_version,
            uuid: props.pipeline_cache_uuid,
        }
    }

    /// The file name for this device, driver and build.
    fn file_name(&self) -> String {
        let uuid: String = self.uuid.iter().map(|b| format!("{b:02x}")).collect();
        format!(
            "pipelines-{:x}-{:x}-{:x}-{uuid}-{}.bin",
            self.vendor_id,
            self.device_id,
            self.driver_version,
            build_key()
        )
    }

    /// Why `data` (the driver's part of a file) does not belong to this
    /// device, or `None` when its header matches.
    fn mismatch(&self, data: &[u8]) -> Option<String> {
        if data.len() < DRIVER_HEADER_BYTES {
            return Some(format!(
                "driver data of {} bytes, shorter than its {DRIVER_HEADER_BYTES}-byte header",
                data.len()
            ));
        }
        let word = |i: usize| u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().expect("4"));
        let (size, version, vendor, device) = (word(0), word(1), word(2), word(3));
        if (size as usize) < DRIVER_HEADER_BYTES || size as usize > data.len() {
            return Some(format!(
                "driver header size {size} out of range (file data {} bytes)",
                data.len()
            ));
        }
        if version != vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32 {
            return Some(format!("driver header version {version}, expected 1"));
        }
        if (vendor, device) != (self.vendor_id, self.device_id) {
            return Some(format!(
                "written for device {vendor:04x}:{device:04x}, this is {:04x}:{:04x}",
                self.vendor_id, self.device_id
            ));
        }
        if data[16..DRIVER_HEADER_BYTES] != self.uuid {
            return Some("written by another driver (pipelineCacheUUID differs)".into());
        }
        None
    }
}

/// What names this build: its commit, and for a build from a changed tree
/// (or one outside git) a hash of the executable's size and modification
/// time too, since the commit alone does not tell two such builds apart.
fn build_key() -> String {
    let commit = crate::COMMIT;
    let clean = commit != "unknown" && !commit.ends_with("-dirty");
    let safe: String = commit
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    if clean {
        return safe;
    }
    let stamp = std::env::current_exe()
        .and_then(std::fs::metadata)
        .map(|m| {
            let modified = m
                .modified()
                .ok()
                .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                .unwrap_or_default();
            format!("{} {}", m.len(), modified.as_nanos())
        })
        // No executable to look at: a key no other build shares.
        .unwrap_or_else(|_| format!("pid {}", std::process::id()));
    let hash = Sha256::digest(stamp.as_bytes());
    let short: String = hash[..8].iter().map(|b| format!("{b:02x}")).collect();
    format!("{safe}-{short}")
}

/// Prints `message` as a warning, once per process: a benchmark makes
/// many devices, and the same unreadable file or folder needs saying once.
fn warn_once(message: String) {
    static SAID: Mutex<Option<HashSet<String>>> = Mutex::new(None);
    let mut said = SAID.lock().unwrap_or_else(|p| p.into_inner());
    if said
        .get_or_insert_with(HashSet::new)
        .insert(message.clone())
    {
        eprintln!("warning: {message}");
    }
}

/// The driver's data in a cache file's bytes, or why there is none to use.
fn parse_file(bytes: &[u8], identity: &CacheIdentity) -> Result<Vec<u8>, String> {
    if bytes.len() < OUR_HEADER_BYTES || &bytes[..8] != MAGIC {
        return Err("not an aerial pipeline cache (no header)".into());
    }
    let length = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
    let data = &bytes[OUR_HEADER_BYTES..];
    if length != data.len() as u64 {
        return Err(format!(
            "truncated or extended: {} bytes of data, the header says {length}",
            data.len()
        ));
    }
    if Sha256::digest(data).as_slice() != &bytes[16..OUR_HEADER_BYTES] {
        return Err("its data does not match its checksum".into());
    }
    if let Some(reason) = identity.mismatch(data) {
        return Err(reason);
    }
    Ok(data.to_vec())
}

/// The bytes of a cache file holding the driver's `data`.
fn file_bytes(data: &[u8]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(OUR_HEADER_BYTES + data.len());
    bytes.extend_from_slice(MAGIC);
    bytes.extend_from_slice(&(data.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&Sha256::digest(data));
    bytes.extend_from_slice(data);
    bytes
}

/// The cache file's contents, or `None` (with a warning when the file
/// exists but cannot be used). Read directly rather than through the
/// crate's input readers: the run writes this file back, so it must not
/// be recorded as one of the inputs no output may replace.
fn read_file(path: &Path, identity: &CacheIdentity) -> Option<Vec<u8>> {
    let warn = |reason: String| {
        warn_once(format!(
            "pipeline cache {} ignored: {reason}; pipelines are compiled afresh",
            path.display()
        ))
    };
    // No file yet (or a folder that cannot be reached, which saving will
    // report): nothing to read, nothing to say.
    if std::fs::metadata(path).is_err() {
        return None;
    }
    let file = match std::fs::File::open(path) {
        Ok(f) => f,
        Err(e) => {
            warn(e.to_string());
            return None;
        }
    };
    let bytes = match crate::safe_files::read_at_most(file, MAX_FILE_BYTES) {
        Ok(bytes) => bytes,
        Err(Some(e)) => {
            warn(e.to_string());
            return None;
        }
        Err(None) => {
            warn(format!(
                "longer than {}",
                crate::budget::Bytes(MAX_FILE_BYTES)
            ));
            return None;
        }
    };
    match parse_file(&bytes, identity) {
        Ok(data) => Some(data),
        Err(reason) => {
            warn(reason);
            None
        }
    }
}

/// A `VkPipelineCache` and where it is kept. Owned by the context, which
/// drops it (saving it first) before destroying the device.
pub(crate) struct PipelineCache {
    device: ash::Device,
    pub(crate) handle: vk::PipelineCache,
    /// The file it was read from and is saved to; `None` in memory only.
    file: Option<PathBuf>,
    identity: CacheIdentity,
    /// The driver's data as read (empty when none was): saving the same
    /// again is skipped.
    loaded: Vec<u8>,
}

impl PipelineCache {
    /// The cache of `device`, with the data of `store`'s file when it
    /// holds usable data for this device.
    pub fn new(
        device: &ash::Device,
        identity: CacheIdentity,
        store: &PipelineCacheStore,
    ) -> Result<PipelineCache, VkError> {
        let file = match store {
            PipelineCacheStore::Memory => None,
            PipelineCacheStore::Folder(folder) => Some(folder.join(identity.file_name())),
            PipelineCacheStore::File(file) => Some(file.clone()),
        };
        let loaded = file
            .as_deref()
            .and_then(|f| read_file(f, &identity))
            .unwrap_or_default();
        let create = |data: &[u8]| {
            let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
            // SAFETY: `device` is a live device; `data` is either empty or
            // starts with a header checked above against this device, and
            // outlives the call.
            unsafe { device.create_pipeline_cache(&info, None) }
        };
        let handle = match create(&loaded) {
            Ok(handle) => handle,
            // The spec lets a driver ignore data it does not like, but a
            // driver that refuses it instead gets an empty cache.
            Err(e) if !loaded.is_empty() => {
                warn_once(format!(
                    "pipeline cache {} ignored: the driver refused its data ({e})",
                    file.as_deref().unwrap_or(Path::new("")).display()
                ));
                create(&[])?
            }
            Err(e) => return Err(e.into()),
        };
        if let (Some(f), false) = (&file, loaded.is_empty()) {
            log::info!(
                "pipeline cache: read {} bytes from {}",
                loaded.len(),
                f.display()
            );
        }
        Ok(PipelineCache {
            device: device.clone(),
            handle,
            file,
            identity,
            loaded,
        })
    }

    /// The driver's data now: what it has compiled so far.
    fn data(&self) -> Result<Vec<u8>, vk::Result> {
        // SAFETY: the handle is a live cache of this device; no pipeline is
        // being created concurrently (creation borrows the context, which
        // is being dropped when this runs).
        unsafe { self.device.get_pipeline_cache_data(self.handle) }
    }

    /// Writes the driver's data to the file when it differs from what was
    /// read. Failures are warnings: a run never fails over its cache.
    fn save(&self) {
        let Some(path) = &self.file else { return };
        let data = match self.data() {
            Ok(data) => data,
            Err(e) => {
                warn_once(format!("pipeline cache not saved: the driver said {e}"));
                return;
            }
        };
        // A driver that answers with something else than a header of this
        // device (or nothing) has nothing worth keeping.
        if data == self.loaded || self.identity.mismatch(&data).is_some() {
            return;
        }
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let written = std::fs::create_dir_all(folder)
            .map_err(|e| format!("cannot make folder {}: {e}", folder.display()))
            .and_then(|()| {
                crate::safe_files::write_cache_bytes(path, &file_bytes(&data))
                    .map_err(|e| e.to_string())
            });
        match written {
            Ok(()) => {
                log::info!(
                    "pipeline cache: wrote {} bytes to {}",
                    data.len(),
                    path.display()
                );
                prune(folder, path);
            }
            // Interrupted: the run is ending without its outputs; the cache
            // simply is not saved, which needs no word.
            Err(_) if crate::interrupt::requested() => {}
            Err(e) => warn_once(format!(
                "pipeline cache not saved ({e}); the next run compiles its pipelines again"
            )),
        }
    }
}

/// Removes the oldest cache files of `folder` beyond [`FILES_KEPT`],
/// never `keep` (the one just written). Only files named as this module
/// names them are touched.
fn prune(folder: &Path, keep: &Path) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    let mut files: Vec<(std::time::SystemTime, PathBuf)> = entries
        .flatten()
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            name.starts_with("pipelines-") && name.ends_with(".bin")
        })
        .filter_map(|e| {
            let modified = e.metadata().ok()?.modified().ok()?;
            Some((modified, e.path()))
        })
        .collect();
    if files.len() <= FILES_KEPT {
        return;
    }
    files.sort_by_key(|f| std::cmp::Reverse(f.0));
    for (_, path) in files.into_iter().skip(FILES_KEPT) {
        if path != keep {
            let _ = std::fs::remove_file(path);
        }
    }
}

impl Drop for PipelineCache {
    fn drop(&mut self) {
        self.save();
        // SAFETY: the context drops this after the device is idle and every
        // pipeline creation has returned, and before destroying the device.
        unsafe { self.device.destroy_pipeline_cache(self.handle, None) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity() -> CacheIdentity {
        CacheIdentity {
            vendor_id: 0x10005,
            device_id: 0,
            driver_version: 1,
            uuid: [7; vk::UUID_SIZE],
        }
    }

    /// Driver data with a header of `identity` and `extra` bytes after it.
    fn driver_data(identity: &CacheIdentity, extra: &[u8]) -> Vec<u8> {
        let mut data = Vec::new();
        for word in [
            DRIVER_HEADER_BYTES as u32,
            1,
            identity.vendor_id,
            identity.device_id,
        ] {
            data.extend_from_slice(&word.to_le_bytes());
        }
        data.extend_from_slice(&identity.uuid);
        data.extend_from_slice(extra);
        data
    }

    #[test]
    fn a_written_file_reads_back() {
        let id = identity();
        let data = driver_data(&id, b"compiled pipelines");
        assert_eq!(parse_file(&file_bytes(&data), &id), Ok(data));
    }

    #[test]
    fn truncated_altered_and_foreign_files_are_refused() {
        let id = identity();
        let bytes = file_bytes(&driver_data(&id, b"compiled pipelines"));
        let truncated = &bytes[..bytes.len() - 3];
        assert!(parse_file(truncated, &id)
            .unwrap_err()
            .contains("truncated"));
        let mut altered = bytes.clone();
        *altered.last_mut().unwrap() ^= 1;
        assert!(parse_file(&altered, &id).unwrap_err().contains("checksum"));
        assert!(parse_file(b"junk", &id).unwrap_err().contains("no header"));
        assert!(parse_file(&[], &id).is_err());

        let other_device = CacheIdentity {
            device_id: 9,
            ..identity()
        };
        let foreign = file_bytes(&driver_data(&other_device, b""));
        assert!(parse_file(&foreign, &id).unwrap_err().contains("device"));
        let other_driver = CacheIdentity {
            uuid: [8; vk::UUID_SIZE],
            ..identity()
        };
        let foreign = file_bytes(&driver_data(&other_driver, b""));
        assert!(parse_file(&foreign, &id).unwrap_err().contains("UUID"));
        let short = file_bytes(&driver_data(&id, b"")[..20]);
        assert!(parse_file(&short, &id).unwrap_err().contains("shorter"));
    }

    #[test]
    fn file_names_tell_devices_and_drivers_apart() {
        let a = identity().file_name();
        let b = CacheIdentity {
            driver_version: 2,
            ..identity()
        }
        .file_name();
        assert_ne!(a, b);
        assert!(a.starts_with("pipelines-10005-0-1-0707"), "{a}");
        assert!(a.ends_with(".bin"));
        assert!(!a.contains('/'));
    }
}
