//! Replays `testdata/firmware/golden.bin` (written by the host test
//! `firmware/tests/golden.rs`, which documents the format) and compares every
//! f32 result bit for bit, counting instructions as it goes.

use nalgebra::Vector3;
use triquint_firmware::Item;
use triquint_firmware::inbox::{CommandData, Inbox};
use triquint_firmware::segment::{Seg, scale};
use triquint_firmware::{Drive, Receiver, RxFrame};
use triquint_shared::Model;
use triquint_shared::dynamics;
use triquint_shared::protocol::{Frame, State, WireSegment};

use crate::count::Counter;
use crate::tick::{Counts, Motor, triquint_can_rx, triquint_control_tick};

/// A mismatch or a malformed file: what and at which byte offset.
#[derive(Debug)]
pub struct Failure {
    pub what: &'static str,
    pub offset: usize,
    pub want: u32,
    pub got: u32,
}

struct Rd<'a> {
    b: &'a [u8],
    p: usize,
}

impl Rd<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], Failure> {
        let s = self.b.get(self.p..self.p + N).ok_or(Failure {
            what: "truncated golden file",
            offset: self.p,
            want: 0,
            got: 0,
        })?;
        self.p += N;
        let mut a = [0; N];
        a.copy_from_slice(s);
        Ok(a)
    }
    fn u8(&mut self) -> Result<u8, Failure> {
        Ok(self.take::<1>()?[0])
    }
    fn u16(&mut self) -> Result<u16, Failure> {
        Ok(u16::from_le_bytes(self.take()?))
    }
    fn u32(&mut self) -> Result<u32, Failure> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Result<u64, Failure> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    fn f32(&mut self) -> Result<f32, Failure> {
        Ok(f32::from_bits(self.u32()?))
    }
    fn v3(&mut self) -> Result<Vector3<f32>, Failure> {
        Ok(Vector3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    /// Compares `got` with the next stored word.
    fn expect(&mut self, what: &'static str, got: u32) -> Result<(), Failure> {
        let offset = self.p;
        let want = self.u32()?;
        if want == got {
            Ok(())
        } else {
            Err(Failure {
                what,
                offset,
                want,
                got,
            })
        }
    }
    fn expect_v3(&mut self, what: &'static str, v: &Vector3<f32>) -> Result<(), Failure> {
        for k in 0..3 {
            self.expect(what, v[k].to_bits())?;
        }
        Ok(())
    }
}

/// Same FNV-1a as the host test: the frames a node queued.
fn drain(node: &mut Drive) -> (u8, u32) {
    let mut h: u32 = 0x811C_9DC5;
    let mut n = 0u8;
    while let Some(f) = node.pop_tx() {
        n = n.wrapping_add(1);
        let mut eat = |b: u8| {
            h ^= b as u32;
            h = h.wrapping_mul(0x0100_0193);
        };
        for b in f.id.to_le_bytes() {
            eat(b);
        }
        eat(f.len);
        eat(f.fd as u8);
        for &b in f.payload() {
            eat(b);
        }
    }
    (n, h)
}

/// Instruction figures gathered during the replay.
#[derive(Default, Debug)]
pub struct Figures {
    /// The highest stack pointer at a call into an entry point.
    pub call_sp: usize,
    pub evals: u32,
    pub quintic_max: u32,
    pub quintic_sum: u64,
    pub dynamics_max: u32,
    pub dynamics_sum: u64,
    pub ticks: u32,
    pub running_ticks: u32,
    pub running_sum: u64,
    pub running_max: u32,
    pub ramp_max: u32,
    /// Ticks that took a command (hold, resume, override, stop) while the
    /// time-scaling was in a transition.
    pub command_mid_ticks: u32,
    pub command_mid_max: u32,
    pub idle_max: u32,
    /// Ticks in which the queue front advanced to the next segment.
    pub switch_ticks: u32,
    pub switch_max: u32,
    /// Switch ticks that also took a new segment from the inbox.
    pub switch_take_ticks: u32,
    pub switch_take_max: u32,
    /// Ticks that took a segment from the inbox (accepted or not).
    pub take_segment_max: u32,
    /// Receive side (CAN task) per frame.
    pub rx_frames: u32,
    pub rx_sum: u64,
    pub rx_max: u32,
    /// Per frame that completes a segment (reassembly end, CRC, checks).
    pub rx_segment_max: u32,
    /// Per frame, other than a segment's last part or a configuration commit.
    pub rx_other_max: u32,
    /// The configuration commit (its checks, in the receive context).
    pub rx_commit_max: u32,
    /// Every tick includes its hand-off (items taken from the inbox).
    pub worst_tick: u32,
}

pub fn replay(data: &[u8], cnt: &Counter) -> Result<Figures, Failure> {
    let mut r = Rd { b: data, p: 0 };
    if r.take::<4>()? != *b"TQG1" {
        return Err(Failure {
            what: "not a golden file",
            offset: 0,
            want: 0,
            got: 0,
        });
    }
    let mut fig = Figures::default();
    let mut model: Option<Model<f32>> = None;
    let mut seg: Option<Seg> = None;
    let mut node: Option<(Receiver, Drive, Inbox)> = None;
    let mut motor = Motor::default();
    loop {
        let at = r.p;
        let tag = r.u8()?;
        match tag {
            b'M' => {
                let rho_u = [r.v3()?, r.v3()?, r.v3()?];
                let mut f = [0f32; 9];
                for x in &mut f {
                    *x = r.f32()?;
                }
                model = Some(Model {
                    rho_u,
                    l: f[0],
                    l2: f[1],
                    platform_mass: f[2],
                    strut_mass: f[3],
                    slider_mass: f[4],
                    rotor_inertia: f[5],
                    ratio: f[6],
                    inv_ratio: f[7],
                    gravity: f[8],
                });
            }
            b'S' => {
                let seq = r.u16()?;
                let flags = r.u16()?;
                let duration_us = r.u32()?;
                let start = r.u64()? as i64;
                let mut coeffs = [[0i64; 6]; 3];
                for row in &mut coeffs {
                    for c in row.iter_mut() {
                        *c = r.u64()? as i64;
                    }
                }
                let w = WireSegment {
                    seq,
                    duration_us,
                    flags,
                    coeffs,
                };
                seg = Some(Seg::from_wire(&w, start));
            }
            b'E' => {
                let (Some(s), Some(m)) = (seg.as_ref(), model.as_ref()) else {
                    return Err(fail("evaluation before segment/model", at));
                };
                let s_ns = r.u64()? as i64;
                let (sg, sd, sdd) = (r.f32()?, r.f32()?, r.f32()?);
                let (mo, nq) = cnt.instructions(|| scale(&s.eval(s_ns), sg, sd, sdd));
                let (t, nd) = cnt.instructions(|| dynamics::torque(m, &mo.q, &mo.qd, &mo.qdd));
                fig.evals += 1;
                fig.quintic_max = fig.quintic_max.max(nq);
                fig.quintic_sum += nq as u64;
                fig.dynamics_max = fig.dynamics_max.max(nd);
                fig.dynamics_sum += nd as u64;
                r.expect_v3("q", &mo.q)?;
                r.expect_v3("qd", &mo.qd)?;
                r.expect_v3("qdd", &mo.qdd)?;
                r.expect_v3("qddd", &mo.qddd)?;
                let ok = r.u8()?;
                let t = match t {
                    Ok(t) if ok == 1 => t,
                    Err(_) if ok == 0 => Vector3::zeros(),
                    _ => return Err(fail("torque solvability", at)),
                };
                r.expect_v3("torque", &t)?;
            }
            b'N' => {
                let id = r.u8()?;
                node = Some((Receiver::new(id), Drive::new(id), Inbox::new()));
                motor = Motor::default();
            }
            b'F' => {
                let Some((rcv, n, inbox)) = node.as_mut() else {
                    return Err(fail("frame before node", at));
                };
                let ts = r.u32()? as u64;
                let id = r.u16()?;
                let len = r.u8()? as usize;
                let fd = r.u8()? != 0;
                let payload = r.b.get(r.p..r.p + len).ok_or(fail("truncated frame", at))?;
                r.p += len;
                let rx = RxFrame {
                    frame: Frame::with_payload(id, payload, fd),
                    timestamp_us: ts,
                };
                let snapshot = n.snapshot();
                // Outside the counted call: the closure's few bytes count as used.
                fig.call_sp = fig.call_sp.max(crate::stack::here());
                let (item, k) = cnt.instructions(|| triquint_can_rx(rcv, &rx, snapshot));
                fig.rx_frames += 1;
                fig.rx_sum += k as u64;
                fig.rx_max = fig.rx_max.max(k);
                match &item {
                    Some(Item::Segment(_)) => fig.rx_segment_max = fig.rx_segment_max.max(k),
                    Some(Item::Command {
                        data: CommandData::Commit { .. },
                        ..
                    }) => fig.rx_commit_max = fig.rx_commit_max.max(k),
                    _ => fig.rx_other_max = fig.rx_other_max.max(k),
                }
                if let Some(item) = item {
                    // A full inbox drops the item, as on the board.
                    let _ = inbox.enqueue(item);
                }
            }
            b'T' => {
                let Some((_, n, inbox)) = node.as_mut() else {
                    return Err(fail("tick before node", at));
                };
                let now = r.u32()? as u64;
                let counts = r.u32()? as i32 as i64;
                let before = (n.state(), n.queue_depth(), n.scaling_phase());
                let segment_waiting = matches!(inbox.peek(), Some(Item::Segment(_)));
                let command_mid = n.scaling().in_transition()
                    && inbox
                        .iter()
                        .take(2)
                        .any(|i| matches!(i, Item::Command { .. }));
                let seq = n.next_seq();
                fig.call_sp = fig.call_sp.max(crate::stack::here());
                let ((), k) = cnt.instructions(|| {
                    triquint_control_tick(n, inbox, now, &mut Counts(counts), &mut motor)
                });
                let took_segment = n.next_seq() != seq;
                // Outside the counted tick: the single context here is the
                // CAN side too.
                if !crate::watchdog::started() {
                    crate::watchdog::start();
                }
                crate::watchdog::tick_checked_in();
                crate::watchdog::can_checked_in();
                crate::watchdog::offer_feed();
                r.expect("motor torque", motor.torque.to_bits())?;
                let flags = r.u8()?;
                let got = motor.enabled as u8 | (n.state() as u8) << 1;
                if flags != got {
                    return Err(Failure {
                        what: "motor enable / state",
                        offset: at,
                        want: flags as u32,
                        got: got as u32,
                    });
                }
                check_tx(&mut r, n)?;
                fig.ticks += 1;
                fig.worst_tick = fig.worst_tick.max(k);
                if command_mid {
                    fig.command_mid_ticks += 1;
                    fig.command_mid_max = fig.command_mid_max.max(k);
                }
                if segment_waiting {
                    fig.take_segment_max = fig.take_segment_max.max(k);
                }
                use triquint_firmware::scaling::Phase;
                match before.0 {
                    State::Running | State::Stopping => {
                        // The queue front advanced (with a segment taken,
                        // the depth stays: compare with one more).
                        let depth = n.queue_depth().saturating_sub(took_segment as usize);
                        if depth < before.1 && n.state() == before.0 {
                            fig.switch_ticks += 1;
                            fig.switch_max = fig.switch_max.max(k);
                            if took_segment {
                                fig.switch_take_ticks += 1;
                                fig.switch_take_max = fig.switch_take_max.max(k);
                            }
                        }
                        if before.2 == Phase::Nominal && before.0 == State::Running {
                            fig.running_ticks += 1;
                            fig.running_sum += k as u64;
                            fig.running_max = fig.running_max.max(k);
                        } else if !command_mid {
                            fig.ramp_max = fig.ramp_max.max(k);
                        }
                    }
                    _ => fig.idle_max = fig.idle_max.max(k),
                }
            }
            b'Z' => return Ok(fig),
            _ => return Err(fail("unknown record", at)),
        }
    }
}

fn fail(what: &'static str, offset: usize) -> Failure {
    Failure {
        what,
        offset,
        want: 0,
        got: 0,
    }
}

fn check_tx(r: &mut Rd, n: &mut Drive) -> Result<(), Failure> {
    let at = r.p;
    let (k, h) = drain(n);
    let want = r.u8()?;
    if want != k {
        return Err(Failure {
            what: "transmitted frame count",
            offset: at,
            want: want as u32,
            got: k as u32,
        });
    }
    if k > 0 {
        r.expect("transmitted frames (hash)", h)?;
    }
    Ok(())
}
