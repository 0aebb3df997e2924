//! Random streams. vvgen's own streams are keyed by identity (seed, rig, split, view, …) through blake3, so a
//! draw never depends on how many draws came before it: adding a view appends poses and moves no other.
//! [`Mt19937`] reproduces numpy's legacy `np.random.seed(s); uniform(0, 1)` stream for compatibility with camera
//! sets published by Blender scripts.

/// A stream of uniform numbers derived from a key.
pub struct Keyed {
    reader: blake3::OutputReader,
    /// Read ahead: blake3 computes whole 64-byte blocks (several at once with SIMD), so 8-byte reads straight
    /// from the reader would recompute each block eight times. The stream's bytes are the same either way.
    buf: [u8; BUF],
    pos: usize,
}

/// Bytes read ahead from the XOF at a time.
const BUF: usize = 512;

impl Keyed {
    /// A stream for `domain` (what is being drawn) and the identity `parts`.
    pub fn new(domain: &str, parts: &[&[u8]]) -> Keyed {
        let mut h = blake3::Hasher::new_derive_key(&format!("vvgen 1 random {domain}"));
        for p in parts {
            // Length-prefixed so ("ab", "c") and ("a", "bc") differ.
            h.update(&(p.len() as u64).to_le_bytes());
            h.update(p);
        }
        Keyed { reader: h.finalize_xof(), buf: [0; BUF], pos: BUF }
    }

    /// The next `N` bytes of the stream (a partial tail of the read-ahead is skipped, deterministically).
    #[inline]
    fn take<const N: usize>(&mut self) -> [u8; N] {
        if self.pos + N > BUF {
            self.reader.fill(&mut self.buf);
            self.pos = 0;
        }
        let b: [u8; N] = self.buf[self.pos..self.pos + N].try_into().expect("BUG: a slice of N bytes");
        self.pos += N;
        b
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }

    /// Uniform in [0, 1) with 24 bits, from 32 bits of the stream: for bulk draws (surface samples) where an
    /// f32 result is all that is kept, at half the stream cost of [`Keyed::uniform`].
    #[inline]
    pub fn uniform_f32(&mut self) -> f32 {
        (u32::from_le_bytes(self.take()) >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [0, 1) with 53 bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in `0..n` (`n > 0`), without modulo bias worth noticing (n ≪ 2^64).
    pub fn below(&mut self, n: u64) -> u64 {
        ((self.next_u64() as u128 * n as u128) >> 64) as u64
    }

    /// A uniform point in the unit ball.
    pub fn in_ball(&mut self) -> [f64; 3] {
        loop {
            let p = [2.0 * self.uniform() - 1.0, 2.0 * self.uniform() - 1.0, 2.0 * self.uniform() - 1.0];
            if p.iter().map(|v| v * v).sum::<f64>() <= 1.0 {
                return p;
            }
        }
    }
}

/// A seed derived from a parent seed and a name (e.g. a split's default seed from the dataset seed).
pub fn derive_seed(parent: u64, name: &str) -> u64 {
    Keyed::new("seed", &[&parent.to_le_bytes(), name.as_bytes()]).next_u64()
}

/// The Mersenne Twister MT19937 as numpy's legacy `RandomState` seeds and uses it.
pub struct Mt19937 {
    mt: [u32; 624],
    index: usize,
}

impl Mt19937 {
    /// `np.random.seed(seed)` for an integer seed (numpy's `init_genrand`).
    pub fn new(seed: u32) -> Mt19937 {
        let mut mt = [0u32; 624];
        mt[0] = seed;
        for i in 1..624 {
            mt[i] = 1_812_433_253u32.wrapping_mul(mt[i - 1] ^ (mt[i - 1] >> 30)).wrapping_add(i as u32);
        }
        Mt19937 { mt, index: 624 }
    }

    fn twist(&mut self) {
        for i in 0..624 {
            let y = (self.mt[i] & 0x8000_0000) | (self.mt[(i + 1) % 624] & 0x7fff_ffff);
            let mut v = self.mt[(i + 397) % 624] ^ (y >> 1);
            if y & 1 != 0 {
                v ^= 0x9908_b0df;
            }
            self.mt[i] = v;
        }
        self.index = 0;
    }

    /// Next 32-bit output (tempered).
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= 624 {
            self.twist();
        }
        let mut y = self.mt[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    /// numpy's `random_sample()`: 53-bit double from two outputs, `uniform(0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        let a = (self.next_u32() >> 5) as f64;
        let b = (self.next_u32() >> 6) as f64;
        (a * 67_108_864.0 + b) / 9_007_199_254_740_992.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mt19937_matches_the_reference_stream() {
        // First outputs of init_genrand(5489), the reference implementation's default seed.
        let mut mt = Mt19937::new(5489);
        assert_eq!(mt.next_u32(), 3_499_211_612);
        assert_eq!(mt.next_u32(), 581_869_302);
        // numpy: np.random.seed(0); np.random.uniform(0, 1, 2) → [0.5488135039273248, 0.7151893663724195]
        let mut np = Mt19937::new(0);
        assert_eq!(np.uniform(), 0.5488135039273248);
        assert_eq!(np.uniform(), 0.7151893663724195);
    }

    #[test]
    fn keyed_streams_depend_on_every_part() {
        let a = Keyed::new("t", &[b"ab", b"c"]).next_u64();
        assert_ne!(a, Keyed::new("t", &[b"a", b"bc"]).next_u64());
        assert_ne!(a, Keyed::new("u", &[b"ab", b"c"]).next_u64());
        assert_eq!(a, Keyed::new("t", &[b"ab", b"c"]).next_u64());
        let mut k = Keyed::new("t", &[]);
        for _ in 0..1000 {
            let u = k.uniform();
            assert!((0.0..1.0).contains(&u));
            assert!(k.below(7) < 7);
        }
    }
}
