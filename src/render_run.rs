//! One render run, as the CLI and the tests use it: create the device
//! (with validation if asked), build the scene's frame, submit it N times,
//! read the images back, tear everything down, and report what the
//! validation layer said. Files are only written by the caller, after the
//! run was found clean. [`render_empty_pass`] does the same for the empty
//! pass that benchmarks measure the driver's floor with.

use crate::budget::MemoryBudget;
use crate::callgrind::Callgrind;
use crate::render::{
    empty_pass, preflight, EmptyPass, FrameTiming, Pixels, PrefixFrames, RenderError, Renderer,
};
use crate::scene::{Scene, ToneMap};
use crate::vk::validation::{Validation, ValidationMessage};
use crate::vk::{Context, ContextOptions, DeviceInfo};

/// What to render and how.
#[derive(Clone, Debug, Default)]
pub struct RenderSettings {
    /// Which validation-layer checks to run under (`Off` for none).
    pub validate: Validation,
    pub device: Option<String>,
    /// Where the device's pipeline cache is kept between runs (in memory
    /// only by default).
    pub pipeline_cache: crate::vk::PipelineCacheStore,
    /// Frames submitted and discarded before the measured ones (warm-up:
    /// first-use costs such as shader compilation in the driver).
    pub warmup: u32,
    /// Frames to submit and time (at least 1); the images are from the last one.
    pub frames: u32,
    /// Read back the linear HDR image too.
    pub keep_hdr: bool,
    /// Also time the empty pass at the scene's output size after every
    /// frame, on the same device ([`RenderRun::empty_pass_frames`]): a
    /// floor measured over the same seconds as the scene, so the ratio of
    /// the two does not depend on what the machine did in between.
    pub empty_pass_between_frames: bool,
    /// Count each pass's pipeline statistics in every measured frame
    /// ([`FrameTiming::work`]); needs a device with the queries.
    pub count_work: bool,
    /// Count each pass's CPU instructions ([`RenderRun::instruction_frames`]);
    /// only in a process started by
    /// [`crate::callgrind::spawn_counting_run`].
    pub count_instructions: bool,
}

/// Everything a run produced.
pub struct RenderRun {
    pub device: DeviceInfo,
    /// Pass names, in the order of each `FrameTiming::pass_ms`.
    pub passes: Vec<&'static str>,
    pub frames: Vec<FrameTiming>,
    pub output: Pixels<u8>,
    pub hdr: Option<Pixels<f32>>,
    /// What building the frame cost beyond its passes
    /// ([`crate::render::Renderer::setup_measures`]).
    pub setup: Vec<(&'static str, f64)>,
    /// The empty pass's timings, [`EMPTY_PASSES_PER_FRAME`] after each
    /// measured frame, with [`RenderSettings::empty_pass_between_frames`];
    /// empty otherwise.
    pub empty_pass_frames: Vec<FrameTiming>,
    /// With [`RenderSettings::count_instructions`], per measured frame the
    /// instructions of each prefix of the frame (the first k passes, k =
    /// 0..=passes); see [`crate::callgrind`]. Empty otherwise.
    pub instruction_frames: Vec<Vec<u64>>,
    /// Validation messages that were not on the allow-list (empty without
    /// validation).
    pub validation: Vec<ValidationMessage>,
}

impl RenderRun {
    /// Metadata stored in every PNG: which device and driver made it.
    pub fn png_metadata(&self) -> Vec<(&'static str, String)> {
        png_metadata(&self.device)
    }
}

/// Metadata stored in every PNG: which device and driver made it.
pub fn png_metadata(device: &DeviceInfo) -> Vec<(&'static str, String)> {
    vec![
        ("Software", format!("aerial {}", env!("CARGO_PKG_VERSION"))),
        ("aerial:device", device.name.clone()),
        (
            "aerial:driver",
            format!(
                "{} {} (driverVersion {:#x})",
                device.driver_name, device.driver_info, device.driver_version
            ),
        ),
        ("aerial:vulkan", device.api_version.clone()),
        ("aerial:host_cpu", host_cpu()),
        ("aerial:codegen", host_codegen()),
    ]
}

/// What of the host CPU changes a CPU driver's pixels, for keying
/// bit-exact references: the vendor and whether `fma` and `avx512f` are
/// present, from `/proc/cpuinfo` (`unknown` elsewhere).
///
/// lavapipe compiles shaders with LLVM for the host. Fused multiply-add
/// changes the rounding of `a * b + c`, and AVX-512 brings other
/// approximate reciprocal instructions; the vendor is kept because
/// approximate reciprocals differ between vendors. The vector width LLVM
/// uses is already in the device name (`llvmpipe (LLVM 15.0.6, 256
/// bits)`). Other extensions (SSE4.1, AVX2, F16C, ...) select different
/// instructions computing the same IEEE results, so a machine with one
/// more unrelated flag renders bit-identically and keeps the strict check.
pub fn host_codegen() -> String {
    match std::fs::read_to_string("/proc/cpuinfo") {
        Ok(info) => codegen_key(&info),
        Err(_) => "unknown".into(),
    }
}

/// The value of the first `name : value` line of a `/proc/cpuinfo` text.
fn cpuinfo_field(cpuinfo: &str, name: &str) -> Option<String> {
    cpuinfo
        .lines()
        .find(|l| l.split(':').next().is_some_and(|k| k.trim() == name))
        .and_then(|l| l.split_once(':'))
        .map(|(_, v)| v.trim().to_string())
}

/// [`host_codegen`] of the text of a `/proc/cpuinfo`.
pub fn codegen_key(cpuinfo: &str) -> String {
    let field = |name: &str| cpuinfo_field(cpuinfo, name);
    let vendor = field("vendor_id").unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let flags = field("flags").unwrap_or_default();
    let has = |f: &str| flags.split_whitespace().any(|x| x == f);
    let sign = |f: &str| {
        if has(f) {
            format!("+{f}")
        } else {
            format!("-{f}")
        }
    };
    format!("{vendor} {} {}", sign("fma"), sign("avx512f"))
}

/// A run that failed, with what the validation layer said before and
/// while the device was torn down (empty without validation): a layer
/// message is often the explanation of the failure.
#[derive(Debug)]
pub struct RunError {
    pub error: RenderError,
    pub validation: Vec<ValidationMessage>,
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if !self.validation.is_empty() {
            write!(f, "; the validation layer also reported:")?;
            for m in &self.validation {
                write!(f, "\n  {m}")?;
            }
        }
        Ok(())
    }
}

// The inner error is part of Display, not a source, so it is shown once.
impl std::error::Error for RunError {}

impl From<RenderError> for RunError {
    fn from(error: RenderError) -> Self {
        RunError {
            error,
            validation: Vec::new(),
        }
    }
}

/// The host CPU's model and the instruction-set extensions a CPU driver's
/// shader compiler may use (SSE, AVX, FMA, F16C families), from
/// `/proc/cpuinfo`; `unknown` elsewhere. Recorded with every PNG because a
/// CPU Vulkan driver such as lavapipe generates different code, and so
/// slightly different pixels, on CPUs with different extensions.
pub fn host_cpu() -> String {
    let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") else {
        return "unknown".into();
    };
    let field = |name: &str| cpuinfo_field(&info, name);
    let model = field("model name").unwrap_or_else(|| "unknown".into());
    let mut flags: Vec<&str> = Vec::new();
    let all = field("flags").unwrap_or_default();
    for f in all.split_whitespace() {
        if ["sse", "avx", "fma", "f16c"]
            .iter()
            .any(|p| f.starts_with(p))
        {
            flags.push(f);
        }
    }
    flags.sort_unstable();
    flags.dedup();
    format!("{model} [{}]", flags.join(" "))
}

/// What a run draws.
#[derive(Clone, Copy)]
pub enum RunSource<'a> {
    /// A scene, drawn and tone-mapped.
    Scene(&'a Scene),
    /// An existing linear HDR image, only tone-mapped.
    HdrImage(&'a Pixels<f32>, ToneMap),
    /// The empty pass (see [`crate::render::empty_pass`]): the driver's
    /// floor at this size; `output` is its constant-coloured attachment.
    EmptyPass { width: u32, height: u32 },
    /// Draws nothing: makes a deliberate mistake on the run's device, so a
    /// test can check that the run reports the layer's message (see
    /// [`Misuse`]). `output` is empty. Only with the `deliberate-misuse`
    /// feature, which the test suite turns on: it is no part of the
    /// shipped API.
    #[cfg(feature = "deliberate-misuse")]
    ValidationCheck(Misuse),
}

/// The deliberate mistakes of [`RunSource::ValidationCheck`].
#[cfg(feature = "deliberate-misuse")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Misuse {
    /// Two writes to one image with no barrier between them.
    SyncHazard,
    /// An object still alive when the device is destroyed.
    Leak,
    /// A leak, then the run fails: the error must still carry the message.
    LeakThenFail,
}

/// Renders `scene` with no progress callback; see [`run`].
pub fn render(scene: &Scene, settings: &RenderSettings) -> Result<RenderRun, RunError> {
    run(RunSource::Scene(scene), settings, &mut || {})
}

/// The one way a run is made: renders `source` `warmup + frames` times with
/// the device and validation the settings ask for, calling `on_frame`
/// after every submitted frame (warm-up frames included), e.g. to drive a
/// progress bar. The validation log is read after the device is torn
/// down, on the error path too.
pub fn run(
    source: RunSource<'_>,
    settings: &RenderSettings,
    on_frame: &mut dyn FnMut(),
) -> Result<RenderRun, RunError> {
    // Refuse what does not fit before the device allocates anything.
    let budget = MemoryBudget::from_env().map_err(RenderError::from)?;
    match source {
        RunSource::Scene(scene) => {
            // The empty pass timed between frames shares the device.
            let empty_pass = if settings.empty_pass_between_frames {
                preflight::EMPTY_PASS_BYTES_PER_PIXEL
            } else {
                0
            };
            preflight::scene_bytes(scene, settings.keep_hdr, empty_pass, &budget)?;
        }
        RunSource::HdrImage(image, _) => {
            preflight::image_memory(image.width, image.height, &budget)?
        }
        RunSource::EmptyPass { width, height } => {
            preflight::empty_pass_memory(width, height, &budget)?
        }
        #[cfg(feature = "deliberate-misuse")]
        RunSource::ValidationCheck(_) => {}
    }
    // Safe points (see `crate::interrupt`): before the device is created,
    // and in `produce` between the phases and before every frame.
    crate::interrupt::check().map_err(RenderError::from)?;
    let ctx = context(settings)?;
    let log = ctx.validation_log();
    let device = ctx.device_info().clone();
    let produced = produce(&ctx, source, settings, on_frame);
    // Destroy the device and instance before reading the log, so messages
    // about leaked objects at teardown are counted too, on the error path
    // as well.
    drop(ctx);
    let validation = log.map(|l| l.messages()).unwrap_or_default();
    let p = match produced {
        Ok(p) => p,
        Err(error) => return Err(RunError { error, validation }),
    };
    Ok(RenderRun {
        device,
        passes: p.passes,
        frames: p.frames,
        output: p.output,
        hdr: p.hdr,
        setup: p.setup,
        empty_pass_frames: p.empty_pass_frames,
        instruction_frames: p.instruction_frames,
        validation,
    })
}

/// Builds the frame for `source` on `ctx` and submits it.
fn produce(
    ctx: &std::sync::Arc<Context>,
    source: RunSource<'_>,
    settings: &RenderSettings,
    on_frame: &mut dyn FnMut(),
) -> Result<Produced, RenderError> {
    crate::interrupt::check()?;
    Ok(match source {
        RunSource::Scene(scene) => {
            let renderer = Renderer::prepare(ctx, scene, None, settings.keep_hdr)?;
            let empty = if settings.empty_pass_between_frames {
                Some(EmptyPass::new(
                    ctx,
                    scene.output.width,
                    scene.output.height,
                )?)
            } else {
                None
            };
            if settings.count_instructions {
                count(renderer, settings, on_frame)?
            } else {
                drive(renderer, empty, settings, on_frame)?
            }
        }
        RunSource::HdrImage(image, tone_map) => drive(
            Renderer::for_hdr_image(ctx, tone_map, image)?,
            None,
            settings,
            on_frame,
        )?,
        RunSource::EmptyPass { width, height } => {
            let mut pass = EmptyPass::new(ctx, width, height)?;
            let (frames, instruction_frames) = if settings.count_instructions {
                count_prefixes(&mut pass, settings, on_frame)?
            } else {
                let frames = submit_frames(settings, on_frame, || pass.render_frame())?;
                (frames, Vec::new())
            };
            Produced {
                passes: vec![empty_pass::PASS_NAME],
                frames,
                output: pass.output(),
                hdr: None,
                setup: Vec::new(),
                empty_pass_frames: Vec::new(),
                instruction_frames,
            }
        }
        #[cfg(feature = "deliberate-misuse")]
        RunSource::ValidationCheck(misuse) => make_mistake(ctx, misuse)?,
    })
}

/// Makes the deliberate mistake `misuse` on `ctx` (see
/// [`RunSource::ValidationCheck`]); produces nothing.
#[cfg(feature = "deliberate-misuse")]
fn make_mistake(ctx: &Context, misuse: Misuse) -> Result<Produced, RenderError> {
    match misuse {
        Misuse::SyncHazard => ctx.record_sync_hazard_for_validation_check()?,
        Misuse::Leak | Misuse::LeakThenFail => ctx.leak_object_for_validation_check()?,
    }
    if misuse == Misuse::LeakThenFail {
        return Err(Context::deliberate_failure_for_validation_check().into());
    }
    Ok(Produced {
        passes: Vec::new(),
        frames: Vec::new(),
        output: Pixels {
            width: 0,
            height: 0,
            data: Vec::new(),
        },
        hdr: None,
        setup: Vec::new(),
        empty_pass_frames: Vec::new(),
        instruction_frames: Vec::new(),
    })
}

/// What one run's frames produced, before the validation log is read: pass
/// names, timings, the images of the last frame.
struct Produced {
    passes: Vec<&'static str>,
    frames: Vec<FrameTiming>,
    output: Pixels<u8>,
    hdr: Option<Pixels<f32>>,
    setup: Vec<(&'static str, f64)>,
    empty_pass_frames: Vec<FrameTiming>,
    instruction_frames: Vec<Vec<u64>>,
}

/// Empty passes timed after each frame with
/// [`RenderSettings::empty_pass_between_frames`] (after one more that is not
/// kept).
pub const EMPTY_PASSES_PER_FRAME: usize = 3;

/// Submits the renderer's frames; with `empty`, the empty pass after each
/// one.
fn drive(
    mut renderer: Renderer,
    mut empty: Option<EmptyPass>,
    settings: &RenderSettings,
    on_frame: &mut dyn FnMut(),
) -> Result<Produced, RenderError> {
    let passes = renderer.plan().pass_names();
    let mut empty_pass_frames = Vec::new();
    let frames = submit_frames(settings, on_frame, || {
        let frame = renderer.render_frame()?;
        if let Some(empty) = empty.as_mut() {
            // The first empty pass after a frame finds the caches full of
            // the frame's data and measured 10-40 % slower than the rest:
            // it is not the floor, so it is not kept.
            empty.render_frame()?;
            for _ in 0..EMPTY_PASSES_PER_FRAME {
                empty_pass_frames.push(empty.render_frame()?);
            }
        }
        Ok(frame)
    })?;
    // Those after warm-up frames are not measurements either.
    let warmup = empty_pass_frames
        .len()
        .saturating_sub(EMPTY_PASSES_PER_FRAME * frames.len());
    empty_pass_frames.drain(..warmup);
    Ok(Produced {
        passes,
        frames,
        output: renderer.output(),
        hdr: renderer.hdr(),
        setup: renderer.setup_measures(),
        empty_pass_frames,
        instruction_frames: Vec::new(),
    })
}

/// Counts the renderer's instructions per frame prefix ([`count_prefixes`]).
fn count(
    mut renderer: Renderer,
    settings: &RenderSettings,
    on_frame: &mut dyn FnMut(),
) -> Result<Produced, RenderError> {
    let passes = renderer.plan().pass_names();
    let (frames, instruction_frames) = count_prefixes(&mut renderer, settings, on_frame)?;
    Ok(Produced {
        passes,
        frames,
        output: renderer.output(),
        hdr: renderer.hdr(),
        setup: renderer.setup_measures(),
        empty_pass_frames: Vec::new(),
        instruction_frames,
    })
}

/// Submits the warm-up frames uninstrumented, then for each measured frame
/// every prefix of it (0..=passes recorded), each counted by callgrind;
/// returns the whole frames' timings and each frame's prefix counts. The
/// whole frame is submitted last, so the read-back images are the frame's.
fn count_prefixes(
    frames: &mut dyn PrefixFrames,
    settings: &RenderSettings,
    on_frame: &mut dyn FnMut(),
) -> Result<(Vec<FrameTiming>, Vec<Vec<u64>>), RenderError> {
    let callgrind = Callgrind::from_env()?.ok_or(crate::callgrind::CountError::NotUnderValgrind)?;
    let passes = frames.pass_count();
    // Warm-up runs every prefix too: the driver compiles some shader
    // variants on first use, which must not land in a counted frame.
    for _ in 0..settings.warmup.max(1) {
        for k in 0..=passes {
            frames.render_prefix(k)?;
        }
        on_frame();
    }
    callgrind.start();
    let mut timings = Vec::new();
    let mut counts = Vec::new();
    for _ in 0..settings.frames.max(1) {
        crate::interrupt::check()?;
        let mut prefixes = Vec::with_capacity(passes + 1);
        let mut whole = None;
        for k in 0..=passes {
            // The driver finishes some of a submission's work (recycling
            // its memory, say) only during the next one, so a count holds
            // part of the previous prefix's cleanup. Submitting the prefix
            // once uncounted first makes that part its own: without it, up
            // to 100,000 instructions moved between neighbouring passes
            // from frame to frame.
            frames.render_prefix(k)?;
            let (timing, n) = callgrind.count(|| frames.render_prefix(k))?;
            prefixes.push(n);
            whole = Some(timing);
        }
        timings.extend(whole);
        counts.push(prefixes);
        on_frame();
    }
    Ok((timings, counts))
}

fn context(settings: &RenderSettings) -> Result<std::sync::Arc<Context>, RenderError> {
    let ctx = Context::new(&ContextOptions {
        validate: settings.validate,
        device: settings.device.clone(),
        display: None,
        pipeline_statistics: settings.count_work,
        pipeline_cache: settings.pipeline_cache.clone(),
    })?;
    if settings.count_instructions && !ctx.device_info().cpu {
        return Err(crate::callgrind::CountError::NotCpuDevice {
            device: ctx.device_info().name.clone(),
        }
        .into());
    }
    Ok(ctx)
}

/// Submits `settings.warmup` discarded frames, then `settings.frames` (at
/// least one) whose timings are returned.
fn submit_frames(
    settings: &RenderSettings,
    on_frame: &mut dyn FnMut(),
    mut frame: impl FnMut() -> Result<FrameTiming, RenderError>,
) -> Result<Vec<FrameTiming>, RenderError> {
    for _ in 0..settings.warmup {
        crate::interrupt::check()?;
        frame()?;
        on_frame();
    }
    let mut frames = Vec::new();
    for _ in 0..settings.frames.max(1) {
        crate::interrupt::check()?;
        frames.push(frame()?);
        on_frame();
    }
    Ok(frames)
}
