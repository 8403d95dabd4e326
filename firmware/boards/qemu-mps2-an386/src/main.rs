//! On-target test of the triquint firmware core on QEMU's mps2-an386
//! (Cortex-M4F): replays the golden plans and frames, compares every f32 bit,
//! measures instructions per control tick, and exits through semihosting
//! (status 0 pass, 1 fail).
#![no_std]
#![no_main]
// The watchdog-test image has its own entry: the golden replay is unused there.
#![cfg_attr(feature = "watchdog-test", allow(dead_code, unused_imports))]

mod count;
mod golden;
mod stack;
mod tick;
mod watchdog;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;

static GOLDEN: &[u8] = include_bytes!("../../../../testdata/firmware/golden.bin");

/// Instructions per control tick allowed in the worst case: the tick must
/// fit its period on the target with room for the CAN receive side.
const BUDGET: u32 = 3000;
/// SysTick counts per 1024 instructions under `-icount shift=10` (1024 ns per
/// instruction) at the 25 MHz core clock: 25.6 × 1024.
const ICOUNT_PER_K: u32 = 26_214;

#[cfg(not(feature = "watchdog-test"))]
#[entry]
fn main() -> ! {
    let p = cortex_m::Peripherals::take().expect("peripherals");
    let cnt = count::Counter::new(p.SYST);
    let sp = stack::here();
    stack::paint(sp);
    let replayed = golden::replay(GOLDEN, &cnt);
    let lowest = stack::lowest_written(sp);
    let pass = match replayed {
        Ok(f) => {
            hprintln!(
                "golden: {} plan evaluations and {} ticks, {} frames: every f32 bit equal",
                f.evals,
                f.ticks,
                f.rx_frames
            );
            let icount = cnt.per_k().abs_diff(ICOUNT_PER_K) <= ICOUNT_PER_K / 100;
            hprintln!(
                "instructions (calibration {} counts / 1024 instructions{})",
                cnt.per_k(),
                if icount {
                    ""
                } else {
                    ": NOT under -icount shift=10, figures meaningless"
                }
            );
            let mean = |s: u64, n: u32| s / n.max(1) as u64;
            hprintln!(
                "  quintic, 3 axes + time-scaling      mean {:5}  max {:5}",
                mean(f.quintic_sum, f.evals),
                f.quintic_max
            );
            hprintln!(
                "  inverse dynamics (IK + Jacobians)   mean {:5}  max {:5}",
                mean(f.dynamics_sum, f.evals),
                f.dynamics_max
            );
            hprintln!(
                "  tick, Running at sigma = 1          mean {:5}  max {:5}  ({} ticks)",
                mean(f.running_sum, f.running_ticks),
                f.running_max,
                f.running_ticks
            );
            hprintln!(
                "  tick, stop/hold/resume ramps (no command)      max {:5}",
                f.ramp_max
            );
            hprintln!(
                "  tick taking a command mid-transition           max {:5}  ({} ticks)",
                f.command_mid_max,
                f.command_mid_ticks
            );
            hprintln!(
                "  tick, segment switch                           max {:5}  ({} ticks)",
                f.switch_max,
                f.switch_ticks
            );
            hprintln!(
                "  tick, segment switch + new segment taken       max {:5}  ({} ticks)",
                f.switch_take_max,
                f.switch_take_ticks
            );
            hprintln!(
                "  tick taking a segment from the inbox           max {:5}",
                f.take_segment_max
            );
            hprintln!(
                "  tick, idle / armed                             max {:5}",
                f.idle_max
            );
            hprintln!(
                "  worst tick (every tick includes its hand-off)      {:5}",
                f.worst_tick
            );
            hprintln!(
                "stack: the entry points used at most {} B below their calls",
                f.call_sp.saturating_sub(lowest)
            );
            hprintln!(
                "CAN receive side, per frame (CAN task, below the tick; {} frames)",
                f.rx_frames
            );
            hprintln!(
                "  any frame                          mean {:5}  max {:5}",
                mean(f.rx_sum, f.rx_frames),
                f.rx_max
            );
            hprintln!(
                "  last part of a segment (reassembly, CRC, limits)  max {:5}",
                f.rx_segment_max
            );
            hprintln!(
                "  configuration commit (checks)                     max {:5}",
                f.rx_commit_max
            );
            hprintln!(
                "  any other frame                                   max {:5}",
                f.rx_other_max
            );
            if !icount {
                false
            } else if f.switch_take_ticks == 0 {
                hprintln!("FAIL: no segment switch took a new segment: worst case not measured");
                false
            } else if f.command_mid_ticks == 0 {
                hprintln!("FAIL: no tick took a command mid-transition: worst case not measured");
                false
            } else if watchdog::feeds() == 0 {
                hprintln!("FAIL: the watchdog was never fed");
                false
            } else if f.worst_tick > BUDGET {
                hprintln!(
                    "FAIL: worst tick (with hand-off) {} instructions > budget {}",
                    f.worst_tick,
                    BUDGET
                );
                false
            } else {
                true
            }
        }
        Err(e) => {
            hprintln!(
                "FAIL: {} at byte {}: want {:#010x}, got {:#010x}",
                e.what,
                e.offset,
                e.want,
                e.got
            );
            false
        }
    };
    let _ = cnt.release();
    hprintln!(
        "watchdog: fed {} times, quiet (timeout {} counts)",
        watchdog::feeds(),
        watchdog::LOAD_COUNTS
    );
    hprintln!("{}", if pass { "PASS" } else { "FAIL" });
    debug::exit(if pass {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::bkpt();
    }
}
