//! Integer ↔ f32 conversion for the control tick. Cortex-M4F converts i32 in
//! one instruction but i64 only through a soft-float routine; tick values (ns within a segment or ramp, encoder counts)
//! almost always fit in i32. Same rounding either way, so results are
//! identical bit for bit.

/// `x as f32`, through i32 when it fits.
#[inline(always)]
pub fn to_f32(x: i64) -> f32 {
    if x == x as i32 as i64 {
        x as i32 as f32
    } else {
        to_f32_wide(x)
    }
}

/// `x as f32` for |x| ≥ 2³¹ (ns beyond 2.1 s: long segments and ramps),
/// out of line (the tick's own code stays small). Below 2³⁶ (68 s) through
/// i32: x shifted right by 5 with the dropped bits ORed into its lowest bit
/// (a sticky bit: 27 to 31 significant bits, at least 3 below f32's
/// rounding position, so round-to-nearest-even sees the same tie or no
/// tie), converted and scaled by 2⁵ exactly, a fraction of the soft-float
/// routine's cost.
#[inline(never)]
fn to_f32_wide(x: i64) -> f32 {
    let m = x.unsigned_abs();
    if m >= 1 << 36 {
        return x as f32;
    }
    let v = ((m >> 5) | u64::from(m & 0x1f != 0)) as i32 as f32 * 32.0;
    if x < 0 { -v } else { v }
}

/// `x as i64` (truncating, saturating), through i32 when in range.
#[inline(always)]
pub fn to_i64(x: f32) -> i64 {
    if x.abs() < 2.0e9 {
        x as i32 as i64
    } else {
        x as i64
    }
}

/// A ramp of `s` seconds in whole µs, as the drive runs it (the host's
/// and the drive's own ramps rounded alike; saturating).
pub fn ramp_us(s: f32) -> u32 {
    to_i64(s * 1e6).clamp(0, u32::MAX as i64) as u32
}

/// [`ramp_us`] in the 100 µs units a stop's ramp travels in, rounded up;
/// `u16::MAX` (6.5535 s or more, an infinite ramp among them) stands for
/// no ramp at all, which no stop is run with.
pub fn ramp_units(s: f32) -> u16 {
    ramp_us(s).div_ceil(100).min(u16::MAX as u32) as u16
}

#[cfg(test)]
mod tests {
    use super::{to_f32, to_i64};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn same_integer_as_the_plain_conversion() {
        for bits in (0..u32::MAX).step_by(9_973) {
            let x = f32::from_bits(bits);
            assert_eq!(to_i64(x), x as i64, "{x:e}");
        }
    }

    #[test]
    fn same_bits_as_the_plain_conversion() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for k in 0..20_000i64 {
            let x: i64 = rng.random();
            for v in [
                x,
                x >> (k % 63),
                -(x >> (k % 63)),
                i32::MAX as i64 + k,
                i32::MIN as i64 - k,
                (1i64 << 31) + (x >> (24 + k % 40)).abs(),
                -(1i64 << 36) + (x >> (k % 63)).abs() % (1i64 << 36),
                (1i64 << 36) - 1 - k,
                (1i64 << 36) + k,
            ] {
                assert_eq!(to_f32(v).to_bits(), (v as f32).to_bits(), "{v}");
            }
        }
    }
}
