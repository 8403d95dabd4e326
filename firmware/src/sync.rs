//! Host time from TimeSync frames: offset and rate from pairs (host transmit
//! time of sync k, local receive time of sync k), all integer arithmetic.

/// Time-sync estimator of one node.
#[derive(Clone, Copy, Debug, Default)]
pub struct SyncEstimator {
    /// Last sync received: (seq, local receive time µs).
    pending: Option<(u8, u64)>,
    /// Latest sample (host µs, local µs).
    a: Option<(i64, u64)>,
    /// Rate correction: host advances (1 + ppb·1e-9) µs per local µs.
    ppb: i64,
    samples: u32,
}

impl SyncEstimator {
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// A TimeSync (`seq`, host transmit time of `seq − 1`) received at local time `local_us`.
    pub fn on_sync(&mut self, seq: u8, prev_tx_us: u32, local_us: u64) {
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
                    }
                }
            }
            self.a = Some((host, plocal));
            self.samples = self.samples.saturating_add(1);
        }
        self.pending = Some((seq, local_us));
    }

    /// Host time (µs) at local time `local_us`, once one sample exists.
    pub fn host_us(&self, local_us: u64) -> Option<i64> {
        self.host_ns(local_us).map(|ns| ns.div_euclid(1000))
    }

    /// Host time (ns) at local time `local_us`.
    pub fn host_ns(&self, local_us: u64) -> Option<i64> {
        let (ha, la) = self.a?;
        let dl = local_us as i64 - la as i64;
        let dl_ns = dl.saturating_mul(1000);
        Some(ha * 1000 + dl_ns + dl_ns.saturating_mul(self.ppb) / 1_000_000_000)
    }

    /// Synchronised: offset and rate known, last sample younger than `timeout_us`.
    pub fn is_synced(&self, local_us: u64, timeout_us: u64) -> bool {
        match self.a {
            Some((_, la)) => self.samples >= 2 && local_us.saturating_sub(la) <= timeout_us,
            None => false,
        }
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
            s.on_sync(k as u8, prev, local(host_tx) as u64);
        }
        assert!(s.is_synced(local(2_950_000.0) as u64, 500_000));
        let est = s.host_us(local(2_950_000.0) as u64).unwrap();
        assert!((est - 2_950_000).abs() <= 2, "{est}");
        assert!((s.rate_ppb() + 150_000).abs() < 20_000, "{}", s.rate_ppb());
        assert!(s.lost(local(4_000_000.0) as u64, 500_000));
    }

    #[test]
    fn unwraps_32_bit_host_time() {
        let mut s = SyncEstimator::default();
        let base: u64 = (1u64 << 32) - 250_000;
        for k in 0..6u64 {
            let host = base + k * 100_000;
            let prev = (host - 100_000) as u32;
            s.on_sync(k as u8, prev, 5_000 + k * 100_000);
        }
        let est = s.host_us(5_000 + 550_000).unwrap();
        assert_eq!(est, (base + 550_000) as i64);
    }
}
