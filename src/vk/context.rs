//! Instance, physical device, logical device, queue and allocator.
//!
//! `Context` is the root of every Vulkan object the renderer creates. Other
//! wrappers hold an `Arc<Context>` so the device outlives them; `Context`
//! itself tears down in the only valid order: wait idle, allocator, device,
//! messenger, instance, then the validation log the layer wrote into.

use super::pipeline_cache::{CacheIdentity, PipelineCache, PipelineCacheStore};
use super::validation::{self, Validation, ValidationLog};
use super::VkError;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_char, CStr, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a [`Context`].
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Which checks of `VK_LAYER_KHRONOS_validation` to enable; with any
    /// but `Off`, its messages are counted.
    pub validate: Validation,
    /// Pick a physical device by index or by a case-insensitive substring of
    /// its name; `None` takes the first device.
    pub device: Option<String>,
    /// Present to windows of this display: the instance enables the
    /// surface extensions the display needs and the device
    /// `VK_KHR_swapchain` (see [`super::Surface`]). `None` for headless
    /// runs, which enable neither.
    pub display: Option<raw_window_handle::RawDisplayHandle>,
    /// Enable pipeline-statistics queries ([`super::PipelineStatsQueries`]);
    /// a device without them is refused.
    pub pipeline_statistics: bool,
    /// Where the device's pipeline cache is kept between runs; in memory
    /// only by default.
    pub pipeline_cache: PipelineCacheStore,
}

/// What identifies the device an output came from; recorded with every
/// output that gets compared, since bit-identical renders are only promised
/// on the same driver.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DeviceInfo {
    pub name: String,
    pub driver_name: String,
    pub driver_info: String,
    pub driver_version: u32,
    pub api_version: String,
    pub timestamp_period_ns: f32,
    pub timestamp_valid_bits: u32,
    /// A CPU implementation (lavapipe, llvmpipe, SwiftShader): its "GPU"
    /// work is the host's instructions, which can be counted.
    pub cpu: bool,
}

/// The Vulkan instance, device and allocator, owned together.
pub struct Context {
    // Field order does not matter for drop: Drop below destroys explicitly.
    pub(crate) entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) physical_device: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Given to every pipeline creation; saved and destroyed in Drop
    /// before the device.
    pipeline_cache: ManuallyDrop<PipelineCache>,
    pub(crate) limits: vk::PhysicalDeviceLimits,
    info: DeviceInfo,
    /// Created with [`ContextOptions::pipeline_statistics`].
    pipeline_statistics: bool,
    /// Occlusion queries count exactly (`occlusionQueryPrecise`, enabled
    /// with pipeline statistics where the device has it).
    occlusion_precise: bool,
    validation_log: Option<Arc<ValidationLog>>,
    // Released after Drop::drop destroyed the device and the instance.
    _layer_hold: Option<validation::LayerHold>,
    // Likewise: until then an interrupt waits for a safe point.
    _busy: crate::interrupt::Busy,
}

impl Context {
    pub fn new(options: &ContextOptions) -> Result<Arc<Context>, VkError> {
        // From the loader on, an interrupt must not end the process without
        // the run reaching a safe point (see `crate::interrupt`).
        let busy = crate::interrupt::Busy::start();
        // SAFETY: loading the system Vulkan loader; no Vulkan calls were made
        // before, and the entry is kept alive as long as the instance.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| VkError::Loader(e.to_string()))?;

        let validate = options.validate.is_on();
        // Before the layer is loaded: see `LayerHold`.
        let layer_hold = validate.then(validation::LayerHold::acquire);
        let validation_log = validate.then(|| Arc::new(ValidationLog::default()));
        if validate {
            // SAFETY: plain query of the loader.
            let layers = unsafe { entry.enumerate_instance_layer_properties() }?;
            let found = layers
                .iter()
                .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
            if !found {
                return Err(VkError::MissingValidationLayer);
            }
        }

        let app_name = CString::new("aerial").expect("static name has no NUL");
        let app_info = vk::ApplicationInfo::default()
            .application_name(&app_name)
            .application_version(1)
            .engine_name(&app_name)
            .api_version(vk::API_VERSION_1_2);

        let layer_names: Vec<*const c_char> = if validate {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let mut extension_names: Vec<*const c_char> = if validate {
            vec![
                ash::ext::debug_utils::NAME.as_ptr(),
                ash::ext::validation_features::NAME.as_ptr(),
            ]
        } else {
            vec![]
        };
        if let Some(display) = options.display {
            // Static C strings of ash-window: VK_KHR_surface and the one
            // for this window system.
            let needed = ash_window::enumerate_required_extensions(display)
                .map_err(|e| VkError::Surface(format!("this window system: {e}")))?;
            extension_names.extend_from_slice(needed);
        }
        let mut validation_features = vk::ValidationFeaturesEXT::default()
            .enabled_validation_features(options.validate.enabled_features());
        let user_data = validation_log.as_ref().map_or(std::ptr::null_mut(), |l| {
            Arc::as_ptr(l) as *mut std::ffi::c_void
        });
        let messenger_info = || {
            vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(validation::counted_severities())
                .message_type(validation::counted_types())
                .pfn_user_callback(Some(validation::debug_callback))
                .user_data(user_data)
        };
        // A separate copy for the instance chain: push_next links it to the
        // other chained structs, and the messenger's own create info must
        // have no pNext.
        let mut instance_messenger_info = messenger_info();

        let mut instance_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&extension_names);
        if validate {
            // Chaining the messenger into instance creation also reports
            // messages from vkCreateInstance / vkDestroyInstance.
            instance_info = instance_info
                .push_next(&mut validation_features)
                .push_next(&mut instance_messenger_info);
        }
        // SAFETY: every pointer in instance_info refers to locals alive for
        // the call.
        let instance = unsafe { entry.create_instance(&instance_info, None) }?;

        let debug = if validate {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            // SAFETY: the user data (the ValidationLog) outlives the messenger
            // because Context drops it after destroying the instance.
            match unsafe { loader.create_debug_utils_messenger(&messenger_info(), None) } {
                Ok(m) => Some((loader, m)),
                Err(e) => {
                    // SAFETY: nothing else was created from this instance.
                    unsafe { instance.destroy_instance(None) };
                    return Err(e.into());
                }
            }
        } else {
            None
        };

        // From here on, partial construction is cleaned up by PartialInstance.
        let partial = PartialInstance {
            instance: Some(instance),
            debug,
            validation_log,
            entry: Some(entry),
            layer_hold,
            busy: Some(busy),
        };
        partial.finish(options)
    }

    /// The device this context renders on.
    pub fn device_info(&self) -> &DeviceInfo {
        &self.info
    }

    /// Whether frames count each pass's pipeline statistics (the context
    /// was created with [`ContextOptions::pipeline_statistics`]).
    pub fn pipeline_statistics(&self) -> bool {
        self.pipeline_statistics
    }

    /// Whether occlusion queries count exactly rather than only zero or
    /// not (enabled together with pipeline statistics, where supported).
    pub fn occlusion_precise(&self) -> bool {
        self.occlusion_precise
    }

    /// The validation messages counted so far; `None` without `--validate`.
    pub fn validation_log(&self) -> Option<Arc<ValidationLog>> {
        self.validation_log.clone()
    }

    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        // A poisoned allocator means a panic mid-allocation; continuing with
        // its state is still memory-safe, so take it.
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The pipeline cache every pipeline of this device is created with.
    pub(crate) fn pipeline_cache(&self) -> vk::PipelineCache {
        self.pipeline_cache.handle
    }

    /// The alignment of dynamic uniform-buffer offsets.
    pub fn uniform_offset_alignment(&self) -> u64 {
        self.limits.min_uniform_buffer_offset_alignment
    }

    /// The largest range a uniform-buffer descriptor may cover.
    pub fn max_uniform_range(&self) -> u64 {
        self.limits.max_uniform_buffer_range as u64
    }

    /// Blocks until the queue is idle.
    pub fn wait_idle(&self) -> Result<(), VkError> {
        // SAFETY: the device is alive for &self.
        unsafe { self.device.device_wait_idle() }?;
        Ok(())
    }
}

/// An instance (and messenger) whose device is not created yet; destroys
/// them if device selection fails.
struct PartialInstance {
    instance: Option<ash::Instance>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    // Dropped after Drop::drop destroyed the instance, which may still call
    // the messenger with this as user data.
    validation_log: Option<Arc<ValidationLog>>,
    // The loader library: dropping it unloads the code that destroying the
    // instance calls into, so it must outlive the instance. As a field it
    // is dropped after Drop::drop has destroyed the instance; as a separate
    // argument of `finish` it was dropped first on the error path (crash).
    entry: Option<ash::Entry>,
    // Released after the instance is destroyed, on the error path too.
    layer_hold: Option<validation::LayerHold>,
    busy: Option<crate::interrupt::Busy>,
}

impl PartialInstance {
    fn finish(mut self, options: &ContextOptions) -> Result<Arc<Context>, VkError> {
        let instance = self.instance.as_ref().expect("set in new");
        let (physical_device, props) = pick_physical_device(instance, options.device.as_deref())?;
        let queue_family = graphics_queue_family(instance, physical_device)?;

        let priorities = [1.0f32];
        let queue_infos = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        // Features to enable must be chosen from what the device reports
        // (best-practices validation warns when vkCreateDevice comes
        // without this query). Optional features: pipeline statistics and
        // with them exact occlusion counts where supported (`--metric work`).
        // SAFETY: valid physical device of this instance.
        let supported = unsafe { instance.get_physical_device_features(physical_device) };
        if options.pipeline_statistics && supported.pipeline_statistics_query == vk::FALSE {
            return Err(VkError::Unsupported(format!(
                "{}: no pipeline-statistics queries (needed for --metric work)",
                c_chars(&props.device_name)
            )));
        }
        let occlusion_precise =
            options.pipeline_statistics && supported.occlusion_query_precise == vk::TRUE;
        let features = vk::PhysicalDeviceFeatures::default()
            .pipeline_statistics_query(options.pipeline_statistics)
            .occlusion_query_precise(occlusion_precise);
        let device_extensions: Vec<*const c_char> = if options.display.is_some() {
            vec![ash::khr::swapchain::NAME.as_ptr()]
        } else {
            vec![]
        };
        let device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_infos)
            .enabled_extension_names(&device_extensions)
            .enabled_features(&features);
        // SAFETY: physical_device comes from this instance; create info
        // points at locals.
        let device = unsafe { instance.create_device(physical_device, &device_info, None) }?;
        // SAFETY: family and index 0 were requested above.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let pipeline_cache =
            match PipelineCache::new(&device, CacheIdentity::of(&props), &options.pipeline_cache) {
                Ok(cache) => cache,
                Err(e) => {
                    // SAFETY: the device has no children yet.
                    unsafe { device.destroy_device(None) };
                    return Err(e);
                }
            };

        let allocator = match Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        }) {
            Ok(a) => a,
            Err(e) => {
                // Dropped first: it saves (nothing yet) and destroys the
                // cache, the device's only child.
                drop(pipeline_cache);
                // SAFETY: the device has no children left.
                unsafe { device.destroy_device(None) };
                return Err(e.into());
            }
        };

        let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
        // SAFETY: Vulkan 1.1+ query on a valid physical device.
        unsafe { instance.get_physical_device_properties2(physical_device, &mut props2) };
        let queue_props =
            // SAFETY: valid physical device.
            unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let info = DeviceInfo {
            name: c_chars(&props.device_name),
            driver_name: c_chars(&driver_props.driver_name),
            driver_info: c_chars(&driver_props.driver_info),
            driver_version: props.driver_version,
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(props.api_version),
                vk::api_version_minor(props.api_version),
                vk::api_version_patch(props.api_version)
            ),
            timestamp_period_ns: props.limits.timestamp_period,
            timestamp_valid_bits: queue_props[queue_family as usize].timestamp_valid_bits,
            cpu: props.device_type == vk::PhysicalDeviceType::CPU,
        };
        log::info!(
            "device: {} ({} {}), Vulkan {}",
            info.name,
            info.driver_name,
            info.driver_info,
            info.api_version
        );

        Ok(Arc::new(Context {
            entry: self.entry.take().expect("set in new"),
            instance: self.instance.take().expect("set in new"),
            debug: self.debug.take(),
            physical_device,
            device,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            pipeline_cache: ManuallyDrop::new(pipeline_cache),
            limits: props.limits,
            info,
            pipeline_statistics: options.pipeline_statistics,
            occlusion_precise,
            validation_log: self.validation_log.clone(),
            _layer_hold: self.layer_hold.take(),
            _busy: self.busy.take().expect("set in new"),
        }))
    }
}

impl Drop for PartialInstance {
    fn drop(&mut self) {
        if let Some(instance) = self.instance.take() {
            // SAFETY: no device was created from this instance (finish takes
            // the instance out on success).
            unsafe {
                if let Some((loader, messenger)) = self.debug.take() {
                    loader.destroy_debug_utils_messenger(messenger, None);
                }
                instance.destroy_instance(None);
            }
        }
    }
}

fn c_chars(raw: &[c_char]) -> String {
    let bytes: Vec<u8> = raw
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

fn pick_physical_device(
    instance: &ash::Instance,
    wanted: Option<&str>,
) -> Result<(vk::PhysicalDevice, vk::PhysicalDeviceProperties), VkError> {
    // SAFETY: valid instance.
    let devices = unsafe { instance.enumerate_physical_devices() }?;
    let candidates: Vec<_> = devices
        .into_iter()
        // SAFETY: handles come from this instance.
        .map(|d| (d, unsafe { instance.get_physical_device_properties(d) }))
        .filter(|(_, p)| p.api_version >= vk::API_VERSION_1_2)
        .collect();
    let names: Vec<String> = candidates
        .iter()
        .map(|(_, p)| c_chars(&p.device_name))
        .collect();
    let chosen = match wanted {
        None => candidates.first(),
        Some(w) => match w.parse::<usize>() {
            Ok(i) => candidates.get(i),
            Err(_) => {
                let w = w.to_lowercase();
                candidates
                    .iter()
                    .zip(&names)
                    .find(|(_, n)| n.to_lowercase().contains(&w))
                    .map(|(c, _)| c)
            }
        },
    };
    chosen.copied().ok_or_else(|| VkError::NoDevice {
        wanted: wanted.unwrap_or("any").to_string(),
        // With indices, since --device takes either.
        available: names
            .iter()
            .enumerate()
            .map(|(i, n)| format!("{i}: {n}"))
            .collect(),
    })
}

fn graphics_queue_family(
    instance: &ash::Instance,
    physical_device: vk::PhysicalDevice,
) -> Result<u32, VkError> {
    // SAFETY: valid physical device.
    let families = unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
    families
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
        .map(|i| i as u32)
        .ok_or(VkError::NoGraphicsQueue)
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: every wrapper holding an Arc<Context> is gone (we are in
        // Drop of the last Arc), so no child objects remain except the
        // allocator's memory blocks, which it frees before the device goes,
        // and the pipeline cache, saved and destroyed while the device is
        // idle and alive.
        unsafe {
            let _ = self.device.device_wait_idle();
            ManuallyDrop::drop(&mut self.pipeline_cache);
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.instance.destroy_instance(None);
        }
        // validation_log (user data of the messenger) drops after this.
        let _ = &self.entry;
    }
}
