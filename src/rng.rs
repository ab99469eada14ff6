//! The crate's small deterministic random generator (splitmix64): random packings and start
//! velocities that must be the same on every machine and thread count for a given seed.

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
    use super::SplitMix64;

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
