//! [`FormatError`]: every reason a `.probes` file is refused.

use super::layout::SectionId;
use crate::prelude::*;
#[cfg(feature = "std")]
use std::path::PathBuf;

/// Why a `.probes` file (or a [`ProbeFile`](super::ProbeFile) about to be
/// written) cannot be trusted. Readers return this instead of panicking;
/// each variant names what was wrong and where.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FormatError {
    /// The file could not be read (only with the `std` feature).
    #[cfg(feature = "std")]
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The first 8 bytes are not `PROBEKIT`.
    #[error("not a .probes file (bad magic bytes)")]
    BadMagic,
    /// A file of an older major version (every 1.x file): written by an
    /// older probekit, whose files this reader does not read. Bake the
    /// scene again to get a file of the current format.
    #[error(
        "format version {major}.{minor}: the file was written by an older probekit and must be baked again (this reader reads {supported}.x)"
    )]
    OlderVersion {
        /// The file's major version.
        major: u16,
        /// The file's minor version.
        minor: u16,
        /// The major version this reader reads.
        supported: u16,
    },
    /// A major version this reader does not know (newer, or 0).
    #[error("unsupported format version {major}.{minor} (this reader reads {supported}.x)")]
    UnsupportedVersion {
        /// The file's major version.
        major: u16,
        /// The file's minor version.
        minor: u16,
        /// The major version this reader reads.
        supported: u16,
    },
    /// The file ends before a structure it declares.
    #[error("truncated file: {needed} bytes needed, {len} present")]
    Truncated {
        /// Bytes the header or section table requires.
        needed: u64,
        /// Bytes present.
        len: u64,
    },
    /// The header's file length differs from the real length (trailing bytes).
    #[error("file length {actual} does not match the header's {declared}")]
    LengthMismatch {
        /// Length stored in the header.
        declared: u64,
        /// Actual length.
        actual: u64,
    },
    /// A checksum does not match the bytes it covers.
    #[error("checksum mismatch in {what}: stored {stored:#010x}, computed {computed:#010x}")]
    ChecksumMismatch {
        /// `"header"` or the section's name.
        what: String,
        /// CRC-32 stored in the file.
        stored: u32,
        /// CRC-32 of the bytes.
        computed: u32,
    },
    /// A section's byte range leaves the file or starts inside the header/table.
    #[error(
        "section {id} at offset {offset} with length {length} lies outside the file's data area"
    )]
    SectionOutOfBounds {
        /// The section.
        id: SectionId,
        /// Its offset.
        offset: u64,
        /// Its length.
        length: u64,
    },
    /// A section does not start on a 16-byte boundary.
    #[error("section {id} at offset {offset} is not 16-byte aligned")]
    SectionMisaligned {
        /// The section.
        id: SectionId,
        /// Its offset.
        offset: u64,
    },
    /// Two sections share bytes.
    #[error("sections {first} and {second} overlap")]
    SectionOverlap {
        /// The section starting first.
        first: SectionId,
        /// The section starting inside it.
        second: SectionId,
    },
    /// The same section id appears twice.
    #[error("section {0} appears more than once")]
    DuplicateSection(SectionId),
    /// A section id unknown to this reader in a file of this reader's minor
    /// version or older (unknown ids are skipped only in newer-minor files).
    #[error("unknown section {0}")]
    UnknownSection(SectionId),
    /// A section of the format in a file of a kind that does not hold it
    /// (a grid in a cloud, tetrahedra in a volume, probes in a rigs file).
    #[error("section {id} does not belong in a {kind} file")]
    MisplacedSection {
        /// The section.
        id: SectionId,
        /// The file's kind (`"cloud"`, `"volume"` or `"rig"`).
        kind: &'static str,
    },
    /// A section the file's kind needs is absent.
    #[error("required section {0} is missing")]
    MissingSection(SectionId),
    /// A section's length differs from what its counts imply.
    #[error("section {id} is {actual} bytes, its counts imply {expected}")]
    SectionSize {
        /// The section.
        id: SectionId,
        /// Bytes implied by the counts in its header.
        expected: u64,
        /// Bytes in the file.
        actual: u64,
    },
    /// Counts whose product overflows or exceeds anything the file could hold.
    #[error("section {0} declares counts too large for the file")]
    CountOverflow(SectionId),
    /// Two sections disagree about how many elements there are.
    #[error("section {id} has {actual} entries, expected {expected}")]
    CountMismatch {
        /// The section.
        id: SectionId,
        /// The count implied by another section (usually the probe count).
        expected: u64,
        /// The count found.
        actual: u64,
    },
    /// An index refers past the end of what it indexes.
    #[error("section {id}, element {element}: index {value} out of range (limit {limit})")]
    IndexOutOfRange {
        /// The section.
        id: SectionId,
        /// The element holding the index.
        element: u64,
        /// The index value.
        value: u64,
        /// The exclusive upper bound.
        limit: u64,
    },
    /// Structure that indices alone cannot express is broken (repeated vertex,
    /// non-reciprocal neighbours, a node with two parents...).
    #[error("section {id}, element {element}: {reason}")]
    InvalidTopology {
        /// The section.
        id: SectionId,
        /// The element.
        element: u64,
        /// What is wrong.
        reason: &'static str,
    },
    /// A NaN or infinite float where a finite value is required.
    #[error("section {id}, element {element}: NaN or infinite value")]
    NonFinite {
        /// The section.
        id: SectionId,
        /// The element.
        element: u64,
    },
    /// A field holds a value outside its documented domain.
    #[error("section {id}, element {element}: {reason}")]
    InvalidValue {
        /// The section (or [`SectionId::HEADER`]).
        id: SectionId,
        /// The element.
        element: u64,
        /// What is wrong.
        reason: &'static str,
    },
    /// A coefficient codec id this reader does not know.
    #[error("unknown coefficient codec {0}")]
    UnknownCodec(u32),
    /// A codec paired with an SH order it cannot hold, or a stride that does
    /// not match the codec.
    #[error("codec {codec} cannot store SH of order {order} with stride {stride}")]
    CodecOrderMismatch {
        /// Codec name.
        codec: &'static str,
        /// Declared order.
        order: u32,
        /// Declared bytes per probe.
        stride: u32,
    },
    /// The codec is known but this build cannot decode it.
    #[error("codec {0} is not available in this build")]
    CodecUnavailable(&'static str),
    /// A file kind id this reader does not know.
    #[error("unknown file kind {0}")]
    UnknownKind(u32),
    /// Text that is not UTF-8.
    #[error("section {0} holds text that is not UTF-8")]
    InvalidUtf8(SectionId),
    /// A light group name that the file does not hold (relighting).
    #[error("no light group named {0:?} in the file")]
    UnknownGroup(String),
    /// A value the writer cannot represent (e.g. more than `u32::MAX`
    /// elements, or a float outside the codec's range).
    #[error("cannot encode: {0}")]
    Unrepresentable(&'static str),
}
