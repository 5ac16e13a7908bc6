//! Validation-layer messages, counted.
//!
//! Every run that enables `VK_LAYER_KHRONOS_validation` installs a debug-utils
//! messenger that records each warning and error. A run that produced any
//! message that is not on the reviewed allow-list is a failed run: the CLI
//! exits non-zero and the tests assert the log is empty.

use ash::vk;
use std::ffi::CStr;
use std::sync::{Condvar, Mutex};
use std::thread::ThreadId;

/// Which checks of `VK_LAYER_KHRONOS_validation` a run enables.
///
/// `Core` is the layer's default set (parameter, object lifetime and
/// state checks); the other modes add `VK_EXT_validation_features` enables
/// on top of it. `All` is what `--validate` without a mode means and what
/// the test suite runs under.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Validation {
    /// No layer, no messenger.
    #[default]
    #[value(skip)]
    Off,
    /// The layer's core checks only.
    Core,
    /// Core checks plus synchronization validation (hazards between
    /// commands that lack a barrier).
    Sync,
    /// Core checks plus best-practices warnings.
    BestPractices,
    /// Core, synchronization and best practices.
    All,
}

impl Validation {
    /// Whether the validation layer is loaded at all.
    pub fn is_on(self) -> bool {
        self != Validation::Off
    }

    /// The `VK_EXT_validation_features` enables this mode chains into
    /// instance creation.
    pub(crate) fn enabled_features(self) -> &'static [vk::ValidationFeatureEnableEXT] {
        use vk::ValidationFeatureEnableEXT as F;
        match self {
            Validation::Off | Validation::Core => &[],
            Validation::Sync => &[F::SYNCHRONIZATION_VALIDATION],
            Validation::BestPractices => &[F::BEST_PRACTICES],
            Validation::All => &[F::SYNCHRONIZATION_VALIDATION, F::BEST_PRACTICES],
        }
    }
}

/// A run failed because the layer reported messages; its `Display` lists
/// them, so printing the error shows every message.
#[derive(Debug, thiserror::Error)]
#[error("{} validation message(s):\n{}", .messages.len(), list(.messages))]
pub struct ValidationFailed {
    pub messages: Vec<ValidationMessage>,
}

fn list(messages: &[ValidationMessage]) -> String {
    messages
        .iter()
        .map(|m| format!("  {m}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The one rule every command applies to a finished run: any counted
/// message fails it.
pub fn check(messages: &[ValidationMessage]) -> Result<(), ValidationFailed> {
    if messages.is_empty() {
        Ok(())
    } else {
        Err(ValidationFailed {
            messages: messages.to_vec(),
        })
    }
}

/// Messages that are known, reviewed and harmless, keyed by VUID (the
/// layer's `pMessageIdName`), each with the reason it is allowed.
///
/// Keep this list short; every entry needs a reason a reviewer can check.
pub const ALLOWED_MESSAGES: &[(&str, &str)] = &[(
    "UNASSIGNED-BestPractices-vkCreateInstance-specialuse-extension-debugging",
    "best practices warns about enabling VK_EXT_debug_utils and \
     VK_EXT_validation_features, which are debugging extensions; a \
     validated run needs both (the messenger that counts messages, and the \
     synchronization and best-practices enables), and runs without \
     validation enable neither",
)];

/// One message the validation layer emitted.
#[derive(Clone, Debug)]
pub struct ValidationMessage {
    pub severity: &'static str,
    pub id_name: String,
    pub text: String,
}

impl std::fmt::Display for ValidationMessage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{}] {}: {}", self.severity, self.id_name, self.text)
    }
}

/// The shared record of validation messages for one instance.
///
/// It is boxed and its address handed to the layer as user data, so it must
/// outlive the instance; [`super::Context`] owns it and drops it last.
#[derive(Default, Debug)]
pub struct ValidationLog {
    messages: Mutex<Vec<ValidationMessage>>,
    allowed: Mutex<usize>,
}

impl ValidationLog {
    /// Every counted (not allowed) message so far.
    pub fn messages(&self) -> Vec<ValidationMessage> {
        self.messages.lock().map(|m| m.clone()).unwrap_or_default()
    }

    /// How many messages matched the allow-list and were not counted.
    pub fn allowed_count(&self) -> usize {
        self.allowed.lock().map(|a| *a).unwrap_or(0)
    }

    fn record(&self, message: ValidationMessage) {
        if ALLOWED_MESSAGES
            .iter()
            .any(|(id, _)| *id == message.id_name)
        {
            if let Ok(mut a) = self.allowed.lock() {
                *a += 1;
            }
            return;
        }
        log::debug!("validation: {message}");
        if let Ok(mut m) = self.messages.lock() {
            m.push(message);
        }
    }
}

/// The severities the messenger reports: warnings and errors are counted;
/// info and verbose messages are not requested at all.
pub(crate) fn counted_severities() -> vk::DebugUtilsMessageSeverityFlagsEXT {
    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
}

pub(crate) fn counted_types() -> vk::DebugUtilsMessageTypeFlagsEXT {
    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
}

/// The messenger callback.
///
/// # Safety
/// Called by the validation layer with `user_data` pointing at the
/// `ValidationLog` owned by the `Context`, which outlives the instance.
pub(crate) unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut std::ffi::c_void,
) -> vk::Bool32 {
    if data.is_null() || user_data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the layer passes a valid callback-data struct for the duration
    // of the call, and user_data is the ValidationLog we registered.
    let (data, log) = unsafe { (&*data, &*(user_data as *const ValidationLog)) };
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: non-null strings from the layer are NUL-terminated.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let severity = if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        "error"
    } else {
        "warning"
    };
    log.record(ValidationMessage {
        severity,
        id_name: text(data.p_message_id_name),
        text: text(data.p_message),
    });
    vk::FALSE
}

/// Which thread may use the validation layer, and how many of its contexts
/// hold it.
static LAYER_OWNER: Mutex<Option<(ThreadId, usize)>> = Mutex::new(None);
static LAYER_FREED: Condvar = Condvar::new();

/// One validated context's hold on the validation layer: while it lives,
/// contexts with validation are created and used by one thread of the
/// process at a time.
///
/// Why: `VK_LAYER_KHRONOS_validation` 1.3.239 crashed (two threads
/// segfaulting inside the layer at the same instant) when two tests of one
/// process ran validated contexts in parallel threads. One context per
/// process, as the CLI runs, never waits. The hold is reentrant for its
/// thread, so a thread may keep one context while it builds another (a
/// test comparing two renderers); another thread waits until the holder's
/// last validated context is dropped.
pub(crate) struct LayerHold;

impl LayerHold {
    pub(crate) fn acquire() -> LayerHold {
        let me = std::thread::current().id();
        let mut owner = LAYER_OWNER.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            match owner.as_mut() {
                None => {
                    *owner = Some((me, 1));
                    break;
                }
                Some((thread, count)) if *thread == me => {
                    *count += 1;
                    break;
                }
                Some(_) => {
                    owner = LAYER_FREED.wait(owner).unwrap_or_else(|e| e.into_inner());
                }
            }
        }
        LayerHold
    }
}

impl Drop for LayerHold {
    fn drop(&mut self) {
        // Counted, not tied to the dropping thread: an `Arc<Context>` may
        // be dropped on another thread than the one that made it.
        let mut owner = LAYER_OWNER.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, count)) = owner.as_mut() {
            *count -= 1;
            if *count == 0 {
                *owner = None;
                LAYER_FREED.notify_all();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::LayerHold;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    use std::time::Duration;

    /// A second thread waits for the first thread's holds to end; the
    /// first thread may hold twice (a context kept while another is built).
    #[test]
    fn the_layer_hold_is_reentrant_and_excludes_other_threads() {
        let outer = LayerHold::acquire();
        let inner = LayerHold::acquire();
        let entered = Arc::new(AtomicBool::new(false));
        let other = {
            let entered = entered.clone();
            std::thread::spawn(move || {
                let _hold = LayerHold::acquire();
                entered.store(true, Ordering::SeqCst);
            })
        };
        std::thread::sleep(Duration::from_millis(100));
        assert!(!entered.load(Ordering::SeqCst), "entered while held twice");
        drop(inner);
        std::thread::sleep(Duration::from_millis(100));
        assert!(!entered.load(Ordering::SeqCst), "entered while held once");
        drop(outer);
        other.join().unwrap();
        assert!(entered.load(Ordering::SeqCst));
    }
}
