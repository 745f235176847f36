//! Truth at a point: path-traced irradiance for the six axis normals with
//! probekit's reference integrator, beside the probes' answer there, on one
//! worker thread that owns the ray tracer. Jobs are numbered, queued, and
//! kept (so every tab sees every earlier point); progress is polled.
//!
//! A leak, as `probekit eval` counts one: the probes' luminance above 4× the
//! true luminance plus 1 % of the mean irradiance of the file's probes.

use crate::query::Probes;
use glam::Vec3;
use probekit::capture::{Baker, ReferenceSettings};
use probekit::scene::Scene;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;

/// The six normals, in the order of every per-normal list: +x, −x, +y, −y,
/// +z, −z.
pub const NORMALS: [(&str, Vec3); 6] = [
    ("+x", Vec3::X),
    ("-x", Vec3::NEG_X),
    ("+y", Vec3::Y),
    ("-y", Vec3::NEG_Y),
    ("+z", Vec3::Z),
    ("-z", Vec3::NEG_Z),
];

/// Most jobs kept; older ones are forgotten first.
pub const MAX_JOBS: usize = 1000;

/// Where a job is.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// Waiting for the worker.
    Queued,
    /// Being traced; `done` normals of six finished.
    Running {
        /// Normals finished.
        done: usize,
    },
    /// Finished.
    Done {
        /// True irradiance per normal.
        truth: [Vec3; 6],
        /// Its standard error per normal.
        std_error: [Vec3; 6],
    },
    /// Failed (the message says why).
    Failed(String),
}

/// One truth request.
#[derive(Clone, Debug)]
pub struct Job {
    /// Its number (from 1).
    pub id: u64,
    /// The point, metres.
    pub position: Vec3,
    /// Samples per normal.
    pub samples: u32,
    /// The probes' irradiance per normal at the point, when asked.
    pub probes: [Vec3; 6],
    /// Where it is.
    pub status: Status,
}

/// The leak floor's `mean` and the test itself (see the module docs).
pub fn is_leak(probes: Vec3, truth: Vec3, mean_irradiance: f32) -> bool {
    probekit::eval::is_leak(probes, truth, mean_irradiance)
}

/// `|probes − truth| / |truth|` (RGB lengths), with the denominator kept at
/// least 1 % of `mean_irradiance` so an unlit point gives a finite error.
pub fn relative_error(probes: Vec3, truth: Vec3, mean_irradiance: f32) -> f32 {
    (probes - truth).length() / (truth.length().max(0.01 * mean_irradiance)).max(1e-12)
}

impl Job {
    /// The job as JSON (see docs/view.md, `GET /api/truth/ID`).
    pub fn to_json(&self, mean_irradiance: f32) -> serde_json::Value {
        let per = |f: &dyn Fn(usize) -> serde_json::Value| -> serde_json::Value {
            let mut m = serde_json::Map::new();
            for (k, (name, _)) in NORMALS.iter().enumerate() {
                m.insert(name.to_string(), f(k));
            }
            serde_json::Value::Object(m)
        };
        let mut v = serde_json::json!({
            "id": self.id,
            "position": self.position.to_array(),
            "samples": self.samples,
            "probes": per(&|k| serde_json::json!(self.probes[k].to_array())),
        });
        let (status, progress) = match &self.status {
            Status::Queued => ("queued", 0.0),
            Status::Running { done } => ("running", *done as f32 / 6.0),
            Status::Done { .. } => ("done", 1.0),
            Status::Failed(_) => ("failed", 0.0),
        };
        v["status"] = status.into();
        v["progress"] = progress.into();
        match &self.status {
            Status::Done { truth, std_error } => {
                v["truth"] = per(&|k| serde_json::json!(truth[k].to_array()));
                v["std_error"] = per(&|k| serde_json::json!(std_error[k].to_array()));
                v["relative_error"] = per(&|k| {
                    serde_json::json!(relative_error(self.probes[k], truth[k], mean_irradiance))
                });
                v["leak"] =
                    per(&|k| serde_json::json!(is_leak(self.probes[k], truth[k], mean_irradiance)));
                let leaks = (0..6).filter(|&k| is_leak(self.probes[k], truth[k], mean_irradiance));
                v["any_leak"] = (leaks.count() > 0).into();
                let worst = (0..6)
                    .map(|k| relative_error(self.probes[k], truth[k], mean_irradiance))
                    .fold(0.0f32, f32::max);
                v["max_relative_error"] = worst.into();
            }
            Status::Failed(msg) => v["error"] = msg.clone().into(),
            _ => {}
        }
        v
    }
}

/// The job table and the worker.
pub struct Truth {
    jobs: Arc<Mutex<Vec<Job>>>,
    sender: Mutex<Option<Sender<u64>>>,
    stop: Arc<AtomicBool>,
    worker: Mutex<Option<JoinHandle<()>>>,
    next_id: Mutex<u64>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic elsewhere must not take the table down with it.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Truth {
    /// Starts the worker over `scene` (`None`: every job fails with "no
    /// scene").
    pub fn start(scene: Option<Arc<Scene>>) -> Self {
        let jobs: Arc<Mutex<Vec<Job>>> = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, rx) = channel::<u64>();
        let (wjobs, wstop) = (jobs.clone(), stop.clone());
        let worker = std::thread::Builder::new()
            .name("truth".into())
            .spawn(move || {
                let baker = scene.as_deref().map(Baker::new);
                while let Ok(id) = rx.recv() {
                    if wstop.load(Ordering::Relaxed) {
                        break;
                    }
                    let Some(job) = lock(&wjobs).iter().find(|j| j.id == id).cloned() else {
                        continue;
                    };
                    let status = match &baker {
                        None => Status::Failed("no scene: truth is off".into()),
                        Some(Err(e)) => Status::Failed(format!("cannot trace the scene: {e}")),
                        Some(Ok(b)) => run(b, &job, &wjobs, &wstop),
                    };
                    if let Some(j) = lock(&wjobs).iter_mut().find(|j| j.id == id) {
                        j.status = status;
                    }
                }
            })
            .ok();
        Truth {
            jobs,
            sender: Mutex::new(Some(tx)),
            stop,
            worker: Mutex::new(worker),
            next_id: Mutex::new(0),
        }
    }

    /// Queues a job at `position` with the probes' answer `probes`; returns it.
    pub fn submit(&self, position: Vec3, samples: u32, probes: [Vec3; 6]) -> Job {
        let id = {
            let mut n = lock(&self.next_id);
            *n += 1;
            *n
        };
        let job = Job {
            id,
            position,
            samples,
            probes,
            status: Status::Queued,
        };
        {
            let mut jobs = lock(&self.jobs);
            if jobs.len() >= MAX_JOBS {
                jobs.remove(0);
            }
            jobs.push(job.clone());
        }
        let sent = lock(&self.sender).as_ref().map(|s| s.send(id).is_ok());
        if sent != Some(true) {
            self.set_status(id, Status::Failed("the truth worker has stopped".into()));
        }
        self.get(id).unwrap_or(job)
    }

    fn set_status(&self, id: u64, status: Status) {
        if let Some(j) = lock(&self.jobs).iter_mut().find(|j| j.id == id) {
            j.status = status;
        }
    }

    /// Job `id`, if kept.
    pub fn get(&self, id: u64) -> Option<Job> {
        lock(&self.jobs).iter().find(|j| j.id == id).cloned()
    }

    /// Every kept job, oldest first.
    pub fn all(&self) -> Vec<Job> {
        lock(&self.jobs).clone()
    }

    /// Stops the worker: a running job ends at its next normal (marked
    /// failed), queued ones are dropped. Waits for the thread.
    pub fn stop(&self) {
        self.stop.store(true, Ordering::Relaxed);
        lock(&self.sender).take();
        if let Some(h) = lock(&self.worker).take() {
            let _ = h.join();
        }
    }
}

/// Traces one job, normal after normal, updating its progress.
fn run(baker: &Baker, job: &Job, jobs: &Mutex<Vec<Job>>, stop: &AtomicBool) -> Status {
    let settings = ReferenceSettings {
        relative_precision: 0.0,
        min_samples: job.samples,
        max_samples: job.samples,
        ..Default::default()
    };
    let mut truth = [Vec3::ZERO; 6];
    let mut std_error = [Vec3::ZERO; 6];
    for (k, (_, n)) in NORMALS.iter().enumerate() {
        if stop.load(Ordering::Relaxed) {
            return Status::Failed("stopped".into());
        }
        if let Some(j) = lock(jobs).iter_mut().find(|j| j.id == job.id) {
            j.status = Status::Running { done: k };
        }
        // The sample index is the normal's: the same point always gets the
        // same truth.
        match baker.reference_irradiance(job.position, *n, k as u64, &settings) {
            Ok(r) => {
                truth[k] = r.irradiance;
                std_error[k] = r.std_error;
            }
            Err(e) => return Status::Failed(e.to_string()),
        }
    }
    Status::Done { truth, std_error }
}

/// The probes' irradiance at `p` for the six normals.
pub fn probes_answer(probes: &Probes, p: Vec3) -> Result<[Vec3; 6], crate::query::QueryError> {
    let mut out = [Vec3::ZERO; 6];
    for (k, (_, n)) in NORMALS.iter().enumerate() {
        out[k] = probes.irradiance(p, *n)?;
    }
    Ok(out)
}
