//! The crate's small deterministic random generators: random packings, start velocities and test
//! geometries that must be the same on every machine and thread count for a given seed.
//! `SplitMix64` draws the deck insertions and packings; `Lcg64` the fixed scenes of the
//! self-checks, the bench and the tests; `mix_seed` gives each insertion round its own stream.

/// The seed of insertion round `round` of a fix seeded with `seed`: round 0 keeps `seed` (the
/// streams of a single insertion), later rounds add multiples of the golden-ratio constant of
/// splitmix64 so that each round draws a new stream.
pub fn mix_seed(seed: u64, round: u64) -> u64 {
    seed.wrapping_add(round.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// 64-bit linear congruential generator with Knuth's MMIX constants (Knuth, TAOCP vol. 2,
/// 3.3.4): the state advances before each draw. Cheap and fixed, for reproducible test scenes;
/// its low bits are weak, so draws use the high ones.
#[derive(Debug, Clone)]
pub struct Lcg64(pub u64);

impl Lcg64 {
    /// The next state (all 64 bits).
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0
    }

    /// Uniform in [0, 1), the 53 high bits of the next state.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [-1, 1): `2 uniform() - 1`.
    pub fn symmetric(&mut self) -> f64 {
        self.uniform() * 2.0 - 1.0
    }
}

/// splitmix64 (Steele, Lea & Flood 2014): 64 bits of state, one multiply-xorshift chain per draw.
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// Uniform in [0, 1), 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller; one of the pair is used, so each draw takes two uniforms).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // in (0, 1]: the logarithm stays finite
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::{mix_seed, Lcg64, SplitMix64};

    #[test]
    fn lcg_first_draws_and_seed_mixing() {
        // Values worked out independently (Python integers mod 2^64).
        let mut r = Lcg64(0);
        assert_eq!(r.next_u64(), 1442695040888963407);
        assert_eq!(r.next_u64(), 1876011003808476466);
        let mut r = Lcg64(0);
        assert_eq!(r.uniform(), (1442695040888963407u64 >> 11) as f64 / (1u64 << 53) as f64);
        assert_eq!(mix_seed(42, 0), 42);
        assert_eq!(mix_seed(42, 2), 4354685564936845396);
    }

    #[test]
    fn uniform_and_normal_moments() {
        let mut r = SplitMix64(7);
        let n = 200_000;
        let u: Vec<f64> = (0..n).map(|_| r.uniform()).collect();
        let mean = u.iter().sum::<f64>() / n as f64;
        // Standard error of the mean of U(0,1): sqrt(1/12/n) = 6.5e-4; 5 of them.
        assert!((mean - 0.5).abs() < 3.3e-3, "{mean}");
        assert!(u.iter().all(|&x| (0.0..1.0).contains(&x)));
        let g: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let m = g.iter().sum::<f64>() / n as f64;
        let v = g.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n as f64;
        // Standard errors: 2.2e-3 for the mean, 3.2e-3 for the variance; 5 of them.
        assert!(m.abs() < 1.1e-2 && (v - 1.0).abs() < 1.6e-2, "mean {m}, variance {v}");
    }
}
