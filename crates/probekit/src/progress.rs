//! The one progress callback of long library calls: `(phase, done, total)`.

/// Progress of a long step: `progress(phase, done, total)` after each unit
/// of work; `phase` names what is running (`"capture"`, `"visibility"`, a
/// sweep's `"adaptive 100: capture"`), `done` of `total` units are finished.
/// `Sync`, since parallel work reports from any thread.
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);
