//! The parts of a test's [`ProbeFile`] whose kind the test knows: its
//! cloud, volume, probes, octree or grid.

use probekit_runtime::format::*;

/// The cloud of a file known to be one.
pub fn c(f: &ProbeFile) -> &CloudFile {
    f.as_cloud().expect("a cloud")
}

/// [`c`], mutable.
pub fn cm(f: &mut ProbeFile) -> &mut CloudFile {
    f.as_cloud_mut().expect("a cloud")
}

/// The volume of a file known to be one.
pub fn v(f: &ProbeFile) -> &VolumeFile {
    f.as_volume().expect("a volume")
}

/// [`v`], mutable.
pub fn vm(f: &mut ProbeFile) -> &mut VolumeFile {
    f.as_volume_mut().expect("a volume")
}

/// The probes of a cloud or volume.
pub fn p(f: &ProbeFile) -> &ProbeSet {
    f.probes().expect("probes")
}

/// [`p`], mutable.
pub fn pm(f: &mut ProbeFile) -> &mut ProbeSet {
    f.probes_mut().expect("probes")
}

/// The octree of an adaptive volume (`None` for anything else).
pub fn octree(f: &ProbeFile) -> Option<&Octree> {
    f.as_volume().and_then(|v| v.octree())
}

/// [`octree`], mutable.
pub fn octree_mut(f: &mut ProbeFile) -> Option<&mut Octree> {
    match &mut f.as_volume_mut()?.structure {
        VolumeStructure::Adaptive(o) => Some(o),
        VolumeStructure::Uniform(_) => None,
    }
}

/// The grid of a uniform volume (`None` for anything else).
pub fn grid(f: &ProbeFile) -> Option<&VolumeGrid> {
    f.as_volume().and_then(|v| v.grid())
}

/// [`grid`], mutable.
pub fn grid_mut(f: &mut ProbeFile) -> Option<&mut VolumeGrid> {
    match &mut f.as_volume_mut()?.structure {
        VolumeStructure::Uniform(g) => Some(g),
        VolumeStructure::Adaptive(_) => None,
    }
}
