//! The one progress-bar factory of the command line ([`Phases`]): a bar on stderr when it is
//! a terminal, labelled with the phase and the unit it counts; plain lines when stderr is a
//! file or a pipe and the run is long (`CREST_PROGRESS=off` silences them).

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Off a terminal, nothing is printed before a run has lasted this long (short commands
/// leave stderr as it was), then a line at most this often within a phase.
const LINE_EVERY: Duration = Duration::from_secs(5);

/// The progress of a pipeline run drawn on stderr: on a terminal, a spinner with the phase's
/// name and its elapsed time from the first second, and a bar with the count and the time
/// left once the phase counts steps out of a known total; off a terminal (a log file, CI),
/// once the run has lasted [`LINE_EVERY`], one plain line when a phase begins and one every
/// [`LINE_EVERY`] with the phase, its percentage and the time left (`CREST_PROGRESS=off`: none).
/// Every command that shows progress draws it with this (`simulate` through the pipeline,
/// `study` run by run).
pub struct Phases {
    bar: Option<ProgressBar>,
    /// The plain lines, shared with a thread that prints a due line while a long step of
    /// the work reports nothing.
    lines: Option<Arc<Mutex<Lines>>>,
}

/// The state of the plain lines.
struct Lines {
    start: Instant,
    phase: String,
    unit: String,
    phase_start: Instant,
    /// When a line was last printed (`None`: none yet in this phase).
    last: Option<Instant>,
    /// The last count reported in this phase (`total` 0: none).
    done: u64,
    total: u64,
    /// Finished: the thread stops.
    stopped: bool,
}

impl Lines {
    /// The line for `done` of `total` steps at `now`, if one is due.
    fn due(&mut self, done: u64, total: u64, now: Instant) -> Option<String> {
        if now.duration_since(self.start) < LINE_EVERY {
            return None;
        }
        if self
            .last
            .is_some_and(|t| now.duration_since(t) < LINE_EVERY)
        {
            return None;
        }
        self.last = Some(now);
        let phase_s = now.duration_since(self.phase_start).as_secs_f64();
        let total_s = now.duration_since(self.start).as_secs_f64();
        Some(if total > 0 {
            let frac = (done as f64 / total as f64).clamp(0.0, 1.0);
            let eta = if done > 0 {
                format!(
                    ", about {} left",
                    seconds(phase_s * (total - done.min(total)) as f64 / done as f64)
                )
            } else {
                String::new()
            };
            format!(
                "progress: {} {:.0}% ({done}/{total} {}){eta}; {} in all",
                self.phase,
                100.0 * frac,
                self.unit,
                seconds(total_s)
            )
        } else {
            format!("progress: {}; {} in all", self.phase, seconds(total_s))
        })
    }
}

/// A duration for people: "42 s", "3 min 05 s", "2 h 07 min".
fn seconds(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s} s"),
        60..3600 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, (s % 3600) / 60),
    }
}

impl Phases {
    /// Start drawing: a bar on a terminal, plain lines elsewhere (none with
    /// `CREST_PROGRESS=off`).
    pub fn new() -> Self {
        if !std::io::stderr().is_terminal() {
            let off = std::env::var("CREST_PROGRESS").is_ok_and(|v| v == "off" || v == "0");
            if off {
                return Self {
                    bar: None,
                    lines: None,
                };
            }
            let now = Instant::now();
            let lines = Arc::new(Mutex::new(Lines {
                start: now,
                phase: String::new(),
                unit: String::new(),
                phase_start: now,
                last: None,
                done: 0,
                total: 0,
                stopped: false,
            }));
            let shared = Arc::clone(&lines);
            // Wakes every second; a due line is printed even while no step finishes.
            std::thread::spawn(move || {
                loop {
                    std::thread::sleep(Duration::from_secs(1));
                    let mut l = shared.lock().unwrap_or_else(|e| e.into_inner());
                    if l.stopped {
                        break;
                    }
                    let (done, total) = (l.done, l.total);
                    if let Some(text) = l.due(done, total, Instant::now()) {
                        eprintln!("{text}");
                    }
                }
            });
            return Self {
                bar: None,
                lines: Some(lines),
            };
        }
        let b = ProgressBar::new_spinner();
        b.enable_steady_tick(std::time::Duration::from_millis(120));
        Self {
            bar: Some(b),
            lines: None,
        }
    }

    /// A counter of `total` steps of phase `name` (in `unit`), for work that reports each
    /// finished step from any thread: call the returned closure once per step.
    pub fn counter<'a>(&'a self, name: &str, unit: &str, total: u64) -> impl Fn() + Sync + 'a {
        use crest::pipeline::Progress;
        use std::sync::atomic::{AtomicU64, Ordering};
        self.phase(name, unit);
        self.advance(0, total);
        let done = AtomicU64::new(0);
        move || {
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            self.advance(d, total);
        }
    }

    /// Remove the bar; stop the lines.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        self.line(|l| {
            l.stopped = true;
            None
        });
    }

    fn line(&self, f: impl FnOnce(&mut Lines) -> Option<String>) {
        let Some(l) = &self.lines else { return };
        let mut l = l.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(text) = f(&mut l) {
            eprintln!("{text}");
        }
    }
}

impl crest::pipeline::Progress for Phases {
    fn phase(&self, name: &str, unit: &str) {
        self.line(|l| {
            let now = Instant::now();
            l.phase = name.to_string();
            l.unit = unit.to_string();
            l.phase_start = now;
            l.last = None;
            (l.done, l.total) = (0, 0);
            l.due(0, 0, now)
        });
        let Some(b) = &self.bar else { return };
        b.set_style(
            ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        b.set_length(0);
        b.set_position(0);
        b.reset_elapsed();
        b.reset_eta();
        b.set_message(name.to_string());
        b.set_prefix(unit.to_string());
    }

    fn advance(&self, done: u64, total: u64) {
        self.line(|l| {
            (l.done, l.total) = (done, total);
            l.due(done, total, Instant::now())
        });
        let Some(b) = &self.bar else { return };
        if total > 0 && b.length() != Some(total) {
            if b.length().unwrap_or(0) == 0 {
                b.set_style(
                    ProgressStyle::with_template(
                        "{spinner} {msg} [{bar:40}] {pos}/{len} {prefix} {elapsed} eta {eta}",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
                );
            }
            b.set_length(total);
        }
        b.set_position(done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(at: Instant) -> Lines {
        Lines {
            start: at,
            phase: "simulating".into(),
            unit: "tiles".into(),
            phase_start: at,
            last: None,
            done: 0,
            total: 0,
            stopped: false,
        }
    }

    #[test]
    fn lines_wait_for_a_long_run_then_come_at_a_modest_rate_with_the_time_left() {
        let t0 = Instant::now();
        let mut l = lines(t0);
        assert_eq!(l.due(1, 10, t0 + Duration::from_secs(2)), None);
        let first = l.due(2, 10, t0 + Duration::from_secs(6)).unwrap();
        assert_eq!(
            first,
            "progress: simulating 20% (2/10 tiles), about 24 s left; 6 s in all"
        );
        assert_eq!(l.due(3, 10, t0 + Duration::from_secs(8)), None);
        assert!(l.due(4, 10, t0 + Duration::from_secs(12)).is_some());
        assert_eq!(seconds(185.0), "3 min 05 s");
        assert_eq!(seconds(7620.0), "2 h 07 min");
    }
}
