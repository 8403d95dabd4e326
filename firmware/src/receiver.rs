//! The CAN receive side of a node, run in the CAN task (below the control
//! tick): decodes every frame, reassembles segments, checks their CRC, limits
//! and soft limits, keeps the written configuration and checks a committed
//! one (the tick builds its robot model). What is left for the tick is a finished
//! [`Item`] (the hand-off types are in the `inbox` module).

use triquint_shared::protocol::{
    Command, CommandCode, DriveConfig, Emergency, FaultCode, Msg, PARAM_COUNT, Reject,
    SegmentEvent, SegmentRx, WireSegment, config::config_crc, decode,
};

use triquint_shared::protocol::contract::{
    EMERGENCY_DATE_MAX_US, LIMIT_CHECK_INTERVALS, MAX_DURATION_US, MIN_DURATION_US,
    RELATIVE_LIMIT_MARGIN,
};

use crate::ceiling_lock::first_widening;
use crate::ceilings::Maxima;
use crate::hal::RxFrame;
use crate::inbox::{CheckedSegment, CommandData, Item, LockCheck, Prepared, TickSnapshot};
use crate::scaling::{Retarget, q16_from_permille};
use crate::segment::Seg;
use crate::sync::SyncEstimator;

/// Receive side of one node.
#[derive(Clone)]
pub struct Receiver {
    node_id: u8,
    /// Segment reassembly, and the predecessor a compact segment continues.
    segments: SegmentRx,
    written: [f32; PARAM_COUNT],
    written_mask: u64,
    flushes: u32,
    sync: SyncEstimator,
    /// The last two configurations prepared, newest first: the node may
    /// refuse a commit (not Idle) and keep running the earlier one.
    configs: [Option<(u32, DriveConfig)>; 2],
    /// The frame being handled is the board's replay of its kept
    /// configuration ([`Receiver::on_kept_frame`]).
    kept: bool,
}

/// Velocity, acceleration and jerk of every axis within the configured
/// limits (with [`RELATIVE_LIMIT_MARGIN`]) by the segment's exact maxima
/// `m`, else `Invalid`; every position finite and this axis's within its
/// soft limits at [`LIMIT_CHECK_INTERVALS`] + 1 points of the segment,
/// else `Invalid` or `OutsideSoftLimits`.
fn within_limits(seg: &Seg, m: &Maxima, cfg: &DriveConfig) -> Result<(), Reject> {
    let k = 1.0 + RELATIVE_LIMIT_MARGIN;
    if !(m.v <= cfg.max_velocity * k && m.a <= cfg.max_acceleration * k && m.j <= cfg.max_jerk * k)
    {
        return Err(Reject::Invalid);
    }
    let axis = (cfg.axis as usize).min(2);
    // A power of two: every sample's u is exact.
    let du = 1.0 / LIMIT_CHECK_INTERVALS as f32;
    for i in 0..=LIMIT_CHECK_INTERVALS {
        let q = seg.positions(i as f32 * du);
        if !q.iter().all(|x| x.is_finite()) {
            return Err(Reject::Invalid);
        }
        if !(cfg.soft_limit_min..=cfg.soft_limit_max).contains(&q[axis]) {
            return Err(Reject::OutsideSoftLimits);
        }
    }
    Ok(())
}

impl Receiver {
    pub fn new(node_id: u8) -> Self {
        Self {
            node_id,
            segments: SegmentRx::default(),
            written: [0.0; PARAM_COUNT],
            written_mask: 0,
            flushes: 0,
            sync: SyncEstimator::default(),
            configs: [None; 2],
            kept: false,
        }
    }

    pub fn node_id(&self) -> u8 {
        self.node_id
    }

    /// [`Receiver::on_frame`] for a frame a board replays from its own
    /// store (the configuration it kept): its commit is not a host's, so
    /// the ceiling lock does not hold it.
    // Always inlined: every caller of `on_frame` on a board is then the
    // receive task itself, which the ELF check holds to the hand-off.
    #[inline(always)]
    pub fn on_kept_frame(&mut self, rx: &RxFrame, snapshot: TickSnapshot) -> Option<Item> {
        self.kept = true;
        let item = self.on_frame(rx, snapshot);
        self.kept = false;
        item
    }

    /// Handles one received frame; returns what the tick must take, if anything.
    pub fn on_frame(&mut self, rx: &RxFrame, snapshot: TickSnapshot) -> Option<Item> {
        let kept = self.kept;
        if snapshot.flushes != self.flushes {
            self.flushes = snapshot.flushes;
            self.segments.clear();
        }
        let Ok((msg, node)) = decode(&rx.frame) else {
            return None;
        };
        let for_me = node == 0 || node == self.node_id;
        let rx_us = rx.timestamp_us;
        match msg {
            Msg::TimeSync(s) => {
                self.sync
                    .on_sync(s.seq, s.prev_tx_us, rx_us, snapshot.may_rebase);
                Some(Item::Sync(self.sync))
            }
            Msg::Emergency(e) if node != self.node_id => {
                let t = self.emergency_ns(&e, node, rx_us, &snapshot);
                Some(Item::Emergency {
                    code: if node == 0 {
                        FaultCode::HostEmergency
                    } else {
                        FaultCode::PeerEmergency
                    },
                    node,
                    t_ns: t,
                    // The host's emergency stop runs the full ramp.
                    ramp_100us: if node == 0 { 0 } else { e.ramp_100us },
                    // The stop it causes when Running.
                    ready: self
                        .ramps(&snapshot)
                        .and_then(|(stop, _)| Retarget::prepare(&snapshot.scaling, t, 0, stop)),
                })
            }
            Msg::Heartbeat(heartbeat) if node != self.node_id => Some(Item::PeerHeartbeat {
                node,
                heartbeat,
                rx_us,
            }),
            Msg::Command(c) if for_me => Some(Item::Command {
                command: c,
                rx_us,
                data: self.command_data(&c, rx_us, &snapshot, kept),
            }),
            Msg::ConfigWrite { index, value } if for_me => {
                if let Some(slot) = self.written.get_mut(index as usize) {
                    *slot = value;
                    self.written_mask |= 1u64 << index;
                }
                None
            }
            Msg::SegmentPart | Msg::SegmentPartFd | Msg::SegmentCompact | Msg::SegmentCompactFd => {
                self.part(msg, rx.frame.payload(), snapshot.config_crc)
            }
            _ => None,
        }
    }

    fn command_data(
        &mut self,
        c: &Command,
        rx_us: u64,
        snapshot: &TickSnapshot,
        kept: bool,
    ) -> CommandData {
        let code = c.command();
        match code {
            Ok(CommandCode::ReadConfig) => CommandData::Values(self.written),
            Ok(CommandCode::ConfigCommit) => self.prepare(c.arg, snapshot.config_crc, kept),
            Ok(
                CommandCode::FeedHold
                | CommandCode::Resume
                | CommandCode::Override
                | CommandCode::Stop
                | CommandCode::QuickStop,
            ) => {
                let t = self.sync.apply_ns(c.arg, rx_us);
                if !snapshot.scaling.in_transition() {
                    return CommandData::At(t);
                }
                // The change of σ the drive makes of it if it acts on it
                // (see `Drive::on_command`): sized here, not in the tick.
                let Some((stop, quick)) = self.ramps(snapshot) else {
                    return CommandData::At(t);
                };
                let (k, full) = match code {
                    Ok(CommandCode::Resume) => (snapshot.override_q16, stop),
                    Ok(CommandCode::Override) => (q16_from_permille(c.arg2 as u32), stop),
                    Ok(CommandCode::QuickStop) => (0, quick),
                    _ => (0, stop),
                };
                match Retarget::prepare(&snapshot.scaling, t, k, full) {
                    Some(r) => CommandData::Scaling(r),
                    None => CommandData::At(t),
                }
            }
            _ => CommandData::None,
        }
    }

    /// When the stop a peer's Emergency causes begins (host ns): at the
    /// host time this node's constant σ reaches the sender's plan time at
    /// its fault, if that is within `PEER_RAMP_MARGIN_US` of the receipt,
    /// so every node's σ(t) is the same to the microsecond of plan time;
    /// else (the host's, a transition, a time too far off) the receipt.
    fn emergency_ns(&self, e: &Emergency, node: u8, rx_us: u64, snapshot: &TickSnapshot) -> i64 {
        const MAX_NS: i64 = EMERGENCY_DATE_MAX_US * 1000;
        let rx = self.sync.host_ns(rx_us).unwrap_or(0);
        if node == 0 {
            return rx;
        }
        // The frame's µs wrap every 71.6 min: unwrapped against our own
        // plan time now.
        let own_us = snapshot.scaling.constant_plan_time_ns(rx).div_euclid(1000);
        let behind = (own_us as u32).wrapping_sub(e.plan_time_us) as i32 as i64;
        snapshot
            .scaling
            .constant_host_time_ns((own_us - behind) * 1000)
            .filter(|t| (t - rx).abs() <= MAX_NS)
            .unwrap_or(rx)
    }

    /// Stop and quick-stop ramps (ns) the tick runs transitions with.
    fn ramps(&self, snapshot: &TickSnapshot) -> Option<(i64, i64)> {
        snapshot.ramps_ns
    }

    /// A commit of the written values if their CRC is `want`: every parameter
    /// written and valid; with what it widens of
    /// the active configuration's (CRC `active_crc`) locked bounds.
    // Cold, out of line: a commit is rare, and every other frame's
    // receive path stays as short as without it.
    #[cold]
    #[inline(never)]
    fn prepare(&mut self, want: u32, active_crc: u32, kept: bool) -> CommandData {
        let crc = config_crc(&self.written);
        let all = (1u64 << PARAM_COUNT) - 1;
        let cfg = DriveConfig::from_values(&self.written);
        let active = self.config_of(active_crc);
        let widens = match active {
            Some(a) => first_widening(a, &cfg),
            // Nothing held yet: the first configuration sets the bounds.
            None if active_crc == 0 => None,
            // Running one this side no longer holds: judged as widening.
            None => Some(PARAM_COUNT as u8),
        };
        let config = if self.written_mask & all != all || crc != want || cfg.validate().is_err() {
            Err(FaultCode::ConfigMismatch)
        } else {
            // The new one, and the one running: a refused commit never
            // takes the running configuration's place.
            if self.configs[0].map(|(c, _)| c) != Some(crc) {
                // Element by element: a new pair of configurations would be
                // built on the stack first.
                if let Some(a) = active {
                    self.configs[1] = Some((active_crc, *a));
                } else {
                    self.configs[1] = self.configs[0];
                }
                self.configs[0] = Some((crc, cfg));
            }
            Ok(Prepared {
                cfg,
                lock: LockCheck {
                    kept,
                    widens,
                    against: active_crc,
                },
            })
        };
        CommandData::Commit { crc, config }
    }

    /// The prepared configuration of CRC `crc`, if this side holds it.
    fn config_of(&self, crc: u32) -> Option<&DriveConfig> {
        self.configs
            .iter()
            .flatten()
            .find(|(c, _)| *c == crc && crc != 0)
            .map(|(_, cfg)| cfg)
    }

    fn part(&mut self, msg: Msg, payload: &[u8], active_crc: u32) -> Option<Item> {
        match self.segments.push(msg.kind(), payload)? {
            SegmentEvent::Pending => None,
            SegmentEvent::Ignored(r) => Some(Item::PartIgnored(r)),
            SegmentEvent::Rejected { seq, reason } => Some(Item::PartRejected {
                seq: seq.unwrap_or(0xFFFF),
                reason,
            }),
            SegmentEvent::Complete {
                segment, pred_crc, ..
            } => Some(Item::Segment(self.check(&segment, pred_crc, active_crc))),
        }
    }

    /// The expensive part of accepting a segment, done here so the tick does
    /// not: conversion, the ceilings and limits on its exact maxima, soft
    /// limits at 65 points, start and end motion.
    fn check(&self, w: &WireSegment, pred_crc: Option<u32>, active_crc: u32) -> CheckedSegment {
        let mut seg = Seg::from_wire(w, 0);
        let cfg = self
            .configs
            .iter()
            .flatten()
            .find(|(c, _)| *c == active_crc && active_crc != 0);
        let verdict = match cfg {
            // The node refuses it anyway (no configuration).
            None => Err(Reject::WrongState),
            // Out-of-range durations are the node's Invalid; skip the work.
            Some(_) if w.duration_us < MIN_DURATION_US || w.duration_us > MAX_DURATION_US => {
                Err(Reject::Invalid)
            }
            Some((_, cfg)) => {
                // The ceilings first: a refusal names which was exceeded.
                // Then the drive's own stop ramps for it.
                let m = Maxima::of(&seg);
                m.check(cfg)
                    .and_then(|()| m.ramps_and_units(cfg))
                    .map(|(full, units)| (seg.ramps_us, seg.unit_ramps) = (full, units))
                    .and_then(|()| within_limits(&seg, &m, cfg))
            }
        };
        CheckedSegment {
            begin: seg.eval(seg.start_ns),
            end: seg.eval(seg.end_ns()),
            seg,
            verdict,
            config_crc: cfg.map(|(c, _)| *c).unwrap_or(0),
            pred_crc,
        }
    }
}
