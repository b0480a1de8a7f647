//! The animation timeline: which clip plays, where, how fast, looped or not, and the pose,
//! build, upload and trace times of the frames it showed. Every frame of a playing clip is a
//! new pose and a structure rebuilt from scratch (off the UI thread); playback follows the
//! wall clock, so when a frame takes longer than the clip advances, frames are dropped, never
//! slowed.

use std::collections::VecDeque;

use eframe::egui;
use egui_plot::{Legend, Line, Plot};
use gridrt_scene::{Clip, ClipTime};
use web_time::{Duration, Instant};

/// Frames kept for the plot.
const HISTORY: usize = 240;
/// The frame rate is measured over the frames shown in this window.
const FPS_WINDOW: Duration = Duration::from_secs(3);
/// Least height of the plot of frame times, points.
pub const PLOT_HEIGHT: f32 = 110.0;
/// The step buttons move by one frame at this rate.
const STEP_FPS: f64 = 30.0;

/// What one shown animation frame cost, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTimes {
    /// Animation frames shown before this one.
    pub frame: u64,
    /// Clip time it shows.
    pub seconds: f64,
    pub pose_ms: f64,
    pub build_ms: f64,
    /// Posed triangles and structure copied to the GPU.
    pub upload_ms: f64,
    /// The GPU frame (primary and shadow rays, shading).
    pub trace_ms: f64,
}

/// The timeline's state (not saved between runs).
#[derive(Debug)]
pub struct Timeline {
    pub clip: usize,
    /// Clip time (seconds on the clip's own time line, as in the file).
    pub seconds: f64,
    pub playing: bool,
    /// Clip seconds per wall-clock second.
    pub speed: f64,
    /// At the clip's end: start over (true) or stop.
    pub looped: bool,
    last_tick: Option<Instant>,
    /// The newest shown frames, oldest first.
    pub history: VecDeque<FrameTimes>,
    /// When each of the newest frames was shown.
    shown_at: VecDeque<Instant>,
    pub frames_shown: u64,
    /// A pose that failed (playback stopped there; it is not retried).
    pub failed: Option<ClipTime>,
}

impl Timeline {
    pub fn new(clip: usize, seconds: f64, playing: bool) -> Timeline {
        Timeline {
            clip,
            seconds,
            playing,
            speed: 1.0,
            looped: true,
            last_tick: None,
            history: VecDeque::new(),
            shown_at: VecDeque::new(),
            frames_shown: 0,
            failed: None,
        }
    }

    /// The pose the view should show.
    pub fn wanted(&self) -> ClipTime {
        ClipTime { clip: self.clip, seconds: self.seconds }
    }

    /// Advances the clip time by the wall-clock time since the last tick (while playing).
    pub fn tick(&mut self, clip: &Clip, now: Instant) {
        let last = self.last_tick.replace(now);
        if !self.playing {
            return;
        }
        let dt = last.map_or(0.0, |l| now.saturating_duration_since(l).as_secs_f64()) * self.speed;
        let t = self.seconds + dt;
        if self.looped {
            self.seconds = clip.looped(t - clip.start);
        } else {
            self.seconds = clip.clamp(t);
            if self.seconds >= clip.end {
                self.playing = false;
            }
        }
    }

    /// Starts or pauses; playing from the end of an unlooped clip starts over.
    pub fn toggle(&mut self, clip: &Clip) {
        self.playing = !self.playing;
        self.last_tick = None;
        if self.playing && !self.looped && self.seconds >= clip.end {
            self.seconds = clip.start;
        }
    }

    /// Moves to `seconds` (clamped to the clip); a pose that failed may be tried again.
    pub fn seek(&mut self, clip: &Clip, seconds: f64) {
        self.seconds = clip.clamp(seconds);
        self.failed = None;
    }

    /// Moves by `frames` frames at [`STEP_FPS`] (paused), within the clip.
    pub fn step(&mut self, clip: &Clip, frames: i32) {
        self.playing = false;
        self.seconds = clip.clamp(self.seconds + frames as f64 / STEP_FPS);
    }

    /// Records a frame the view finished showing.
    pub fn record(&mut self, mut times: FrameTimes, now: Instant) {
        times.frame = self.frames_shown;
        self.frames_shown += 1;
        self.history.push_back(times);
        while self.history.len() > HISTORY {
            self.history.pop_front();
        }
        self.shown_at.push_back(now);
        // The window's frames, and at least the last two however slow they are.
        while self.shown_at.len() > 2
            && self.shown_at.front().is_some_and(|&t| now.saturating_duration_since(t) > FPS_WINDOW)
        {
            self.shown_at.pop_front();
        }
    }

    /// Frames shown per second over the last few seconds, or over the last two frames when
    /// they are further apart (`None` until two frames were shown).
    pub fn fps(&self) -> Option<f64> {
        let (first, last) = (self.shown_at.front()?, self.shown_at.back()?);
        let span = last.saturating_duration_since(*first).as_secs_f64();
        (self.shown_at.len() >= 2 && span > 0.0).then(|| (self.shown_at.len() - 1) as f64 / span)
    }

    /// Mean times over the newest `n` frames.
    pub fn mean(&self, n: usize) -> Option<FrameTimes> {
        let k = self.history.len().min(n);
        if k == 0 {
            return None;
        }
        let recent = self.history.iter().rev().take(k);
        let mut m = FrameTimes { frame: self.frames_shown, seconds: self.seconds, ..FrameTimes::zero() };
        for t in recent {
            m.pose_ms += t.pose_ms / k as f64;
            m.build_ms += t.build_ms / k as f64;
            m.upload_ms += t.upload_ms / k as f64;
            m.trace_ms += t.trace_ms / k as f64;
        }
        Some(m)
    }
}

impl FrameTimes {
    pub fn zero() -> FrameTimes {
        FrameTimes { frame: 0, seconds: 0.0, pose_ms: 0.0, build_ms: 0.0, upload_ms: 0.0, trace_ms: 0.0 }
    }
}

fn clip_name(c: &Clip) -> String {
    match &c.name {
        Some(n) => format!("{} {n}", c.index),
        None => format!("{}", c.index),
    }
}

/// The timeline panel: clip, play/pause, steps, the time slider, speed, loop, the frame rate
/// and the plot of per-frame times.
pub fn ui(ui: &mut egui::Ui, tl: &mut Timeline, clips: &[Clip]) {
    let Some(clip) = clips.get(tl.clip) else { return };
    ui.horizontal(|ui| {
        let mut chosen = tl.clip;
        egui::ComboBox::from_id_salt("timeline clip").selected_text(clip_name(clip)).show_ui(ui, |ui| {
            for c in clips {
                ui.selectable_value(&mut chosen, c.index, clip_name(c));
            }
        });
        if chosen != tl.clip {
            tl.clip = chosen;
            tl.seek(&clips[chosen], clips[chosen].start);
        }
        let clip = &clips[tl.clip];
        if ui.button("<").on_hover_text(format!("back 1/{STEP_FPS} s (pauses)")).clicked() {
            tl.step(clip, -1);
        }
        if ui.add_sized([56.0, 18.0], egui::Button::new(if tl.playing { "pause" } else { "play" })).clicked() {
            tl.toggle(clip);
        }
        if ui.button(">").on_hover_text(format!("forward 1/{STEP_FPS} s (pauses)")).clicked() {
            tl.step(clip, 1);
        }
        let mut t = tl.seconds;
        let slider = egui::Slider::new(&mut t, clip.start..=clip.end.max(clip.start + 1e-6))
            .text("s")
            .fixed_decimals(2)
            .clamping(egui::SliderClamping::Always);
        if ui.add_sized([ui.available_width().clamp(120.0, 360.0), 18.0], slider).changed() {
            tl.seek(clip, t);
        }
        ui.add(egui::DragValue::new(&mut tl.speed).range(0.05..=8.0).speed(0.01).prefix("speed ×"));
        ui.checkbox(&mut tl.looped, "loop");
    });
    let text = match (tl.fps(), tl.mean(30)) {
        (Some(fps), Some(m)) => format!(
            "{fps:.1} frames/s, each posed, rebuilt and traced · mean of the last 30: pose {:.1} ms, build {:.1} ms, \
             upload {:.1} ms, trace {:.1} ms",
            m.pose_ms, m.build_ms, m.upload_ms, m.trace_ms
        ),
        _ => format!("{} frames shown", tl.frames_shown),
    };
    ui.add(egui::Label::new(egui::RichText::new(text).small()).truncate());
    if tl.history.len() < 2 {
        return;
    }
    let series = |name: &str, f: fn(&FrameTimes) -> f64| {
        Line::new(name, tl.history.iter().map(|t| [t.frame as f64, f(t)]).collect::<Vec<_>>())
    };
    Plot::new("timeline plot")
        .height(ui.available_height().max(PLOT_HEIGHT))
        .legend(Legend::default())
        .x_axis_label("frame")
        .y_axis_label("ms")
        .allow_scroll(false)
        .include_y(0.0)
        .show(ui, |p| {
            p.line(series("pose", |t| t.pose_ms));
            p.line(series("build", |t| t.build_ms));
            p.line(series("upload", |t| t.upload_ms));
            p.line(series("trace", |t| t.trace_ms));
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(start: f64, end: f64) -> Clip {
        // A real clip from a generated file (the fields are private to the scene crate).
        let glb = gridrt_scene::crowd::crowd_glb(1, 1);
        let loaded = gridrt_scene::gltf_load::load_rigged_slice_with(&glb, "crowd", None, &Default::default()).unwrap();
        let mut c = loaded.rig.clips()[0].clone();
        c.start = start;
        c.end = end;
        c
    }

    #[test]
    fn playback_follows_the_clock_loops_or_stops_and_steps() {
        let c = clip(1.0, 3.0);
        let t0 = Instant::now();
        let mut tl = Timeline::new(0, 1.0, true);
        tl.tick(&c, t0);
        assert_eq!(tl.seconds, 1.0, "the first tick only starts the clock");
        tl.tick(&c, t0 + Duration::from_millis(500));
        assert!((tl.seconds - 1.5).abs() < 1e-9, "{}", tl.seconds);
        tl.speed = 2.0;
        tl.tick(&c, t0 + Duration::from_millis(1500));
        assert!((tl.seconds - 1.5).abs() < 1e-9, "1.5 + 2 × 1 s loops over the 2 s clip: {}", tl.seconds);
        tl.looped = false;
        tl.tick(&c, t0 + Duration::from_millis(3000));
        assert_eq!((tl.seconds, tl.playing), (3.0, false), "an unlooped clip stops at its end");
        tl.toggle(&c);
        assert_eq!((tl.seconds, tl.playing), (1.0, true), "play at the end starts over");
        tl.step(&c, 3);
        assert!(!tl.playing && (tl.seconds - 1.1).abs() < 1e-9, "{}", tl.seconds);
        tl.step(&c, -100);
        assert_eq!(tl.seconds, 1.0);
        let before = tl.seconds;
        tl.tick(&c, t0 + Duration::from_secs(10));
        assert_eq!(tl.seconds, before, "paused: the clock does not move the clip");
    }

    #[test]
    fn frame_rate_and_means_come_from_the_shown_frames() {
        let t0 = Instant::now();
        let mut tl = Timeline::new(0, 0.0, true);
        assert_eq!((tl.fps(), tl.mean(10)), (None, None));
        for k in 0..=20u64 {
            let times = FrameTimes { pose_ms: 1.0, build_ms: k as f64, trace_ms: 4.0, ..FrameTimes::zero() };
            tl.record(times, t0 + Duration::from_millis(100 * k));
        }
        // 21 frames 100 ms apart, all within the window.
        assert!((tl.fps().unwrap() - 10.0).abs() < 1e-9, "{:?}", tl.fps());
        let m = tl.mean(5).unwrap();
        assert_eq!((m.pose_ms, m.trace_ms), (1.0, 4.0));
        assert!((m.build_ms - 18.0).abs() < 1e-9, "mean of 16..=20: {}", m.build_ms);
        assert_eq!(tl.history.back().unwrap().frame, 20);
        // Frames older than the window leave the rate, but the last two always count.
        tl.record(FrameTimes::zero(), t0 + Duration::from_millis(2000 + 3000));
        assert!(tl.fps().unwrap() < 10.0);
        tl.record(FrameTimes::zero(), t0 + Duration::from_millis(5000 + 10_000));
        assert!((tl.fps().unwrap() - 0.1).abs() < 1e-9, "one frame in 10 s: {:?}", tl.fps());
    }
}
