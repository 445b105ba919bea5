//! Progress on stderr for work that can take seconds — a calibration's
//! solver, a large simulated campaign, a plan's sampling and choosing:
//! drawn only when stderr is a terminal, so logs and pipes get nothing.

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
    /// A bar on stderr when it is a terminal, else nothing. Hidden until a
    /// run lasts (indicatif draws at most a few times a second).
    pub fn new() -> Bar {
        Bar::when(std::io::stderr().is_terminal(), ProgressDrawTarget::stderr)
    }

    /// The decision apart from where the bar is drawn: a bar drawn to
    /// `target` when `terminal`, else none.
    fn when(terminal: bool, target: impl FnOnce() -> ProgressDrawTarget) -> Bar {
        let bar = terminal.then(|| {
            let bar = ProgressBar::with_draw_target(Some(STEPS), target());
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

    /// Shows `phase` running without a measure of how far it is: a spinner
    /// and the time it has taken.
    pub fn busy(&mut self, phase: &str) {
        if let Some(bar) = &self.bar {
            bar.set_style(
                ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            self.phase = phase.to_string();
            bar.set_message(self.phase.clone());
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Not a terminal: no bar, and showing progress draws nothing.
    #[test]
    fn nothing_is_drawn_when_stderr_is_not_a_terminal() {
        let mut bar = Bar::when(false, || panic!("no draw target is made"));
        assert!(bar.bar.is_none());
        bar.show("simulate", 0.5);
        bar.busy("choosing");
        assert!(bar.phase.is_empty());
    }

    /// A terminal: a bar that follows the phase and the fraction done.
    #[test]
    fn a_terminal_gets_a_bar_that_follows_the_work() {
        let mut bar = Bar::when(true, ProgressDrawTarget::hidden);
        bar.show("simulate", 0.25);
        let inner = bar.bar.clone().expect("a bar");
        assert_eq!(
            (inner.position(), inner.message()),
            (250, "simulate".into())
        );
        bar.show("simulate", 2.0);
        assert_eq!(inner.position(), STEPS);
        bar.busy("choosing");
        assert_eq!(inner.message(), "choosing");
    }
}
