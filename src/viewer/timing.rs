//! Per-pass GPU times and frame times over the last frames, for the window
//! title, the `T` key and the summary printed on exit.

use crate::render::FrameTiming;
use crate::report::stats::Summary;
use std::collections::VecDeque;

/// How many recent frames the medians are taken over.
pub const WINDOW: usize = 60;

/// The last [`WINDOW`] frames' times.
#[derive(Clone, Debug, Default)]
pub struct TimingWindow {
    passes: Vec<&'static str>,
    /// GPU ms per pass, one entry per frame.
    gpu: VecDeque<Vec<f64>>,
    /// Submit to fence of the renderer's frame (CPU ms).
    render: VecDeque<f64>,
    /// Acquire, copy to the window and present (CPU ms).
    present: VecDeque<f64>,
    /// From one frame's start to the next's (CPU ms): everything the loop
    /// does, events and view updates included.
    frame: VecDeque<f64>,
}

fn push<T>(queue: &mut VecDeque<T>, value: T) {
    if queue.len() == WINDOW {
        queue.pop_front();
    }
    queue.push_back(value);
}

fn median(values: impl IntoIterator<Item = f64>) -> Option<Summary> {
    let v: Vec<f64> = values.into_iter().collect();
    Summary::of(&v)
}

impl TimingWindow {
    /// Starts over for a frame with these passes (after a rebuild that
    /// changed them; the times of other passes do not mix).
    pub fn set_passes(&mut self, passes: Vec<&'static str>) {
        if passes != self.passes {
            *self = TimingWindow {
                passes,
                ..TimingWindow::default()
            };
        }
    }

    /// Records one frame.
    pub fn push(&mut self, timing: &FrameTiming, present_ms: f64) {
        if timing.pass_ms.len() == self.passes.len() {
            push(&mut self.gpu, timing.pass_ms.clone());
        }
        push(&mut self.render, timing.cpu_ms);
        push(&mut self.present, present_ms);
    }

    /// Records the time from the previous frame's start to this one's.
    pub fn push_frame_interval(&mut self, ms: f64) {
        push(&mut self.frame, ms);
    }

    /// Each pass's summary over the window (empty without timestamps).
    pub fn pass_summaries(&self) -> Vec<(&'static str, Summary)> {
        self.passes
            .iter()
            .enumerate()
            .filter_map(|(i, name)| Some((*name, median(self.gpu.iter().map(|f| f[i]))?)))
            .collect()
    }

    /// The frames in the window.
    pub fn frames(&self) -> usize {
        self.render.len()
    }

    /// Summaries of the renderer's frame (submit to fence), the present
    /// step and the whole loop iteration.
    pub fn cpu_summaries(&self) -> [(&'static str, Option<Summary>); 3] {
        [
            ("render", median(self.render.iter().copied())),
            ("present", median(self.present.iter().copied())),
            ("frame", median(self.frame.iter().copied())),
        ]
    }

    /// A short line for the window title: each pass's median GPU time and
    /// the median frame time.
    pub fn title(&self) -> String {
        let mut parts: Vec<String> = self
            .pass_summaries()
            .iter()
            .map(|(name, s)| format!("{name} {:.1}", s.median))
            .collect();
        if let (_, Some(frame)) = &self.cpu_summaries()[2] {
            parts.push(format!("frame {:.1} ms", frame.median));
        }
        parts.join(" · ")
    }

    /// A table of every pass and step: median, p95 and max in ms.
    pub fn report(&self) -> String {
        let mut out = format!(
            "{:<14} {:>10} {:>10} {:>10}   (last {} frames)\n",
            "GPU pass",
            "median ms",
            "p95 ms",
            "max ms",
            self.frames()
        );
        let row = |name: &str, s: &Summary| {
            format!(
                "{name:<14} {:>10.3} {:>10.3} {:>10.3}\n",
                s.median, s.p95, s.max
            )
        };
        let passes = self.pass_summaries();
        if passes.is_empty() {
            out.push_str("(no GPU timestamps on this device)\n");
        }
        for (name, s) in &passes {
            out.push_str(&row(name, s));
        }
        out.push_str(&format!("{:<14}\n", "CPU"));
        for (name, s) in self.cpu_summaries() {
            if let Some(s) = s {
                out.push_str(&row(name, &s));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_cover_the_last_frames_only() {
        let mut t = TimingWindow::default();
        t.set_passes(vec!["opaque", "tonemap"]);
        for i in 0..(WINDOW + 10) {
            let ms = if i < 10 { 1000.0 } else { i as f64 };
            t.push(
                &FrameTiming {
                    pass_ms: vec![ms, 1.0],
                    cpu_ms: 2.0,
                    work: Vec::new(),
                },
                0.5,
            );
        }
        let passes = t.pass_summaries();
        assert_eq!(passes.len(), 2);
        assert!(passes[0].1.max < 1000.0, "old frames left the window");
        assert_eq!(passes[1].1.median, 1.0);
        assert_eq!(t.frames(), WINDOW);
        assert!(t.title().starts_with("opaque "), "{}", t.title());
        // Other passes start a new window.
        t.set_passes(vec!["opaque"]);
        assert_eq!(t.frames(), 0);
    }
}
