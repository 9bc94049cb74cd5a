//! The number types the avoidance step runs in, behind one trait.
//!
//! Fixed-point types saturate instead of overflowing (the `fixed` crate's `saturating_*`), divisions
//! by zero saturate, and nothing here panics. `f32`/`f64` use `libm` so the code stays `no_std`.

pub use fixed::types::{I16F16, I20F12, I8F24};

/// The number type the board's avoidance step runs in. `f32` on the Cortex-M4F (it has an FPU): in
/// QEMU's instruction count the `f32` step with the lookup-table Gaussian is the cheapest variant
/// and on the host its path is the closest to the `f64` reference (docs/avoidance.md, "Speed
/// against accuracy"). The cargo feature `avoid-fixed` selects `I16F16` for parts without an FPU
/// (every avoidance type is generic over [`Real`], so nothing else changes). Defined here, beside
/// the types, so that `link.rs` need not import the module root (no import circle).
#[cfg(not(feature = "avoid-fixed"))]
pub type BoardReal = f32;
/// The number type the board's avoidance step runs in: `I16F16` (feature `avoid-fixed`, for parts
/// without an FPU).
#[cfg(feature = "avoid-fixed")]
pub type BoardReal = I16F16;

/// A real number as the avoidance step needs it: saturating arithmetic, no panics.
pub trait Real: Copy + PartialOrd {
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// Division in hardware (the floats on an FPU): the speed and separation monitor then bounds
    /// the speed towards each sector (a division per sector); the fixed-point types (a 64-bit
    /// software division each) bound the whole speed by the nearest sector instead (one division
    /// a step, more conservative: `safe.rs`).
    const HW_DIV: bool;
    /// Nearest representable value (saturating; NaN maps to zero).
    fn from_f32(v: f32) -> Self;
    /// Nearest representable value of an `f64` (saturating; NaN maps to zero).
    fn from_f64(v: f64) -> Self;
    /// The value as `f64` (exact for all the fixed formats).
    fn to_f64(self) -> f64;
    /// From the wire format: Q16.16 raw bits.
    fn from_q16(raw: i32) -> Self;
    /// From a small integer.
    fn from_int(v: i32) -> Self;
    /// `self + o`, saturating.
    fn add(self, o: Self) -> Self;
    /// `self - o`, saturating.
    fn sub(self, o: Self) -> Self;
    /// `self * o`, saturating.
    fn mul(self, o: Self) -> Self;
    /// `self / o`; saturates on overflow and on division by zero (sign of `self`).
    fn div(self, o: Self) -> Self;
    /// `-self`, saturating.
    fn neg(self) -> Self;
    /// `self / 2` (an arithmetic shift in fixed point, rounding towards minus infinity; no
    /// multiplication or division).
    fn halve(self) -> Self;
    /// `|self|`, saturating.
    fn abs(self) -> Self;
    /// Square root; zero for negative input.
    fn sqrt(self) -> Self;
    /// Largest integer not above `self`, clamped to `i32`.
    fn floor_int(self) -> i32;
    /// `self x 10^6` rounded to the nearest integer and saturated to `i32` (NaN: 0): metres to
    /// micrometres for the velocity frame, without `f64` arithmetic on the target.
    fn to_micro(self) -> i32;
    /// `(sum w_k g_k, sum w_k h_k)` over the shortest of the three slices (the field's inner loop).
    #[inline]
    fn dot2(ws: &[Self], gs: &[Self], hs: &[Self]) -> (Self, Self) {
        let (mut a, mut b) = (Self::ZERO, Self::ZERO);
        for ((w, g), h) in ws.iter().zip(gs).zip(hs) {
            a = a.add(w.mul(*g));
            b = b.add(w.mul(*h));
        }
        (a, b)
    }
}

/// Integer square root of a `u64`, bit by bit (64 iterations at most).
const fn isqrt_u64(n: u64) -> u64 {
    let mut rem = n;
    let mut root: u64 = 0;
    if n == 0 {
        return 0;
    }
    // Highest power of four not above n.
    let mut bit: u64 = 1 << (63u32.saturating_sub(n.leading_zeros()) & !1);
    while bit != 0 {
        // root + bit <= 2 sqrt(n) + bit < 2^33: cannot wrap.
        let trial = root.wrapping_add(bit);
        if rem >= trial {
            rem = rem.wrapping_sub(trial);
            root = (root >> 1).wrapping_add(bit);
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    root
}

macro_rules! impl_fixed {
    ($t:ty) => {
        impl Real for $t {
            const ZERO: Self = <$t>::ZERO;
            const ONE: Self = <$t>::from_bits(1 << <$t>::FRAC_NBITS);
            const HW_DIV: bool = false;
            #[inline]
            fn from_f32(v: f32) -> Self {
                if v.is_nan() {
                    Self::ZERO
                } else {
                    <$t>::saturating_from_num(v)
                }
            }
            #[inline]
            fn from_f64(v: f64) -> Self {
                if v.is_nan() {
                    Self::ZERO
                } else {
                    <$t>::saturating_from_num(v)
                }
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self.to_num::<f64>()
            }
            #[inline]
            fn from_q16(raw: i32) -> Self {
                <$t>::saturating_from_num(I16F16::from_bits(raw))
            }
            #[inline]
            fn from_int(v: i32) -> Self {
                <$t>::saturating_from_num(v)
            }
            #[inline]
            fn add(self, o: Self) -> Self {
                self.saturating_add(o)
            }
            #[inline]
            fn sub(self, o: Self) -> Self {
                self.saturating_sub(o)
            }
            #[inline]
            fn mul(self, o: Self) -> Self {
                self.saturating_mul(o)
            }
            #[inline]
            fn div(self, o: Self) -> Self {
                match self.checked_div(o) {
                    Some(q) => q,
                    None => {
                        if (self < Self::ZERO) != (o < Self::ZERO) {
                            <$t>::MIN
                        } else {
                            <$t>::MAX
                        }
                    }
                }
            }
            #[inline]
            fn neg(self) -> Self {
                self.saturating_neg()
            }
            #[inline]
            fn halve(self) -> Self {
                <$t>::from_bits(self.to_bits() >> 1)
            }
            #[inline]
            fn abs(self) -> Self {
                self.saturating_abs()
            }
            #[inline]
            fn sqrt(self) -> Self {
                let bits = self.to_bits();
                if bits <= 0 {
                    return Self::ZERO;
                }
                // sqrt(b / 2^f) = sqrt(b * 2^f) / 2^f; b * 2^f < 2^63 for f <= 31.
                let wide = (bits as u64) << <$t>::FRAC_NBITS;
                let r = isqrt_u64(wide);
                <$t>::from_bits(if r > i32::MAX as u64 { i32::MAX } else { r as i32 })
            }
            #[inline]
            fn to_micro(self) -> i32 {
                // |bits| < 2^31, times 10^6 < 2^51: no overflow in i64; round half up.
                let wide = (self.to_bits() as i64).wrapping_mul(1_000_000);
                let r = wide.wrapping_add(1 << (<$t>::FRAC_NBITS - 1)) >> <$t>::FRAC_NBITS;
                r.clamp(i32::MIN as i64, i32::MAX as i64) as i32
            }
            #[inline]
            fn floor_int(self) -> i32 {
                // Arithmetic shift right is floor for two's complement.
                self.to_bits() >> <$t>::FRAC_NBITS
            }
            /// Accumulates the raw products in `i64` (one `smlal` each on the M4) and rounds once.
            /// No overflow: `|w| < 2^31`, `|g|, |h| <= 8` so each product is below `2^(34 + FRAC)`
            /// `<= 2^58`, and at most `MAX_WINDOW = 10` are summed (`< 2^62`); the result saturates.
            #[inline]
            fn dot2(ws: &[Self], gs: &[Self], hs: &[Self]) -> (Self, Self) {
                let (mut a, mut b) = (0i64, 0i64);
                for ((w, g), h) in ws.iter().zip(gs).zip(hs) {
                    let w = w.to_bits() as i64;
                    a = a.wrapping_add(w.wrapping_mul(g.to_bits() as i64));
                    b = b.wrapping_add(w.wrapping_mul(h.to_bits() as i64));
                }
                let narrow = |v: i64| {
                    let v = v >> <$t>::FRAC_NBITS;
                    <$t>::from_bits(v.clamp(i32::MIN as i64, i32::MAX as i64) as i32)
                };
                (narrow(a), narrow(b))
            }
        }
    };
}

impl_fixed!(I16F16);
impl_fixed!(I8F24);
impl_fixed!(I20F12);

macro_rules! impl_float {
    ($t:ty, $sqrt:path, $floor:path, $round:path) => {
        impl Real for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const HW_DIV: bool = true;
            #[inline]
            fn from_f32(v: f32) -> Self {
                if v.is_nan() {
                    0.0
                } else {
                    v as $t
                }
            }
            #[inline]
            fn from_f64(v: f64) -> Self {
                if v.is_nan() {
                    0.0
                } else {
                    v as $t
                }
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn from_q16(raw: i32) -> Self {
                (raw as $t) * (1.0 / 65536.0)
            }
            #[inline]
            fn from_int(v: i32) -> Self {
                v as $t
            }
            #[inline]
            fn add(self, o: Self) -> Self {
                self + o
            }
            #[inline]
            fn sub(self, o: Self) -> Self {
                self - o
            }
            #[inline]
            fn mul(self, o: Self) -> Self {
                self * o
            }
            #[inline]
            fn div(self, o: Self) -> Self {
                if o == 0.0 {
                    if self < 0.0 {
                        <$t>::MIN
                    } else {
                        <$t>::MAX
                    }
                } else {
                    self / o
                }
            }
            #[inline]
            fn neg(self) -> Self {
                -self
            }
            #[inline]
            fn halve(self) -> Self {
                self * 0.5
            }
            #[inline]
            fn abs(self) -> Self {
                if self < 0.0 {
                    -self
                } else {
                    self
                }
            }
            #[inline]
            fn sqrt(self) -> Self {
                if self > 0.0 {
                    $sqrt(self)
                } else {
                    0.0
                }
            }
            #[inline]
            fn to_micro(self) -> i32 {
                // Half away from zero by adding a half before `as` (which truncates, saturates and
                // maps NaN to 0: no panic). Not `roundf`: a software call of about 20 instructions,
                // six a velocity frame, in QEMU's count of the board's step. Within a micrometre of
                // `roundf` (a value just below a half may round up in the addition).
                let t = self * 1e6;
                (if t >= 0.0 { t + 0.5 } else { t - 0.5 }) as i32
            }
            #[inline]
            fn floor_int(self) -> i32 {
                // `as` saturates and maps NaN to 0: no panic.
                $floor(self) as i32
            }
        }
    };
}

impl_float!(f32, libm::sqrtf, libm::floorf, libm::roundf);
impl_float!(f64, libm::sqrt, libm::floor, libm::round);

#[cfg(test)]
mod tests {
    use super::*;

    fn check<R: Real>(tol: f64) {
        for &v in &[0.0f64, 0.25, 1.0, 2.0, 10.0, 100.5] {
            let r = R::from_f64(v).sqrt().to_f64();
            assert!((r - libm::sqrt(v)).abs() <= tol, "sqrt({v}) = {r}");
        }
        assert_eq!(R::from_f64(-2.5).floor_int(), -3);
        assert_eq!(R::from_f64(2.5).floor_int(), 2);
        assert!(R::from_f64(1.0).div(R::ZERO).to_f64() > 1.0);
        assert!((R::from_q16(3 << 15).to_f64() - 1.5).abs() < 1e-6);
        assert_eq!(R::from_f64(0.25).to_micro(), 250_000);
        assert_eq!(R::from_f64(-0.5).to_micro(), -500_000);
    }

    #[test]
    fn real_ops_agree_with_f64() {
        check::<I16F16>(1e-4);
        check::<I20F12>(2e-3);
        check::<f32>(1e-5);
        check::<f64>(1e-12);
        // I8F24 saturates at 128: test within its range.
        let r = I8F24::from_f64(2.0).sqrt().to_f64();
        assert!((r - core::f64::consts::SQRT_2).abs() < 1e-6);
        assert!(I8F24::from_f64(500.0).to_f64() > 127.9);
    }
}
