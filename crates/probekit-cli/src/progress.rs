//! The one progress display of every long command.
//!
//! The library reports progress as `(phase, done, total)` calls. On a
//! terminal they drive one bar named by the phase; off a terminal (a pipe,
//! a CI log) they print one line when a phase starts, one per 10 % of it
//! with the elapsed time and an estimate of what is left (once the phase has
//! run [`QUIET`], so a phase of a moment prints two lines, not twelve), and
//! one when it ends — so a bake in a log says what it is doing. A bar never
//! passes its total.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Off a terminal, a phase's 10 % lines start once it has run this long.
pub const QUIET: Duration = Duration::from_secs(1);

/// Progress of a command on stderr (see the module docs).
pub struct Progress {
    bar: Option<ProgressBar>,
    lines: Mutex<Lines>,
}

/// The line printer's state.
struct Lines {
    phase: String,
    started: Instant,
    /// Tenths of the phase already reported.
    tenths: usize,
    finished: bool,
}

impl Progress {
    /// A bar when stderr is a terminal, else lines.
    pub fn new() -> Self {
        Self::with_terminal(std::io::stderr().is_terminal())
    }

    /// A bar (`terminal`) or lines.
    pub fn with_terminal(terminal: bool) -> Self {
        let bar = terminal.then(|| {
            let pb = ProgressBar::new(0);
            pb.set_style(
                ProgressStyle::with_template(
                    "{msg:28} {bar:40} {pos}/{len}  {elapsed} elapsed, ETA {eta}",
                )
                .expect("static template"),
            );
            pb
        });
        Progress {
            bar,
            lines: Mutex::new(Lines {
                phase: String::new(),
                started: Instant::now(),
                tenths: 0,
                finished: true,
            }),
        }
    }

    /// Reports `done` of `total` in `phase` (`done` is clamped to `total`).
    pub fn update(&self, phase: &str, done: usize, total: usize) {
        let done = done.min(total);
        if let Some(pb) = &self.bar {
            if pb.message() != phase {
                pb.set_message(phase.to_string());
                pb.reset_elapsed();
                pb.reset_eta();
            }
            pb.set_length(total as u64);
            pb.set_position(done as u64);
            return;
        }
        let Ok(mut l) = self.lines.lock() else {
            return;
        };
        if l.phase != phase {
            if !l.finished {
                let secs = l.started.elapsed().as_secs_f64();
                eprintln!("{}: done in {}", l.phase, seconds(secs));
            }
            l.phase = phase.to_string();
            l.started = Instant::now();
            l.tenths = 0;
            l.finished = false;
            eprintln!("{phase}: started ({total})");
        }
        if l.finished || total == 0 {
            return;
        }
        if done == total {
            l.finished = true;
            let secs = l.started.elapsed().as_secs_f64();
            eprintln!("{phase}: done ({total}) in {}", seconds(secs));
            return;
        }
        let tenths = done * 10 / total;
        if tenths > l.tenths && l.started.elapsed() >= QUIET {
            l.tenths = tenths;
            let secs = l.started.elapsed().as_secs_f64();
            let left = secs * (total - done) as f64 / done.max(1) as f64;
            eprintln!(
                "{phase}: {}0 % ({done}/{total}), {} elapsed, about {} left",
                tenths,
                seconds(secs),
                seconds(left)
            );
        }
    }

    /// A callback for the library's `(phase, done, total)` progress.
    pub fn callback(&self) -> impl Fn(&str, usize, usize) + Sync + '_ {
        move |phase, done, total| self.update(phase, done, total)
    }

    /// A callback for a `(done, total)` progress of one `phase`.
    pub fn phase<'a>(&'a self, phase: &'a str) -> impl Fn(usize, usize) + Sync + 'a {
        move |done, total| self.update(phase, done, total)
    }

    /// Clears the bar (before the command prints its result).
    pub fn finish(&self) {
        if let Some(pb) = &self.bar {
            pb.finish_and_clear();
        }
    }
}

impl Default for Progress {
    fn default() -> Self {
        Self::new()
    }
}

/// `12.3 s`, `4 min 05 s`.
fn seconds(s: f64) -> String {
    let d = Duration::from_secs_f64(s.max(0.0));
    if d.as_secs() >= 60 {
        format!("{} min {:02} s", d.as_secs() / 60, d.as_secs() % 60)
    } else {
        format!("{s:.1} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_people_write_them() {
        assert_eq!(seconds(3.04), "3.0 s");
        assert_eq!(seconds(245.0), "4 min 05 s");
    }
}
