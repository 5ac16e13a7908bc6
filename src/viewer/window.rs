//! The viewer's event loop: a winit window, its Vulkan surface and
//! swapchain, and the renderer, driven by keys, the mouse and scripts.
//!
//! One frame: apply the input of this frame (script actions included),
//! move the camera and sun by the elapsed time (a fixed step under a
//! script), update the renderer's view, submit the recorded frame, copy
//! its output to the window, then take the frame's screenshots.

use super::camera::{turn_sun, FlyCamera, Surroundings};
use super::input::{Action, Key, HELP};
use super::knobs;
use super::script::{Script, ScriptAction};
use super::timing::TimingWindow;
use super::{ViewOptions, ViewOutcome, ViewerError, SCRIPT_STEP_SECONDS};
use crate::image_io;
use crate::render::{preflight, RenderError, Renderer, SceneGeometry, ViewChange};
use crate::safe_files;
use crate::scene::Scene;
use crate::vk::validation::ValidationLog;
use crate::vk::{Context, ContextOptions, Presented, Surface, Swapchain};
use glam::DVec3;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// Degrees a second the sun turns while its key is held.
const SUN_DEGREES_PER_SECOND: f64 = 10.0;
/// How long a script waits for the window system to apply a `resize`.
const RESIZE_TIMEOUT: Duration = Duration::from_secs(5);
/// How often the title's times are refreshed.
const TITLE_PERIOD: Duration = Duration::from_millis(500);
/// The longest time step of an unscripted frame (a stall, e.g. a rebuild,
/// must not throw the camera far).
const MAX_STEP_SECONDS: f64 = 0.1;

pub(super) fn run(options: ViewOptions) -> ViewOutcome {
    let mut app = App {
        options,
        live: None,
        log: None,
        error: None,
        frames: 0,
        timings: String::new(),
    };
    match EventLoop::new() {
        Ok(event_loop) => {
            if let Err(e) = event_loop.run_app(&mut app) {
                app.error
                    .get_or_insert(ViewerError::Window(window_error(&e)));
            }
        }
        Err(e) => app.error = Some(ViewerError::Window(window_error(&e))),
    }
    // Tear down in order (renderer and swapchain before the surface, all
    // before the device), then read what the layer said, teardown included.
    if let Some(live) = app.live.take() {
        app.frames = live.frame;
        app.timings = live.timings.report();
        drop(live);
    }
    let validation = app.log.map(|l| l.messages()).unwrap_or_default();
    ViewOutcome {
        frames: app.frames,
        error: app.error,
        validation,
        timings: app.timings,
    }
}

/// A window system error as a message for the user: the windowing
/// library's operating-system errors start with the place in its own
/// source they were made at (`os error at src/...rs:123:`), which says
/// nothing to the user and names a folder of the machine that built the
/// program; that part is left out.
fn window_error(error: &impl std::fmt::Display) -> String {
    let text = error.to_string();
    if let Some(rest) = text.strip_prefix("os error at ") {
        // `FILE:LINE: message`: the message starts after the line number.
        let mut parts = rest.splitn(3, ':');
        if let (Some(_file), Some(line), Some(message)) = (parts.next(), parts.next(), parts.next())
        {
            if !line.is_empty() && line.bytes().all(|b| b.is_ascii_digit()) {
                return message.trim_start().to_string();
            }
        }
    }
    text
}

struct App {
    options: ViewOptions,
    live: Option<Live>,
    log: Option<Arc<ValidationLog>>,
    error: Option<ViewerError>,
    frames: u64,
    timings: String,
}

/// Everything that exists while the window is open. Fields drop in
/// order: the renderer and swapchain before the surface, the window last.
struct Live {
    renderer: Renderer,
    swapchain: Option<Swapchain>,
    /// The swapchain no longer matches the window: make a new one before
    /// the next frame.
    stale: bool,
    surface: Arc<Surface>,
    ctx: Arc<Context>,
    window: Arc<Window>,
    geometry: Arc<SceneGeometry>,
    surroundings: Surroundings,
    /// The viewer's copy of the scene: camera, sun, knobs and size follow
    /// the input; the renderer is built from it.
    scene: Scene,
    scene_name: String,
    home_sun: Option<DVec3>,
    camera: FlyCamera,
    /// Keys held down.
    held: HashSet<Key>,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    /// The view changed since the renderer's was set.
    view_dirty: bool,
    /// Frames drawn so far; the next frame's number.
    frame: u64,
    script: Option<Script>,
    /// The frame whose script input was applied (it is not applied twice
    /// when the frame waits for a resize).
    script_input_done: Option<u64>,
    /// A scripted resize the window system has not applied yet, and until
    /// when to wait for it.
    pending_resize: Option<(PhysicalSize<u32>, Instant)>,
    timings: TimingWindow,
    last_frame_start: Option<Instant>,
    last_title: Instant,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.live.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(live) => {
                let swapchain = match &live.swapchain {
                    Some(s) => format!("{:?} swapchain", s.format()),
                    None => "no swapchain yet".to_string(),
                };
                println!(
                    "aerial view: {} at {}x{} on {}; {swapchain}, present mode {:?}",
                    live.scene_name,
                    live.scene.output.width,
                    live.scene.output.height,
                    live.ctx.device_info().name,
                    self.options.present_mode
                );
                println!("{HELP}\nknobs:\n{}", knobs::listing(&live.scene));
                self.live = Some(live);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(live) = self.live.as_mut() else {
            return;
        };
        let result = match event {
            WindowEvent::CloseRequested => {
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => {
                live.stale = true;
                if live.pending_resize.is_some_and(|(want, _)| want == size) {
                    live.pending_resize = None;
                }
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => match Key::from_winit(&event.logical_key) {
                Some(key) if event.state == ElementState::Pressed && !event.repeat => {
                    live.key_down(key, event_loop, &self.options)
                }
                Some(key) if event.state == ElementState::Released => {
                    live.held.remove(&key);
                    Ok(())
                }
                _ => Ok(()),
            },
            WindowEvent::Focused(false) if !live.scripted() => {
                // Keys released elsewhere send no release here: stop
                // moving rather than fly on (a script's keys stay held:
                // its images must not depend on the window focus).
                live.held.clear();
                live.dragging = false;
                Ok(())
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                live.dragging = state == ElementState::Pressed;
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let (true, Some(before)) = (live.dragging, live.cursor) {
                    live.camera.look(now.0 - before.0, now.1 - before.1);
                    live.view_dirty = true;
                }
                live.cursor = Some(now);
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                live.camera.zoom(steps);
                live.view_dirty = true;
                Ok(())
            }
            WindowEvent::RedrawRequested => live.frame(event_loop, &self.options),
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // A safe point between frames: an interrupt closes the window as
        // the close button does (see `crate::interrupt`).
        if crate::interrupt::requested() {
            event_loop.exit();
            return;
        }
        let Some(live) = self.live.as_ref() else {
            return;
        };
        let size = live.window.inner_size();
        if size.width == 0 || size.height == 0 {
            // Minimized: nothing to draw; look again in a while.
            event_loop.set_control_flow(ControlFlow::WaitUntil(
                Instant::now() + Duration::from_millis(100),
            ));
        } else {
            event_loop.set_control_flow(ControlFlow::Poll);
            live.window.request_redraw();
        }
    }
}

impl App {
    /// Opens the window, the device that presents to it, and the renderer.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Live, ViewerError> {
        let scene = self.options.scene.clone();
        let (w, h) = (scene.output.width, scene.output.height);
        let attributes = Window::default_attributes()
            .with_title(format!(
                "aerial view — {}{}",
                self.options.scene_name,
                warning_note(scene.warnings.len())
            ))
            .with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| ViewerError::Window(window_error(&e)))?,
        );
        let display = {
            use raw_window_handle::HasDisplayHandle;
            window
                .display_handle()
                .map_err(|e| ViewerError::Window(window_error(&e)))?
                .as_raw()
        };
        // Refuse what does not fit before the device allocates anything.
        preflight::scene_fits(&scene, false)?;
        let ctx = Context::new(&ContextOptions {
            validate: self.options.validate,
            device: self.options.device.clone(),
            pipeline_cache: self.options.pipeline_cache.clone(),
            display: Some(display),
            ..Default::default()
        })?;
        self.log = ctx.validation_log();
        let surface = Arc::new(Surface::new(&ctx, window.clone())?);
        let size = window.inner_size();
        let swapchain = Swapchain::new(
            &ctx,
            &surface,
            size.width.max(1),
            size.height.max(1),
            self.options.present_mode,
            None,
        )?;
        let mut scene = scene;
        let (sw, sh) = swapchain.extent();
        scene
            .set_output_size(Some(sw), Some(sh))
            .map_err(|e| ViewerError::Render(RenderError::Frame(format!("window size: {e}"))))?;
        let geometry = Arc::new(SceneGeometry::new(&scene)?);
        let renderer = Renderer::prepare(&ctx, &scene, Some(geometry.clone()), false)?;
        let mut timings = TimingWindow::default();
        timings.set_passes(renderer.plan().pass_names());
        Ok(Live {
            renderer,
            swapchain: Some(swapchain),
            stale: false,
            surface,
            ctx,
            window,
            surroundings: Surroundings::of(&scene, &geometry),
            geometry,
            home_sun: scene.sky.as_ref().map(|s| s.sun.direction),
            camera: FlyCamera::new(scene.camera),
            scene,
            scene_name: self.options.scene_name.clone(),
            held: HashSet::new(),
            dragging: false,
            cursor: None,
            view_dirty: false,
            frame: 0,
            script: self.options.script.clone(),
            script_input_done: None,
            pending_resize: None,
            timings,
            last_frame_start: None,
            last_title: Instant::now(),
        })
    }
}

impl Live {
    /// Whether a script is running: it has actions at this frame or later.
    fn scripted(&self) -> bool {
        self.script
            .as_ref()
            .and_then(|s| s.last_frame())
            .is_some_and(|last| self.frame <= last)
    }

    /// A key went down: held keys are remembered, one-shot actions run.
    fn key_down(
        &mut self,
        key: Key,
        event_loop: &ActiveEventLoop,
        options: &ViewOptions,
    ) -> Result<(), ViewerError> {
        self.held.insert(key);
        match key.action() {
            Some(Action::Zoom(steps)) => {
                self.camera.zoom(f64::from(steps));
                self.view_dirty = true;
            }
            Some(Action::ResetCamera) => {
                self.camera.reset();
                self.view_dirty = true;
            }
            Some(Action::ResetSun) => {
                if let (Some(sky), Some(home)) = (self.scene.sky.as_mut(), self.home_sun) {
                    sky.sun.direction = home;
                    self.view_dirty = true;
                }
            }
            Some(Action::CycleKnob(n)) => self.cycle_knob(n)?,
            Some(Action::PrintTimings) => print!("{}", self.timings.report()),
            Some(Action::Screenshot) => {
                let path = next_free_screenshot_path();
                self.screenshot(&path, options)?;
            }
            Some(Action::Help) => println!("{HELP}\nknobs:\n{}", knobs::listing(&self.scene)),
            Some(Action::Quit) => event_loop.exit(),
            Some(Action::Move { .. } | Action::Fast | Action::Sun(_)) | None => {}
        }
        Ok(())
    }

    /// Sets knob `n` (1-based, among those that apply) to its next value
    /// and builds the renderer again; a value the renderer refuses is
    /// reported and undone.
    fn cycle_knob(&mut self, n: usize) -> Result<(), ViewerError> {
        let cycles = knobs::applicable(&self.scene);
        let Some(cycle) = n.checked_sub(1).and_then(|i| cycles.get(i)) else {
            return Ok(());
        };
        let before = self.scene.clone();
        let value = cycle.advance(&mut self.scene)?;
        let built = preflight::scene_fits(&self.scene, false).and_then(|()| {
            Renderer::prepare(&self.ctx, &self.scene, Some(self.geometry.clone()), false)
        });
        match built {
            Ok(renderer) => {
                self.renderer = renderer;
                self.timings.set_passes(self.renderer.plan().pass_names());
                println!("{}={value}", cycle.name);
            }
            Err(e) => {
                eprintln!("{}={value} cannot be drawn: {e}", cycle.name);
                self.scene = before;
            }
        }
        Ok(())
    }

    /// Draws and shows one frame (see the module docs for the order).
    fn frame(
        &mut self,
        event_loop: &ActiveEventLoop,
        options: &ViewOptions,
    ) -> Result<(), ViewerError> {
        let start = Instant::now();
        let scripted = self.scripted();

        // This frame's scripted input, once.
        if let (Some(script), true) = (&self.script, self.script_input_done != Some(self.frame)) {
            let actions: Vec<ScriptAction> = script.at(self.frame).cloned().collect();
            self.script_input_done = Some(self.frame);
            for action in actions {
                match action {
                    ScriptAction::Press(key) => self.key_down(key, event_loop, options)?,
                    ScriptAction::Release(key) => {
                        self.held.remove(&key);
                    }
                    ScriptAction::Mouse(dx, dy) => {
                        self.camera.look(dx, dy);
                        self.view_dirty = true;
                    }
                    ScriptAction::Resize(w, h) => {
                        let want = PhysicalSize::new(w, h);
                        if self.window.inner_size() != want {
                            let _ = self.window.request_inner_size(want);
                            self.pending_resize = Some((want, Instant::now() + RESIZE_TIMEOUT));
                        }
                    }
                    ScriptAction::Screenshot(_) | ScriptAction::Quit => {}
                }
            }
        }
        // A scripted resize holds the script until the window has its new
        // size, so the script's frames are drawn at the sizes it asked for.
        if let Some((want, until)) = self.pending_resize {
            if self.window.inner_size() == want {
                self.pending_resize = None;
                self.stale = true;
            } else if Instant::now() < until {
                return Ok(());
            } else {
                eprintln!(
                    "warning: the window system did not resize the window to {}x{}; going on at {}x{}",
                    want.width,
                    want.height,
                    self.window.inner_size().width,
                    self.window.inner_size().height
                );
                self.pending_resize = None;
            }
        }

        if !self.ensure_swapchain(options)? {
            return Ok(()); // minimized
        }

        // Simulation step.
        let dt = match (scripted, self.last_frame_start) {
            (true, _) => SCRIPT_STEP_SECONDS,
            (false, Some(last)) => start
                .duration_since(last)
                .as_secs_f64()
                .min(MAX_STEP_SECONDS),
            (false, None) => 0.0,
        };
        if let Some(last) = self.last_frame_start {
            self.timings
                .push_frame_interval(start.duration_since(last).as_secs_f64() * 1e3);
        }
        self.last_frame_start = Some(start);
        self.simulate(dt);

        if self.view_dirty {
            self.scene.camera = self.camera.camera();
            if self.renderer.set_view(&self.scene)? == ViewChange::Rebuilt {
                self.timings.set_passes(self.renderer.plan().pass_names());
            }
            self.view_dirty = false;
        }
        let timing = self.renderer.render_frame()?;
        let present_start = Instant::now();
        let source = self.renderer.output_image().ok_or_else(|| {
            RenderError::Frame("the frame has no output attachment to show".into())
        })?;
        let swapchain = self.swapchain.as_mut().expect("ensured above");
        match swapchain.present(source)? {
            Presented::Done => {}
            Presented::Suboptimal | Presented::OutOfDate => self.stale = true,
        }
        self.timings
            .push(&timing, present_start.elapsed().as_secs_f64() * 1e3);

        // This frame's screenshots, then quit.
        let mut quit = false;
        if let Some(script) = &self.script {
            let actions: Vec<ScriptAction> = script.at(self.frame).cloned().collect();
            for action in actions {
                match action {
                    ScriptAction::Screenshot(path) => self.screenshot(&path, options)?,
                    ScriptAction::Quit => quit = true,
                    _ => {}
                }
            }
        }
        self.frame += 1;
        if quit {
            event_loop.exit();
        }
        if self.last_title.elapsed() >= TITLE_PERIOD {
            self.last_title = Instant::now();
            self.window.set_title(&format!(
                "aerial view — {}{} — {}",
                self.scene_name,
                warning_note(self.scene.warnings.len()),
                self.timings.title()
            ));
        }
        Ok(())
    }

    /// Makes the swapchain match the window, and the renderer the
    /// swapchain. False while the window has no area (minimized).
    fn ensure_swapchain(&mut self, options: &ViewOptions) -> Result<bool, ViewerError> {
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(false);
        }
        if self.stale || self.swapchain.is_none() {
            let old = self.swapchain.take();
            self.swapchain = Some(Swapchain::new(
                &self.ctx,
                &self.surface,
                size.width,
                size.height,
                options.present_mode,
                old,
            )?);
            self.stale = false;
        }
        let (w, h) = self.swapchain.as_ref().expect("made above").extent();
        if (w, h) != (self.scene.output.width, self.scene.output.height) {
            self.scene
                .set_output_size(Some(w), Some(h))
                .map_err(|e| RenderError::Frame(format!("window size: {e}")))?;
            // The plan changes with the size: set_view builds the frame
            // again at the new size.
            self.view_dirty = true;
        }
        Ok(true)
    }

    /// Moves the camera and the sun by the held keys over `dt` seconds.
    fn simulate(&mut self, dt: f64) {
        let (mut forward, mut right, mut up, mut sun) = (0i32, 0i32, 0i32, 0i32);
        let mut fast = false;
        for key in &self.held {
            match key.action() {
                Some(Action::Move {
                    forward: f,
                    right: r,
                    up: u,
                }) => {
                    forward += i32::from(f);
                    right += i32::from(r);
                    up += i32::from(u);
                }
                Some(Action::Sun(s)) => sun += i32::from(s),
                Some(Action::Fast) => fast = true,
                _ => {}
            }
        }
        let boost = if fast { 10.0 } else { 1.0 };
        if (forward, right, up) != (0, 0, 0) && dt > 0.0 {
            let height = self.surroundings.height(self.camera.eye());
            let distance = self.camera.speed(height) * boost * dt;
            self.camera.translate(
                f64::from(forward.signum()),
                f64::from(right.signum()),
                f64::from(up.signum()),
                distance,
                &self.surroundings,
            );
            self.view_dirty = true;
        }
        if sun != 0 && dt > 0.0 {
            let eye = self.camera.eye();
            let vertical = self.surroundings.vertical(eye).unwrap_or(DVec3::Y);
            if let Some(sky) = self.scene.sky.as_mut() {
                let angle =
                    (SUN_DEGREES_PER_SECOND * boost * dt * f64::from(sun.signum())).to_radians();
                sky.sun.direction = turn_sun(sky.sun.direction, vertical, angle);
                self.view_dirty = true;
            }
        }
    }

    /// Writes the last frame as PNG at `path` (with the camera in its
    /// metadata) and the same view's linear HDR image as EXR next to it,
    /// and prints the `[camera]` that reproduces it with `aerial render`.
    fn screenshot(&mut self, path: &Path, options: &ViewOptions) -> Result<(), ViewerError> {
        let shot_err = |reason: String| ViewerError::Screenshot {
            path: path.display().to_string(),
            reason,
        };
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
        {
            return Err(shot_err(
                "names the PNG; the EXR is written next to it with the extension .exr".into(),
            ));
        }
        // As every command: output is only written from a clean run.
        if let Some(log) = self.ctx.validation_log() {
            crate::vk::validation::check(&log.messages())?;
        }
        let exr_path = path.with_extension("exr");
        safe_files::check_output(path, safe_files::Format::Png)
            .map_err(|e| shot_err(e.to_string()))?;
        safe_files::check_destination(&exr_path).map_err(|e| shot_err(e.to_string()))?;
        // The frame on screen (the renderer reads its output back every
        // frame) and, for the EXR, the same view drawn once more by a
        // renderer that keeps the HDR image.
        let pixels = self.renderer.output();
        let hdr = {
            let mut with_hdr =
                Renderer::with_geometry(&self.ctx, &self.scene, self.geometry.clone(), true)?;
            with_hdr.render_frame()?;
            with_hdr
                .hdr()
                .ok_or_else(|| shot_err("the HDR image was not read back".into()))?
        };
        let camera_toml = self.camera.toml();
        let mut metadata = crate::render_run::png_metadata(self.ctx.device_info());
        metadata.push(("aerial:scene", options.scene_name.clone()));
        metadata.push(("aerial:camera", camera_toml.clone()));
        let sun_line = self.scene.sky.as_ref().map(|s| {
            let d = s.sun.direction;
            format!("[{}, {}, {}]", d.x, d.y, d.z)
        });
        if let Some(sun) = &sun_line {
            metadata.push(("aerial:sun_direction", sun.clone()));
        }
        let knob_line = crate::scene::knob_settings(&self.scene)
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect::<Vec<_>>()
            .join(" ");
        metadata.push(("aerial:knobs", knob_line));
        let pending = vec![
            image_io::png_file(path, &pixels, &metadata)?,
            image_io::exr_file(&exr_path, &hdr)?,
        ];
        safe_files::commit_all(pending).map_err(|e| shot_err(e.to_string()))?;
        println!(
            "wrote {} and {} (frame {}); this view with `aerial render`:\n{camera_toml}{}",
            path.display(),
            exr_path.display(),
            self.frame,
            sun_line
                .map(|s| format!("# and in [sun]: direction = {s}\n"))
                .unwrap_or_default()
        );
        Ok(())
    }
}

/// `aerial-view-NNN.png` in the current folder, the first NNN whose PNG
/// and EXR are both free.
fn next_free_screenshot_path() -> PathBuf {
    (1u32..)
        .map(|n| PathBuf::from(format!("aerial-view-{n:03}.png")))
        .find(|p| !p.exists() && !p.with_extension("exr").exists())
        .expect("some number is free")
}

/// The title's note that something is drawn with a fallback: the count of
/// the scene's asset warnings (the warnings themselves are on stderr), kept
/// current as knobs change the scene.
fn warning_note(count: usize) -> String {
    match count {
        0 => String::new(),
        1 => " (1 asset warning)".into(),
        n => format!(" ({n} asset warnings)"),
    }
}
