//! A progress bar on stderr for long solver runs: drawn only when stderr is
//! a terminal, so logs and pipes get nothing.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Steps of the bar.
const STEPS: u64 = 1000;

/// The bar, or nothing when stderr is not a terminal.
pub struct Bar {
    bar: Option<ProgressBar>,
    phase: String,
}

impl Bar {
    /// A hidden bar that appears once a run lasts (indicatif draws at most
    /// a few times a second).
    pub fn new() -> Bar {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::with_draw_target(Some(STEPS), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("{msg:>8} [{bar:40}] {percent:>3}% {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            bar.enable_steady_tick(Duration::from_millis(200));
            bar
        });
        Bar {
            bar,
            phase: String::new(),
        }
    }

    /// Shows `fraction` of `phase` done.
    pub fn show(&mut self, phase: &str, fraction: f64) {
        if let Some(bar) = &self.bar {
            if phase != self.phase {
                self.phase = phase.to_string();
                bar.set_message(self.phase.clone());
            }
            bar.set_position((fraction.clamp(0.0, 1.0) * STEPS as f64) as u64);
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
