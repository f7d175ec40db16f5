//! The one progress-bar factory of the command line: a bar on stderr when it is a terminal
//! (nothing otherwise), labelled with the phase and the unit it counts.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar of `len` steps for phase `label`, counting `unit`, or `None` when stderr
/// is not a terminal.
pub fn bar(len: u64, label: &str, unit: &str) -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let b = ProgressBar::new(len);
    let template = format!(
        "{{spinner}} {label} [{{bar:40}}] {{pos}}/{{len}} {unit} {{elapsed_precise}} eta {{eta}}"
    );
    b.set_style(
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    Some(b)
}
