//! The parts of a [`ProbeFile`] the baker built itself and so knows the
//! kind of: a cloud's [`CloudFile`], a volume's [`VolumeFile`], either's
//! [`ProbeSet`]. Files read from outside are matched on their kind
//! instead ([`ProbeFile::as_cloud`], ...).

use super::{CloudFile, Octree, ProbeFile, ProbeSet, VolumeFile, VolumeGrid, VolumeStructure};

/// Access to the parts of a file whose kind the caller established.
pub(crate) trait Parts {
    /// The cloud; the file is one.
    fn cloud(&self) -> &CloudFile;
    /// [`Parts::cloud`], mutable.
    fn cloud_mut(&mut self) -> &mut CloudFile;
    /// The volume; the file is one.
    #[cfg_attr(not(test), allow(dead_code))]
    fn volume(&self) -> &VolumeFile;
    /// The probes; the file is a cloud or a volume.
    fn probe_set(&self) -> &ProbeSet;
    /// [`Parts::probe_set`], mutable.
    fn probe_set_mut(&mut self) -> &mut ProbeSet;
    /// The octree of an adaptive volume, `None` for anything else.
    fn octree(&self) -> Option<&Octree>;
    /// The grid of a uniform volume, `None` for anything else.
    fn grid(&self) -> Option<&VolumeGrid>;
}

impl Parts for ProbeFile {
    fn cloud(&self) -> &CloudFile {
        self.as_cloud().expect("the baker's file is a cloud here")
    }
    fn cloud_mut(&mut self) -> &mut CloudFile {
        self.as_cloud_mut()
            .expect("the baker's file is a cloud here")
    }
    fn volume(&self) -> &VolumeFile {
        self.as_volume().expect("the baker's file is a volume here")
    }
    fn probe_set(&self) -> &ProbeSet {
        self.probes().expect("the baker's file has probes here")
    }
    fn probe_set_mut(&mut self) -> &mut ProbeSet {
        self.probes_mut().expect("the baker's file has probes here")
    }
    fn octree(&self) -> Option<&Octree> {
        self.as_volume().and_then(VolumeFile::octree)
    }
    fn grid(&self) -> Option<&VolumeGrid> {
        match &self.as_volume()?.structure {
            VolumeStructure::Uniform(g) => Some(g),
            VolumeStructure::Adaptive(_) => None,
        }
    }
}
