//! Lanes for the multi-contact kernel: a formula written once over [`Lane`] runs on one `f64` (the
//! portable path) or on four at a time in an AVX2 register ([`F64x4`]).
//!
//! Why explicit lanes: a particle's contact pairs come in short rows (1–15 pairs), which the
//! compiler's loop vectoriser leaves mostly to its scalar remainder. Evaluating a row in whole
//! registers over zero-padded inputs keeps every pair in vector code. Each operation is one IEEE
//! operation per lane (no fused multiply-add), so both instances give the same bits.

use std::ops::{Add, Div, Mul, Sub};

/// One value per lane with the operations Eq. 2's bracket needs.
pub trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Lanes per value.
    const WIDTH: usize;
    type Mask: Copy;
    fn splat(v: f64) -> Self;
    /// The first [`Lane::WIDTH`] values of `s`.
    fn load(s: &[f64]) -> Self;
    /// Into the first [`Lane::WIDTH`] values of `s`.
    fn store(self, s: &mut [f64]);
    /// Lane l into `s[l · stride]` (a column of a row-major matrix).
    fn store_column(self, s: &mut [f64], stride: usize);
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// −x (the sign flipped, as Rust's unary minus).
    fn neg(self) -> Self;
    fn gt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    /// `a` where `m` holds, else `b`.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

impl Lane for f64 {
    const WIDTH: usize = 1;
    type Mask = bool;
    #[inline(always)]
    fn splat(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn load(s: &[f64]) -> Self {
        s[0]
    }
    #[inline(always)]
    fn store(self, s: &mut [f64]) {
        s[0] = self;
    }
    #[inline(always)]
    fn store_column(self, s: &mut [f64], _stride: usize) {
        s[0] = self;
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        -self
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m {
            a
        } else {
            b
        }
    }
}

// Crate-internal: AVX2 code runs only behind the run-time check, so no safe code outside the core
// may get hold of a value.
#[cfg(target_arch = "x86_64")]
pub(crate) use avx::F64x4;

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::Lane;
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Sub};

    /// Four f64 lanes in an AVX register. Only for code compiled with AVX2 enabled and reached
    /// after [`crate::physics::avx2`] said yes: every method is inlined into such a function.
    #[derive(Clone, Copy)]
    pub(crate) struct F64x4(__m256d);

    // SAFETY (every block below): the methods are `#[inline(always)]` and only called from
    // functions compiled with `#[target_feature(enable = "avx2")]` behind a run-time check.
    macro_rules! binary {
        ($tr:ident, $f:ident, $intr:ident) => {
            impl $tr for F64x4 {
                type Output = F64x4;
                #[inline(always)]
                fn $f(self, o: F64x4) -> F64x4 {
                    F64x4(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_pd);
    binary!(Sub, sub, _mm256_sub_pd);
    binary!(Mul, mul, _mm256_mul_pd);
    binary!(Div, div, _mm256_div_pd);

    impl Lane for F64x4 {
        const WIDTH: usize = 4;
        type Mask = F64x4;
        #[inline(always)]
        fn splat(v: f64) -> Self {
            F64x4(unsafe { _mm256_set1_pd(v) })
        }
        #[inline(always)]
        fn load(s: &[f64]) -> Self {
            let s = &s[..4];
            F64x4(unsafe { _mm256_loadu_pd(s.as_ptr()) })
        }
        #[inline(always)]
        fn store(self, s: &mut [f64]) {
            let s = &mut s[..4];
            unsafe { _mm256_storeu_pd(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn store_column(self, s: &mut [f64], stride: usize) {
            let s = &mut s[..3 * stride + 1];
            let (lo, hi) = unsafe { (_mm256_castpd256_pd128(self.0), _mm256_extractf128_pd::<1>(self.0)) };
            let p = s.as_mut_ptr();
            // In bounds: the slice holds index 3·stride (checked just above).
            unsafe {
                _mm_storel_pd(p, lo);
                _mm_storeh_pd(p.add(stride), lo);
                _mm_storel_pd(p.add(2 * stride), hi);
                _mm_storeh_pd(p.add(3 * stride), hi);
            }
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            F64x4(unsafe { _mm256_sqrt_pd(self.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            F64x4(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn neg(self) -> Self {
            F64x4(unsafe { _mm256_xor_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Self {
            F64x4(unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> Self {
            F64x4(unsafe { _mm256_cmp_pd::<_CMP_LE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        fn select(m: Self, a: Self, b: Self) -> Self {
            F64x4(unsafe { _mm256_blendv_pd(b.0, a.0, m.0) })
        }
    }
}
