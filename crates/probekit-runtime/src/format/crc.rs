//! CRC-32 (IEEE 802.3, reflected polynomial `0xEDB88320`, initial value and
//! final XOR `0xFFFFFFFF`) — the checksum of every `.probes` section.
//!
//! The same CRC as zlib, PNG and gzip (`crc32("123456789") = 0xCBF43926`),
//! so an engine can check sections with any library it already has.
//! Table-driven, one byte per step: fast enough for load-time checking
//! (hundreds of MB/s) without a dependency.

/// The reflected IEEE polynomial.
const POLY: u32 = 0xEDB8_8320;

/// 256-entry table: `TABLE[b]` is the CRC register after shifting byte `b`
/// through eight polynomial-division steps. Built at compile time.
const TABLE: [u32; 256] = build_table();

const fn build_table() -> [u32; 256] {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 { (c >> 1) ^ POLY } else { c >> 1 };
            k += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
}

/// An incremental CRC-32 (IEEE): feed bytes with [`Crc32::update`], read the
/// checksum with [`Crc32::finish`]. Feeding `a` then `b` equals feeding `a ++ b`.
#[derive(Clone, Copy, Debug)]
pub struct Crc32 {
    state: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A fresh checksum (register `0xFFFFFFFF`).
    pub const fn new() -> Self {
        Self { state: 0xFFFF_FFFF }
    }

    /// Feeds `bytes`.
    pub fn update(&mut self, bytes: &[u8]) {
        let mut c = self.state;
        for &b in bytes {
            c = TABLE[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8);
        }
        self.state = c;
    }

    /// The CRC-32 of everything fed so far.
    pub const fn finish(&self) -> u32 {
        self.state ^ 0xFFFF_FFFF
    }
}

/// CRC-32 (IEEE) of `bytes` in one call.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(bytes);
    c.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit-at-a-time long division by the polynomial: the definition, with
    /// no table, as an independent reference.
    fn crc32_bitwise(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= b as u32;
            for _ in 0..8 {
                let mask = (c & 1).wrapping_neg();
                c = (c >> 1) ^ (POLY & mask);
            }
        }
        !c
    }

    #[test]
    fn published_check_values() {
        // The standard check value of CRC-32/ISO-HDLC (the catalogue of
        // parametrised CRC algorithms, Greg Cook).
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        // zlib.crc32(b"The quick brown fox jumps over the lazy dog")
        assert_eq!(
            crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
    }

    #[test]
    fn table_matches_bitwise_definition_and_is_incremental() {
        let mut state = 0x1234_5678u32;
        let bytes: Vec<u8> = (0..4099)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
            .collect();
        for len in [0, 1, 7, 64, 1000, 4099] {
            assert_eq!(crc32(&bytes[..len]), crc32_bitwise(&bytes[..len]));
        }
        let mut inc = Crc32::new();
        inc.update(&bytes[..1234]);
        inc.update(&bytes[1234..]);
        assert_eq!(inc.finish(), crc32(&bytes));
    }
}
