//! CAN fault confinement (ISO 11898-1, 12.1.4): each station's transmit and
//! receive error counters (TEC, REC) and the error state they put it in.
//! The fault-injecting bus ([`crate::faults::FaultInjector`]) applies them
//! to the errors it injects, and the drives report them in HeartbeatExt.

/// A station is error-passive from this count on (TEC or REC).
pub const ERROR_PASSIVE: u16 = 128;
/// A station whose TEC exceeds this is bus-off.
pub const BUS_OFF_ABOVE: u16 = 255;
/// A bus-off station rejoins, counters cleared, after 128 occurrences of 11
/// recessive bits: 1408 bit times, at the nominal 1 Mbit/s (ns).
pub const RECOVERY_NS: u64 = 128 * 11 * 1000;

/// The error state a station's counters put it in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorState {
    Active,
    Passive,
    BusOff,
}

/// One station's error counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ErrorCounters {
    pub tec: u16,
    pub rec: u16,
}

impl ErrorCounters {
    /// The station saw an error while transmitting: +8.
    pub fn tx_error(&mut self) {
        self.tec = self.tec.saturating_add(8);
    }
    /// A frame transmitted without error: −1.
    pub fn tx_ok(&mut self) {
        self.tec = self.tec.saturating_sub(1);
    }
    /// The station detected an error while receiving: +1 (REC stops at 255:
    /// a receiver never goes bus-off on receive errors alone).
    pub fn rx_error(&mut self) {
        self.rec = (self.rec + 1).min(255);
    }
    /// A frame received without error: −1, or back to 127 (in 119..=127 per
    /// the standard) from an error-passive count.
    pub fn rx_ok(&mut self) {
        self.rec = if self.rec >= ERROR_PASSIVE {
            ERROR_PASSIVE - 1
        } else {
            self.rec.saturating_sub(1)
        };
    }
    pub fn state(&self) -> ErrorState {
        if self.tec > BUS_OFF_ABOVE {
            ErrorState::BusOff
        } else if self.tec >= ERROR_PASSIVE || self.rec >= ERROR_PASSIVE {
            ErrorState::Passive
        } else {
            ErrorState::Active
        }
    }
    /// (TEC, REC) as a controller's 8-bit registers report them (HeartbeatExt).
    pub fn registers(&self) -> (u8, u8) {
        (self.tec.min(255) as u8, self.rec.min(255) as u8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_states_follow_iso_11898_1() {
        let mut c = ErrorCounters::default();
        c.tx_error();
        c.rx_error();
        assert_eq!(c.registers(), (8, 1));
        c.tx_ok();
        c.rx_ok();
        assert_eq!(c.registers(), (7, 0));
        c.rx_ok();
        assert_eq!(c.rec, 0, "no underflow");
        for _ in 0..15 {
            c.tx_error();
        }
        assert_eq!(c.tec, 127);
        assert_eq!(c.state(), ErrorState::Active);
        c.tx_error();
        assert_eq!(c.state(), ErrorState::Passive);
        for _ in 0..16 {
            c.tx_error();
        }
        assert_eq!(c.tec, 263);
        assert_eq!(c.state(), ErrorState::BusOff);
        assert_eq!(c.registers().0, 255);
        let mut r = ErrorCounters::default();
        for _ in 0..300 {
            r.rx_error();
        }
        assert_eq!((r.rec, r.state()), (255, ErrorState::Passive));
        r.rx_ok();
        assert_eq!((r.rec, r.state()), (127, ErrorState::Active));
    }
}
