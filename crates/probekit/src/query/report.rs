//! [`QueryReport`]: the irradiance `probekit query` prints.

use glam::Vec3;
use probekit_runtime::{ObjectState, Probes, QueryError};
use serde::Serialize;

/// Irradiance `E(n)` (linear RGB, not divided by π) at one point or at
/// each point of a batch, as `probekit query` prints it: serialised as
/// `{"irradiance":[r,g,b]}` for one point and
/// `{"irradiance":[[r,g,b],...]}` for a batch.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QueryReport {
    /// The irradiance: one triple, or one per point in order.
    pub irradiance: Irradiance,
}

/// One irradiance or a batch of them (serialised without a tag).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Irradiance {
    /// At one point.
    One([f32; 3]),
    /// At each point of a batch, in order.
    Batch(Vec<[f32; 3]>),
}

impl QueryReport {
    /// The irradiance of `probes` at `position` for `normal`.
    pub fn one(probes: &Probes, position: Vec3, normal: Vec3) -> Result<Self, QueryError> {
        let e = probes.irradiance(&mut ObjectState::new(), position, normal)?;
        Ok(Self {
            irradiance: Irradiance::One(e),
        })
    }

    /// The irradiance of `probes` at every `(position, normal)` pair, in
    /// order ([`irradiance_at`]).
    pub fn batch(probes: &Probes, points: &[(Vec3, Vec3)]) -> Result<Self, QueryError> {
        Ok(Self {
            irradiance: Irradiance::Batch(irradiance_at(probes, points)?),
        })
    }
}

/// The irradiance of `probes` at every `(position, normal)` pair, in order,
/// sharing one [`ObjectState`] (a coherent batch walks little); the first
/// bad query is the error (its `index` is the pair's).
pub fn irradiance_at(
    probes: &Probes,
    points: &[(Vec3, Vec3)],
) -> Result<Vec<[f32; 3]>, QueryError> {
    let (positions, normals): (Vec<Vec3>, Vec<Vec3>) = points.iter().copied().unzip();
    let mut out = vec![[0.0; 3]; points.len()];
    probes.irradiance_many(&mut ObjectState::new(), &positions, &normals, &mut out)?;
    Ok(out)
}
