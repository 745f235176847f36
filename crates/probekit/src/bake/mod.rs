//! Probe capture: Monte Carlo path tracing of the incoming radiance at a
//! point, projected into radiance SH.

pub mod sampling;
