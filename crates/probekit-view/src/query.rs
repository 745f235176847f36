//! The runtime query the page shows: a loaded probe file answering "radiance
//! SH at this point", with the cell and the weights it blended.
//!
//! This is the one module that knows which type serves queries (today
//! `probekit::query::Predictor`, over `probekit_runtime`'s
//! `ProbeCloud` and `Volume`), so that replacing it touches this file only.
//! A cloud answers as an engine's `ProbeCloud` does, with every blend
//! setting the file stores (distance moments, cell visibility, fitted
//! weights, directional brightness); a volume interpolates trilinearly.

use glam::Vec3;
use probekit::query::Predictor;
use probekit_runtime::cloud::{Location, WalkState};
use probekit_runtime::{Interp, ProbeFile};

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
    /// A volume's interpolation (trilinear over its grid or octree).
    Volume,
}

/// One query's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Answer {
    /// Radiance SH at the point, `order²` RGB coefficients, as the runtime
    /// returns them (the blend of the probes below, per direction where the
    /// file's directional brightness applies).
    pub sh: Vec<Vec3>,
    /// Where the point was located.
    pub cell: Cell,
    /// The probes blended (indices into the file's probes; empty for volumes).
    pub probes: Vec<u32>,
    /// Their blend weights, summing to 1 (after the file's visibility and
    /// fitted weights), one per entry of `probes`.
    pub weights: Vec<f32>,
}

/// A cloud's tetrahedra (four probe indices each) and hull faces (three).
pub type CloudCells = (Vec<[u32; 4]>, Vec<[u32; 3]>);

/// A probe file ready for queries. Queries take `&self`: one value serves
/// every HTTP thread.
pub struct Probes {
    predictor: Predictor,
    order: usize,
}

impl Probes {
    /// Builds the query structure of a cloud or a volume (trilinear).
    pub fn from_file(file: &ProbeFile) -> Result<Self, QueryError> {
        let predictor =
            Predictor::from_file(file, Interp::Trilinear).map_err(|e| QueryError(e.to_string()))?;
        let order = predictor.order();
        Ok(Probes { predictor, order })
    }

    /// SH bands of the answers.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Radiance SH at `p` (metres), with the cell and weights.
    pub fn sh_at(&self, p: Vec3) -> Result<Answer, QueryError> {
        let mut sh = vec![Vec3::ZERO; self.order * self.order];
        let mut st = WalkState::new();
        self.predictor
            .sh_at(p, &mut st, &mut sh)
            .map_err(|e| QueryError(e.to_string()))?;
        let (cell, probes, weights) = match &self.predictor {
            Predictor::Cloud(c) => {
                let mut st = WalkState::new();
                let cell = match c.mesh().locate(p, &mut st) {
                    Location::Inside { tet, .. } => Cell::Tetrahedron(tet),
                    Location::Outside { hull_face, .. } => Cell::HullFace(hull_face),
                };
                let mut st = WalkState::new();
                let (probes, weights) = c.weights_at(p, &mut st);
                // A hull face blends three probes: the fourth slot is unused.
                let used = if matches!(cell, Cell::HullFace(_)) {
                    3
                } else {
                    4
                };
                (cell, probes[..used].to_vec(), weights[..used].to_vec())
            }
            Predictor::Volume(..) => (Cell::Volume, Vec::new(), Vec::new()),
        };
        Ok(Answer {
            sh,
            cell,
            probes,
            weights,
        })
    }

    /// Irradiance `E(n)` (not divided by π) at `p` for unit normal `n`, as
    /// the runtime computes it.
    pub fn irradiance(&self, p: Vec3, n: Vec3) -> Result<Vec3, QueryError> {
        let mut st = WalkState::new();
        self.predictor
            .irradiance(p, n, &mut st)
            .map_err(|e| QueryError(e.to_string()))
    }

    /// Irradiance at many points with their normals, sharing one walk
    /// (coherent batches walk little).
    pub fn irradiance_many(&self, points: &[(Vec3, Vec3)]) -> Result<Vec<Vec3>, QueryError> {
        let mut st = WalkState::new();
        points
            .iter()
            .map(|&(p, n)| {
                self.predictor
                    .irradiance(p, n, &mut st)
                    .map_err(|e| QueryError(e.to_string()))
            })
            .collect()
    }

    /// The cloud's tetrahedra and hull faces (probe indices), `None` for a
    /// volume.
    pub fn cells(&self) -> Option<CloudCells> {
        match &self.predictor {
            Predictor::Cloud(c) => {
                let mesh = c.mesh();
                let hull = (0..mesh.hull_face_count() as u32)
                    .filter_map(|f| mesh.hull_face_probes(f))
                    .collect();
                Some((mesh.tets().to_vec(), hull))
            }
            Predictor::Volume(..) => None,
        }
    }
}
