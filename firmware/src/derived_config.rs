//! What a drive derives once from a configuration: periods, filter
//! constants and its axis, in f32 and integers only. Built by the receive
//! side when it prepares a commit, copied by the tick.

use triquint_shared::protocol::DriveConfig;

use crate::f32_cast::{ramp_us, to_i64};

/// What is derived once from a configuration (by the receive side, when it
/// prepares a commit). Small on purpose: the tick copies it; the
/// configuration and model stay in the drive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DerivedConfig {
    /// CRC-32 of the configuration.
    pub crc: u32,
    /// This node's axis (0–2).
    pub axis: usize,
    /// Control period (s).
    pub dt: f32,
    /// Metres per encoder count.
    pub inv_cpm: f32,
    /// First-order filter constant of the velocity and error derivative.
    pub vel_alpha: f32,
    /// Stop ramp (ns).
    pub stop_ns: i64,
    /// Quick-stop ramp (ns).
    pub quick_stop_ns: i64,
    /// Underrun margin beyond the stop distance (ns).
    pub margin_ns: i64,
    /// Time sync (and peer heartbeat) timeout (µs).
    pub sync_timeout_us: u64,
    /// Telemetry period (µs; 0: none).
    pub telemetry_us: u64,
    /// Heartbeat period (µs).
    pub heartbeat_us: u64,
}

impl DerivedConfig {
    /// Periods and filter constants of configuration `cfg` (with CRC `crc`),
    /// in f32 and integers only.
    pub fn new(cfg: &DriveConfig, crc: u32) -> Self {
        let dt = 1.0 / cfg.control_rate;
        let wc = 2.0 * core::f32::consts::PI * cfg.velocity_filter * dt;
        // Whole microseconds (validated > 0; saturating far beyond any use).
        let us = |s: f32| to_i64(s * 1e6).max(0) as u64;
        let ns = |s: f32| (ramp_us(s) as i64).saturating_mul(1000);
        Self {
            crc,
            axis: (cfg.axis as usize).min(2),
            dt,
            inv_cpm: 1.0 / cfg.counts_per_metre,
            vel_alpha: wc / (1.0 + wc),
            stop_ns: ns(cfg.stop_time),
            quick_stop_ns: ns(cfg.quick_stop_time),
            margin_ns: ns(cfg.underrun_margin),
            sync_timeout_us: us(cfg.sync_timeout),
            telemetry_us: if cfg.telemetry_rate > 0.0 {
                us(1.0 / cfg.telemetry_rate)
            } else {
                0
            },
            heartbeat_us: us(cfg.heartbeat_period),
        }
    }
}
