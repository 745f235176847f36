//! The KTX2 container, written by hand after the *KTX File Format
//! Specification, version 2.0* (Khronos, <https://registry.khronos.org/KTX/specs/2.0/ktxspec.v2.html>):
//! 12-byte identifier, 9 header words (vkFormat, typeSize, width, height,
//! depth, layerCount = 0, faceCount = 1, levelCount = 1,
//! supercompressionScheme = 0), the index (DFD and KVD offsets/lengths, no
//! SGD), one level-index entry, the Data Format Descriptor (one basic block,
//! *Khronos Data Format Specification 1.3* §5: colour model RGBSDA, BT.709
//! primaries, linear transfer), key/value data (`KTXwriter`), then the level
//! data aligned to `lcm(texel size, 4)`. Texels are stored x fastest, then y,
//! then z.

use super::ExportError;

/// A texel format this module writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// `VK_FORMAT_R16G16B16A16_SFLOAT` (97).
    Rgba16Float,
    /// `VK_FORMAT_R8G8B8A8_SNORM` (38).
    Rgba8Snorm,
    /// `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32` (123).
    Rgb9e5,
    /// `VK_FORMAT_R8G8B8A8_UINT` (41): the brick atlas's indirection texture.
    Rgba8Uint,
}

impl TexelFormat {
    /// The Vulkan format number.
    pub const fn vk_format(self) -> u32 {
        match self {
            Self::Rgba16Float => 97,
            Self::Rgba8Snorm => 38,
            Self::Rgb9e5 => 123,
            Self::Rgba8Uint => 41,
        }
    }

    /// Bytes per texel.
    pub const fn texel_bytes(self) -> usize {
        match self {
            Self::Rgba16Float => 8,
            Self::Rgba8Snorm | Self::Rgb9e5 | Self::Rgba8Uint => 4,
        }
    }

    /// KTX2 `typeSize`.
    const fn type_size(self) -> u32 {
        match self {
            Self::Rgba16Float => 2,
            Self::Rgba8Snorm | Self::Rgba8Uint => 1,
            Self::Rgb9e5 => 4,
        }
    }

    fn from_vk(v: u32) -> Option<Self> {
        [
            Self::Rgba16Float,
            Self::Rgba8Snorm,
            Self::Rgb9e5,
            Self::Rgba8Uint,
        ]
        .into_iter()
        .find(|f| f.vk_format() == v)
    }

    /// DFD samples: (bitOffset, bitLength − 1, channelType, lower, upper).
    fn samples(self) -> Vec<(u16, u8, u8, u32, u32)> {
        match self {
            Self::Rgba16Float => [0u8, 1, 2, 15]
                .iter()
                .enumerate()
                .map(|(i, &ch)| (16 * i as u16, 15, ch | 0xC0, 0xBF80_0000, 0x3F80_0000))
                .collect(),
            Self::Rgba8Snorm => [0u8, 1, 2, 15]
                .iter()
                .enumerate()
                .map(|(i, &ch)| (8 * i as u16, 7, ch | 0x40, 0xFFFF_FF81, 0x7F))
                .collect(),
            Self::Rgba8Uint => [0u8, 1, 2, 15]
                .iter()
                .enumerate()
                .map(|(i, &ch)| (8 * i as u16, 7, ch, 0, 255))
                .collect(),
            Self::Rgb9e5 => (0..3u8)
                .flat_map(|c| [(9 * c as u16, 8, c, 0, 8448), (27, 4, c | 0x20, 15, 31)])
                .collect(),
        }
    }
}

/// One decoded KTX2 3D texture (single level, no layers, no faces).
#[derive(Clone, Debug, PartialEq)]
pub struct Ktx2 {
    /// Texel format.
    pub format: TexelFormat,
    /// Width, height, depth in texels.
    pub size: [u32; 3],
    /// Key/value pairs.
    pub kvd: Vec<(String, String)>,
    /// Texel bytes, x fastest, then y, then z.
    pub data: Vec<u8>,
}

const IDENTIFIER: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

fn align(n: usize, a: usize) -> usize {
    n.div_ceil(a) * a
}

impl Ktx2 {
    /// Serializes the texture as a KTX2 file (module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let samples = self.format.samples();
        let block_size = 24 + 16 * samples.len();
        let mut dfd = Vec::new();
        dfd.extend_from_slice(&((4 + block_size) as u32).to_le_bytes());
        dfd.extend_from_slice(&0u32.to_le_bytes()); // vendor 0, type 0
        dfd.extend_from_slice(&2u16.to_le_bytes()); // version 1.3
        dfd.extend_from_slice(&(block_size as u16).to_le_bytes());
        dfd.extend_from_slice(&[1, 1, 1, 0]); // RGBSDA, BT709, linear, straight alpha
        dfd.extend_from_slice(&[0, 0, 0, 0]); // 1×1×1×1 block
        let mut planes = [0u8; 8];
        planes[0] = self.format.texel_bytes() as u8;
        dfd.extend_from_slice(&planes);
        for (off, len, ch, lo, hi) in samples {
            dfd.extend_from_slice(&off.to_le_bytes());
            dfd.extend_from_slice(&[len, ch, 0, 0, 0, 0]);
            dfd.extend_from_slice(&lo.to_le_bytes());
            dfd.extend_from_slice(&hi.to_le_bytes());
        }
        let mut kvd = Vec::new();
        for (k, v) in &self.kvd {
            let len = k.len() + 1 + v.len() + 1;
            kvd.extend_from_slice(&(len as u32).to_le_bytes());
            kvd.extend_from_slice(k.as_bytes());
            kvd.push(0);
            kvd.extend_from_slice(v.as_bytes());
            kvd.push(0);
            kvd.resize(align(kvd.len(), 4), 0);
        }
        let dfd_off = 12 + 36 + 32 + 24;
        let kvd_off = dfd_off + dfd.len();
        let data_off = align(kvd_off + kvd.len(), 8);
        let mut out = Vec::with_capacity(data_off + self.data.len());
        out.extend_from_slice(&IDENTIFIER);
        for w in [
            self.format.vk_format(),
            self.format.type_size(),
            self.size[0],
            self.size[1],
            self.size[2],
            0,
            1,
            1,
            0,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        for w in [
            dfd_off as u32,
            dfd.len() as u32,
            kvd_off as u32,
            kvd.len() as u32,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(&0u64.to_le_bytes());
        out.extend_from_slice(&0u64.to_le_bytes());
        for w in [
            data_off as u64,
            self.data.len() as u64,
            self.data.len() as u64,
        ] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.extend_from_slice(&dfd);
        out.extend_from_slice(&kvd);
        out.resize(data_off, 0);
        out.extend_from_slice(&self.data);
        out
    }

    /// Parses a file written by [`Self::to_bytes`] (single-level 3D
    /// textures of the three formats); checks identifier, sizes, offsets and
    /// the DFD's format description.
    pub fn from_bytes(b: &[u8]) -> Result<Self, ExportError> {
        let bad = ExportError::BadKtx2;
        if b.len() < 104 || b[..12] != IDENTIFIER {
            return Err(bad("identifier or header"));
        }
        let u32_at = |o: usize| -> Result<u32, ExportError> {
            b.get(o..o + 4)
                .map(|s| u32::from_le_bytes(s.try_into().expect("4 bytes")))
                .ok_or(bad("truncated"))
        };
        let u64_at = |o: usize| -> Result<u64, ExportError> {
            b.get(o..o + 8)
                .map(|s| u64::from_le_bytes(s.try_into().expect("8 bytes")))
                .ok_or(bad("truncated"))
        };
        let format = TexelFormat::from_vk(u32_at(12)?).ok_or(bad("unsupported vkFormat"))?;
        if u32_at(16)? != format.type_size() {
            return Err(bad("typeSize"));
        }
        let size = [u32_at(20)?, u32_at(24)?, u32_at(28)?];
        if u32_at(32)? != 0 || u32_at(36)? != 1 || u32_at(40)? != 1 || u32_at(44)? != 0 {
            return Err(bad("layers, faces, levels or supercompression"));
        }
        let (dfd_off, dfd_len) = (u32_at(48)? as usize, u32_at(52)? as usize);
        let (kvd_off, kvd_len) = (u32_at(56)? as usize, u32_at(60)? as usize);
        let (lo, ll) = (u64_at(80)? as usize, u64_at(88)? as usize);
        let texels = size
            .iter()
            .try_fold(1usize, |a, &s| a.checked_mul(s as usize));
        if texels.and_then(|t| t.checked_mul(format.texel_bytes())) != Some(ll) {
            return Err(bad("level length"));
        }
        let dfd = b
            .get(dfd_off..dfd_off + dfd_len)
            .ok_or(bad("DFD out of range"))?;
        let samples = format.samples();
        if dfd.len() != 28 + 16 * samples.len() || dfd[12] != 1 || dfd[14] != 1 {
            return Err(bad("DFD"));
        }
        for (k, (off, len, ch, _, _)) in samples.iter().enumerate() {
            let s = &dfd[28 + 16 * k..];
            if u16::from_le_bytes([s[0], s[1]]) != *off || s[2] != *len || s[3] != *ch {
                return Err(bad("DFD sample"));
            }
        }
        let mut kvd = Vec::new();
        let mut p = kvd_off;
        let end = kvd_off + kvd_len;
        while p + 4 <= end {
            let len = u32_at(p)? as usize;
            let s = b.get(p + 4..p + 4 + len).ok_or(bad("KVD out of range"))?;
            let mut parts = s.split(|&c| c == 0);
            let k = parts.next().ok_or(bad("KVD key"))?;
            let v = parts.next().ok_or(bad("KVD value"))?;
            kvd.push((
                String::from_utf8_lossy(k).into_owned(),
                String::from_utf8_lossy(v).into_owned(),
            ));
            p = align(p + 4 + len, 4);
        }
        let data = b
            .get(lo..lo + ll)
            .ok_or(bad("level data out of range"))?
            .to_vec();
        Ok(Self {
            format,
            size,
            kvd,
            data,
        })
    }
}
