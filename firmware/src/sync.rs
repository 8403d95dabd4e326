//! Host time from TimeSync frames: offset and rate from pairs (host transmit
//! time of sync k, local receive time of sync k), all integer arithmetic.

/// A command dated further back than this (µs) applies on receipt instead.
pub const APPLY_LATE_MAX_US: i64 = 100_000;

/// Time-sync estimator of one node.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SyncEstimator {
    /// Last sync received: (seq, local receive time µs).
    pending: Option<(u8, u64)>,
    /// Latest sample (host µs, local µs).
    a: Option<(i64, u64)>,
    /// Rate correction: host advances (1 + ppb·1e-9) µs per local µs.
    ppb: i64,
    /// The same as a fraction of 2^32 (ppb·2^32/1e9, rounded): the tick
    /// corrects by a multiplication, not a 64-bit division, which is a
    /// long soft routine on the target.
    rate_q32: i32,
    samples: u32,
    /// Local receive time (µs) of the sync that produced the latest accepted sample.
    good_us: Option<u64>,
    /// Local receive time (µs) of the last sync received (paired or not).
    rx_us: Option<u64>,
    /// Samples discarded as outliers since the last accepted one.
    pub outliers: u32,
}

/// `ppb` as a fraction of 2^32, rounded half away from zero (the
/// estimator takes |ppb| ≤ 10⁶; up to 2·10⁶ fits with room).
fn rate_q32(ppb: i64) -> i32 {
    let q = ((ppb << 32) + ppb.signum() * 500_000_000) / 1_000_000_000;
    q as i32
}

/// A sample whose host time differs from the prediction by more than this (µs)
/// is a late or corrupted sync, not a clock: it is discarded. Clocks within
/// ±1000 ppm drift at most 100 µs per 100 ms sync period.
pub const OUTLIER_US: i64 = 500;
/// Consecutive outliers after which an idle node takes a new host time base.
pub const REBASE_AFTER: u32 = triquint_shared::protocol::SYNC_REBASE_AFTER;

impl SyncEstimator {
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// A TimeSync (`seq`, host transmit time of `seq − 1`) received at local
    /// time `local_us`. `may_rebase`: no motion depends on the time base, so
    /// [`REBASE_AFTER`] outliers in a row mean a new host time base (a new
    /// host session), not late frames, and the estimator starts afresh.
    pub fn on_sync(&mut self, seq: u8, prev_tx_us: u32, local_us: u64, may_rebase: bool) {
        self.rx_us = Some(local_us);
        if let Some((pseq, plocal)) = self.pending
            && pseq.wrapping_add(1) == seq
        {
            // Unwrap the 32-bit host time against our estimate.
            let host = match self.host_us(plocal) {
                Some(est) => {
                    let d = prev_tx_us.wrapping_sub(est as u32) as i32 as i64;
                    est + d
                }
                None => prev_tx_us as i64,
            };
            // Once synced, a sample far from the prediction is a late receive
            // timestamp or a corrupted frame: keep the old time base.
            let mut host = host;
            if self.samples >= 2
                && let Some(est) = self.host_us(plocal)
                && (host - est).abs() > OUTLIER_US
            {
                self.outliers = self.outliers.saturating_add(1);
                if !(may_rebase && self.outliers >= REBASE_AFTER) {
                    self.pending = Some((seq, local_us));
                    return;
                }
                let rx = self.rx_us;
                *self = Self::default();
                self.rx_us = rx;
                host = prev_tx_us as i64;
            }
            if let Some((ha, la)) = self.a {
                let dl = plocal as i64 - la as i64;
                if dl > 1000 {
                    let dh = host - ha;
                    let ppb = (dh - dl).saturating_mul(1_000_000_000) / dl;
                    // Reject absurd rates (> ±1000 ppm): a glitch, not a clock.
                    if ppb.abs() <= 1_000_000 {
                        self.ppb = if self.samples >= 2 {
                            (3 * self.ppb + ppb) / 4
                        } else {
                            ppb
                        };
                        self.rate_q32 = rate_q32(self.ppb);
                    }
                }
            }
            self.a = Some((host, plocal));
            self.samples = self.samples.saturating_add(1);
            self.good_us = Some(local_us);
            self.outliers = 0;
        }
        self.pending = Some((seq, local_us));
    }

    /// Host time (µs) at local time `local_us`, once one sample exists.
    pub fn host_us(&self, local_us: u64) -> Option<i64> {
        // host_ns = (ha + dl)·1000 + c: floor(host_ns / 1000) is
        // ha + dl + floor(c / 1000), exactly, with the rate correction c
        // divided in i32 (one instruction) when it fits, as it does within
        // minutes of a sample; a 64-bit division is a long soft routine on the
        // target.
        let (ha, la) = self.a?;
        let dl = local_us as i64 - la as i64;
        let c = self.correction_ns(dl.saturating_mul(1000));
        let c_us = match i32::try_from(c) {
            Ok(c) => i64::from(c.div_euclid(1000)),
            Err(_) => c.div_euclid(1000),
        };
        Some(ha + dl + c_us)
    }

    /// The rate correction (ns) over `dl_ns` of local time:
    /// floor(dl_ns · rate_q32 / 2^32), exactly, from the high and low words
    /// of `dl_ns` (neither product can overflow).
    fn correction_ns(&self, dl_ns: i64) -> i64 {
        let m = self.rate_q32 as i64;
        let hi = (dl_ns >> 32) * m;
        let lo = ((dl_ns as u32) as i64 * m) >> 32;
        hi + lo
    }

    /// Host time (ns) a hold, resume, stop or override with argument `arg`
    /// (host time in µs, wrapping; 0 = on receipt) received at local time
    /// `local_us` applies at: `arg` if it is up to [`APPLY_LATE_MAX_US`] old
    /// (every node then computes the same time-scaling, closed form from
    /// that instant), else then; 0 without a time base.
    pub fn apply_ns(&self, arg: u32, local_us: u64) -> i64 {
        let Some(now) = self.host_us(local_us) else {
            return 0;
        };
        let d = arg.wrapping_sub(now as u32) as i32 as i64;
        let t = if arg != 0 && (-APPLY_LATE_MAX_US..=0).contains(&d) {
            now + d
        } else {
            now
        };
        t * 1000
    }

    /// Host time (ns) at local time `local_us`.
    pub fn host_ns(&self, local_us: u64) -> Option<i64> {
        let (ha, la) = self.a?;
        let dl = local_us as i64 - la as i64;
        let dl_ns = dl.saturating_mul(1000);
        Some(ha * 1000 + dl_ns + self.correction_ns(dl_ns))
    }

    /// Synchronised: offset and rate known, a sync received no more than
    /// `timeout_us` ago (one lost sync is ridden out on the rate estimate),
    /// and an accepted sample no more than 4 × `timeout_us` ago (a stream of
    /// outliers is not a time base).
    pub fn is_synced(&self, local_us: u64, timeout_us: u64) -> bool {
        match (self.good_us, self.rx_us) {
            (Some(g), Some(r)) => {
                self.samples >= 2
                    && local_us.saturating_sub(r) <= timeout_us
                    && local_us.saturating_sub(g) <= 4 * timeout_us
            }
            _ => false,
        }
    }

    /// The host time (ns) at which the sync was lost, if it was by
    /// `local_us`: the last sync's (or good sample's) host time plus the
    /// timeout in host time, the same instant to the microsecond on every
    /// node that received the same syncs, whichever tick notices it and
    /// whatever rate each estimated.
    pub fn lost_at_ns(&self, local_us: u64, timeout_us: u64) -> Option<i64> {
        let (g, r) = (self.good_us?, self.rx_us?);
        let (after_r, after_g) = (
            timeout_us.saturating_add(1),
            timeout_us.saturating_mul(4).saturating_add(1),
        );
        let (from, after) = if r.saturating_add(after_r) <= g.saturating_add(after_g) {
            (r, after_r)
        } else {
            (g, after_g)
        };
        if self.samples < 2 || from.saturating_add(after) > local_us {
            return None;
        }
        Some(self.host_ns(from)? + after as i64 * 1000)
    }

    /// Has had a sync once but lost it.
    pub fn lost(&self, local_us: u64, timeout_us: u64) -> bool {
        self.samples >= 2 && !self.is_synced(local_us, timeout_us)
    }

    pub fn rate_ppb(&self) -> i64 {
        self.ppb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracks_offset_and_drift() {
        // Local clock: offset 12345678 µs, runs 150 ppm fast.
        let local = |host_us: f64| 12_345_678.0 + host_us * (1.0 + 150e-6);
        let mut s = SyncEstimator::default();
        for k in 0..20u32 {
            let host_tx = 1_000_000.0 + k as f64 * 100_000.0;
            let prev = if k == 0 {
                0
            } else {
                (host_tx - 100_000.0) as u32
            };
            s.on_sync(k as u8, prev, local(host_tx) as u64, false);
        }
        assert!(s.is_synced(local(2_950_000.0) as u64, 500_000));
        let est = s.host_us(local(2_950_000.0) as u64).unwrap();
        assert!((est - 2_950_000).abs() <= 2, "{est}");
        assert!((s.rate_ppb() + 150_000).abs() < 20_000, "{}", s.rate_ppb());
        assert!(s.lost(local(4_000_000.0) as u64, 500_000));
    }

    /// host_us is floor(host_ns / 1000) exactly, whatever the sample, rate
    /// and instant (before and after the sample, rates of either sign).
    #[test]
    fn host_us_is_host_ns_in_whole_microseconds() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..50_000 {
            let la: u64 = rng.random_range(0..1u64 << 40);
            let ppb = rng.random_range(-2_000_000..2_000_000);
            let s = SyncEstimator {
                a: Some((rng.random_range(-(1i64 << 40)..1i64 << 40), la)),
                ppb,
                rate_q32: rate_q32(ppb),
                ..SyncEstimator::default()
            };
            let local = la.saturating_add_signed(rng.random_range(-(1i64 << 36)..1i64 << 36));
            let ns = s.host_ns(local).unwrap();
            assert_eq!(s.host_us(local), Some(ns.div_euclid(1000)), "{s:?} {local}");
        }
    }

    /// The correction is the exact rate's within a nanosecond (the floor)
    /// and 1.2e-10 of the span (the rate rounded to 2^-32), over a second
    /// and over hours.
    #[test]
    fn the_rate_correction_is_the_exact_rates() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for _ in 0..50_000 {
            let ppb: i64 = rng.random_range(-2_000_000..=2_000_000);
            let s = SyncEstimator {
                ppb,
                rate_q32: rate_q32(ppb),
                ..SyncEstimator::default()
            };
            let short: i64 = rng.random_range(-1_000_000_000..1_000_000_000);
            let exact = |dl: i64| (dl as i128 * ppb as i128) as f64 / 1e9;
            let long: i64 = rng.random_range(-(1i64 << 46)..1i64 << 46);
            for dl in [short, long] {
                let d = (s.correction_ns(dl) as f64 - exact(dl)).abs();
                assert!(
                    d <= 1.0 + 1.2e-10 * dl.abs() as f64,
                    "{ppb} ppb over {dl} ns: {d} ns off"
                );
            }
        }
    }

    /// Five syncs 100 ms apart with host time = local time − 7 µs.
    fn synced(may_rebase: bool) -> SyncEstimator {
        let mut s = SyncEstimator::default();
        for k in 0..5u64 {
            s.on_sync(
                k as u8,
                (k * 100_000).saturating_sub(100_000) as u32,
                7 + k * 100_000,
                may_rebase,
            );
        }
        s
    }

    #[test]
    fn late_sync_is_discarded_and_silence_times_out_from_the_last_good_sync() {
        let s = &mut synced(false);
        let before = s.host_us(450_007).unwrap();
        // Sync 5 is received 30 ms late; sync 6 pairs host time 500 000 with it.
        s.on_sync(5, 400_000, 530_007, false);
        s.on_sync(6, 500_000, 600_007, false);
        assert_eq!(s.outliers, 1);
        assert!((s.host_us(450_007).unwrap() - before).abs() <= 1);
        // The timeout runs from the last sync received.
        assert!(s.is_synced(600_007 + 250_000, 250_000));
        assert!(!s.is_synced(600_007 + 250_001, 250_000));
        // Outliers only: no longer synced 4 timeouts after the last good sample
        // (sync 5 at 530 007 paired sync 4's times and was good).
        for k in 7..20u64 {
            s.on_sync(
                k as u8,
                (k * 100_000 - 100_000 + 30_000) as u32,
                7 + k * 100_000,
                false,
            );
        }
        assert!(s.outliers > 5);
        assert!(!s.is_synced(1_900_007, 250_000));
    }

    /// A new host session restarts host time: an idle node follows it after
    /// REBASE_AFTER syncs; a node with motion pending never does.
    #[test]
    fn idle_node_follows_a_new_host_time_base() {
        for idle in [true, false] {
            let mut s = synced(idle);
            // The new session's host clock starts at 9 000 000 µs.
            for k in 5..12u64 {
                let host = 9_000_000 + (k - 5) * 100_000;
                s.on_sync(
                    k as u8,
                    host.saturating_sub(100_000) as u32,
                    7 + k * 100_000,
                    idle,
                );
            }
            let t = 7 + 11 * 100_000;
            let est = s.host_us(t).unwrap();
            if idle {
                assert!((est - 9_600_000).abs() <= 1, "{est}");
                assert!(s.is_synced(t, 250_000));
            } else {
                assert!((est - 1_100_000).abs() <= 1, "{est}");
                assert!(s.outliers >= 6);
            }
        }
    }

    #[test]
    fn unwraps_32_bit_host_time() {
        let mut s = SyncEstimator::default();
        let base: u64 = (1u64 << 32) - 250_000;
        for k in 0..6u64 {
            let host = base + k * 100_000;
            let prev = (host - 100_000) as u32;
            s.on_sync(k as u8, prev, 5_000 + k * 100_000, false);
        }
        let est = s.host_us(5_000 + 550_000).unwrap();
        assert_eq!(est, (base + 550_000) as i64);
    }
}
