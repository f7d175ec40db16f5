//! The one progress-bar factory of the command line ([`Phases`]): a bar on stderr when it is
//! a terminal (nothing otherwise), labelled with the phase and the unit it counts.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// The progress of a pipeline run drawn on stderr (when it is a terminal): a spinner with
/// the phase's name and its elapsed time from the first second, and a bar with the count and
/// the time left once the phase counts steps out of a known total. Every command that shows
/// progress draws it with this (`simulate` through the pipeline, `study` run by run).
pub struct Phases {
    bar: Option<ProgressBar>,
}

impl Phases {
    /// Start drawing (nothing when stderr is not a terminal).
    pub fn new() -> Self {
        if !std::io::stderr().is_terminal() {
            return Self { bar: None };
        }
        let b = ProgressBar::new_spinner();
        b.enable_steady_tick(std::time::Duration::from_millis(120));
        Self { bar: Some(b) }
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

    /// Remove the bar.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

impl crest::pipeline::Progress for Phases {
    fn phase(&self, name: &str, unit: &str) {
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
