//! The runtime query the page shows: a loaded probe file answering "radiance
//! SH at this point", with the cell and the weights it blended.
//!
//! This is the one module that knows which type serves queries: the
//! runtime's [`probekit_runtime::Probes`], loaded as an engine loads it,
//! so the page shows what an engine reads. A cloud answers with every
//! blend setting the file stores (distance moments, cell visibility,
//! fitted weights, directional brightness); a volume interpolates
//! trilinearly.

use glam::Vec3;
use probekit_runtime::{LoadOptions, ObjectState, ProbeFile};

/// Why a file cannot answer queries.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct QueryError(String);

/// The cell a query fell in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cell {
    /// Inside tetrahedron `index` of the cloud.
    Tetrahedron(u32),
    /// Outside the cloud's convex hull, lit from hull face `index`.
    HullFace(u32),
    /// In cell `index` of a volume (trilinear over its grid or octree;
    /// [`probekit_runtime::Cell::VolumeCell`] says how cells are numbered).
    Volume(u32),
}

/// One query's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Answer {
    /// Radiance SH at the point, bands 0–2 (9 RGB coefficients), as the
    /// runtime returns them (the blend of the probes below, per direction
    /// where the file's directional brightness applies).
    pub sh: Vec<Vec3>,
    /// Where the point was located.
    pub cell: Cell,
    /// The probes blended (indices into the file's probes): a
    /// tetrahedron's four, a hull face's three, a volume cell's eight
    /// corners.
    pub probes: Vec<u32>,
    /// Their blend weights, summing to 1 (a cloud's after the file's
    /// visibility and fitted weights; a volume's trilinear ones), one per
    /// entry of `probes`.
    pub weights: Vec<f32>,
}

/// A cloud's tetrahedra (four probe indices each) and hull faces (three).
pub type CloudCells = (Vec<[u32; 4]>, Vec<[u32; 3]>);

/// A probe file ready for queries. Queries take `&self`: one value serves
/// every HTTP thread.
pub struct Probes {
    probes: probekit_runtime::Probes,
}

/// A query error as the page reports it.
fn text(e: impl std::fmt::Display) -> QueryError {
    QueryError(e.to_string())
}

impl Probes {
    /// Loads a cloud or a volume (trilinear) with the blend the file
    /// stores.
    pub fn from_file(file: &ProbeFile) -> Result<Self, QueryError> {
        let probes =
            probekit_runtime::Probes::from_file(file, LoadOptions::default()).map_err(text)?;
        Ok(Probes { probes })
    }

    /// SH bands of the file's coefficients.
    pub fn order(&self) -> usize {
        self.probes.order() as usize
    }

    /// Radiance SH at `p` (metres), with the cell and weights
    /// ([`probekit_runtime::Probes::query`], a fresh state for every call).
    pub fn sh_at(&self, p: Vec3) -> Result<Answer, QueryError> {
        let q = self
            .probes
            .query(&mut ObjectState::new(), p)
            .map_err(text)?;
        let (cell, used) = match q.cell {
            probekit_runtime::Cell::Tetrahedron(t) => (Cell::Tetrahedron(t), 4),
            // A hull face blends three probes: the fourth slot is unused.
            probekit_runtime::Cell::HullFace(f) => (Cell::HullFace(f), 3),
            probekit_runtime::Cell::VolumeCell(c) => (Cell::Volume(c), 8),
        };
        Ok(Answer {
            sh: q.sh.iter().map(|c| Vec3::from_array(*c)).collect(),
            cell,
            probes: q.probes[..used].to_vec(),
            weights: q.weights[..used].to_vec(),
        })
    }

    /// Irradiance `E(n)` (not divided by π) at `p` for unit normal `n`, as
    /// the runtime computes it.
    pub fn irradiance(&self, p: Vec3, n: Vec3) -> Result<Vec3, QueryError> {
        let e = self.probes.irradiance(&mut ObjectState::new(), p, n);
        e.map(Vec3::from_array).map_err(text)
    }

    /// Irradiance at many points with their normals, sharing one state
    /// (coherent batches walk little).
    pub fn irradiance_many(&self, points: &[(Vec3, Vec3)]) -> Result<Vec<Vec3>, QueryError> {
        let e = probekit::query::irradiance_at(&self.probes, points).map_err(text)?;
        Ok(e.into_iter().map(Vec3::from_array).collect())
    }

    /// The cloud's tetrahedra and hull faces (probe indices), `None` for a
    /// volume.
    pub fn cells(&self) -> Option<CloudCells> {
        let mesh = self.probes.cloud()?.mesh();
        let hull = (0..mesh.hull_face_count() as u32)
            .filter_map(|f| mesh.hull_face_probes(f))
            .collect();
        Some((mesh.tets().to_vec(), hull))
    }
}
