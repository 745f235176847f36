//! The one progress callback of long library calls, `(phase, done, total)`,
//! and the phase timing of a bake ([`Clock`], [`PhaseTime`]): wall and CPU
//! seconds and rays traced per phase.

use serde::Serialize;
use std::time::{Duration, Instant};

/// Progress of a long step: `progress(phase, done, total)` after each unit
/// of work; `phase` names what is running (`"capture"`, `"visibility"`, a
/// sweep's `"adaptive 100: capture"`), `done` of `total` units are finished.
/// `Sync`, since parallel work reports from any thread.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// What one phase of a bake cost: wall-clock and CPU seconds and rays
/// traced, with the phases inside it (placement's pool, scoring, …).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PhaseTime {
    /// The phase: `load`, `placement`, `capture`, `distance moments`, `cell
    /// visibility`, `weight fit`, `assembly` (a sub-phase: its own name).
    pub phase: String,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// CPU seconds of the whole process (user and system, every thread)
    /// while the phase ran, from the operating system's process CPU clock
    /// (`clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`, `GetProcessTimes` on
    /// Windows); 0 where the clock cannot be read. With `n` threads busy it
    /// approaches `n ×` the wall time; under other load it stays near the
    /// work done, where wall time grows.
    pub cpu_seconds: f64,
    /// Rays the bake's tracer intersected with the scene in the phase
    /// (closest-hit, any-hit and transmittance queries alike; analytic
    /// light shapes are not rays). The same for any thread count.
    pub rays: u64,
    /// The phases inside this one, in the order they first ran; a phase
    /// that runs more than once (placement's rounds) sums its runs.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub phases: Vec<PhaseTime>,
}

impl PhaseTime {
    /// A phase named `phase` that took nothing.
    pub fn zero(phase: &str) -> Self {
        PhaseTime {
            phase: phase.to_string(),
            wall_seconds: 0.0,
            cpu_seconds: 0.0,
            rays: 0,
            phases: Vec::new(),
        }
    }

    /// Adds `other`'s seconds and rays to this one's (sub-phases too, by
    /// name).
    pub fn add(&mut self, other: &PhaseTime) {
        self.wall_seconds += other.wall_seconds;
        self.cpu_seconds += other.cpu_seconds;
        self.rays += other.rays;
        for p in &other.phases {
            add_phase(&mut self.phases, p);
        }
    }
}

/// Adds `p` to the entry of `phases` with its name, or appends it.
fn add_phase(phases: &mut Vec<PhaseTime>, p: &PhaseTime) {
    match phases.iter_mut().find(|q| q.phase == p.phase) {
        Some(q) => q.add(p),
        None => phases.push(p.clone()),
    }
}

/// The process's CPU time so far (user and system, all threads), `None`
/// where the operating system's clock cannot be read.
pub fn process_cpu_time() -> Option<Duration> {
    cpu_time::ProcessTime::try_now()
        .ok()
        .map(|t| t.as_duration())
}

/// A point in time for [`Clock`]: wall clock, process CPU time and the
/// tracer's ray count.
#[derive(Clone, Copy, Debug)]
struct Mark {
    wall: Instant,
    cpu: Option<Duration>,
    rays: u64,
}

impl Mark {
    fn now(rays: u64) -> Self {
        Mark {
            wall: Instant::now(),
            cpu: process_cpu_time(),
            rays,
        }
    }
}

/// Times consecutive phases: each [`Clock::lap`] ends the running phase
/// and starts the next. A lap whose name was used before adds to that
/// entry, so interleaved phases (scoring and capture in placement's
/// rounds) sum up. Rays come from the caller (the tracer's running count,
/// [`crate::trace::Tracer::rays`]).
#[derive(Clone, Debug)]
pub struct Clock {
    last: Mark,
    phases: Vec<PhaseTime>,
}

impl Clock {
    /// Starts timing now; `rays` is the tracer's count now (0 without one).
    pub fn new(rays: u64) -> Self {
        Clock {
            last: Mark::now(rays),
            phases: Vec::new(),
        }
    }

    /// Ends `phase` now, `rays` the tracer's count now, and starts the next.
    pub fn lap(&mut self, phase: &str, rays: u64) -> &mut PhaseTime {
        self.lap_with(phase, rays, Vec::new())
    }

    /// [`Clock::lap`] with the sub-phases `inner` timed inside `phase`.
    pub fn lap_with(&mut self, phase: &str, rays: u64, inner: Vec<PhaseTime>) -> &mut PhaseTime {
        let now = Mark::now(rays);
        let cpu = match (now.cpu, self.last.cpu) {
            (Some(a), Some(b)) => a.saturating_sub(b).as_secs_f64(),
            _ => 0.0,
        };
        let p = PhaseTime {
            phase: phase.to_string(),
            wall_seconds: (now.wall - self.last.wall).as_secs_f64(),
            cpu_seconds: cpu,
            rays: now.rays.saturating_sub(self.last.rays),
            phases: inner,
        };
        self.last = now;
        let i = match self.phases.iter().position(|q| q.phase == p.phase) {
            Some(i) => {
                self.phases[i].add(&p);
                i
            }
            None => {
                self.phases.push(p);
                self.phases.len() - 1
            }
        };
        &mut self.phases[i]
    }

    /// Restarts the running phase now (what ran since the last lap is not
    /// counted), `rays` the tracer's count now.
    pub fn restart(&mut self, rays: u64) {
        self.last = Mark::now(rays);
    }

    /// The phases so far, in order.
    pub fn phases(&self) -> &[PhaseTime] {
        &self.phases
    }

    /// The phases so far, taking them out (the clock goes on timing).
    pub fn take_phases(&mut self) -> Vec<PhaseTime> {
        std::mem::take(&mut self.phases)
    }

    /// Adds `phases` (timed elsewhere) to this clock's, by name.
    pub fn absorb(&mut self, phases: &[PhaseTime]) {
        for p in phases {
            add_phase(&mut self.phases, p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Laps of one name add up; rays are the differences of the counts
    /// given; wall and CPU seconds are non-negative and a busy loop's CPU
    /// time shows.
    #[test]
    fn laps_sum_by_name_and_count_rays_between_marks() {
        let mut c = Clock::new(10);
        c.lap("a", 15);
        c.lap("b", 40);
        let t = Instant::now();
        let mut x = 0u64;
        while t.elapsed() < Duration::from_millis(30) {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        c.lap("a", 41);
        let p = c.phases();
        assert_eq!(p.len(), 2);
        assert_eq!((p[0].phase.as_str(), p[0].rays), ("a", 6));
        assert_eq!((p[1].phase.as_str(), p[1].rays), ("b", 25));
        assert!(p[0].wall_seconds >= 0.03);
        assert!(p
            .iter()
            .all(|q| q.wall_seconds >= 0.0 && q.cpu_seconds >= 0.0));
        if process_cpu_time().is_some() {
            assert!(p[0].cpu_seconds > 0.0, "{p:?}");
        }
    }

    /// Sub-phases add by name, in first-seen order.
    #[test]
    fn sub_phases_add_by_name() {
        let sub = |n: &str, r| PhaseTime {
            rays: r,
            ..PhaseTime::zero(n)
        };
        let mut c = Clock::new(0);
        c.lap_with("p", 0, vec![sub("x", 1), sub("y", 2)]);
        c.lap_with("p", 0, vec![sub("y", 3), sub("z", 4)]);
        let p = &c.phases()[0];
        let got: Vec<(&str, u64)> = p
            .phases
            .iter()
            .map(|q| (q.phase.as_str(), q.rays))
            .collect();
        assert_eq!(got, [("x", 1), ("y", 5), ("z", 4)]);
    }
}
