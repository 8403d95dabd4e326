//! The current loop at 20 kHz, highest priority: the interrupt of the
//! injected conversions' end (ADC1_2, raised by ADC2's end of sequence).
//! TIM1 itself starts the conversions of phases U and V (through the on-board
//! op-amps, ADC1 and ADC2 at once) at the PWM centre, the peak of the
//! centre-aligned counter, where every low-side switch conducts: the sampling
//! instant is fixed by the timer, not by interrupt latency, and the
//! interrupt runs when the samples are ready, so it never waits on a
//! converter. It runs the field-oriented PI loop and writes the duties. The
//! power stage is on only when the node enabled it and the axis is homed.

use core::f32::consts::TAU;
use core::sync::atomic::{AtomicPtr, Ordering};

use embassy_stm32::adc::{AdcChannel, InjectedAdc};
use embassy_stm32::interrupt;
use embassy_stm32::pac;
use embassy_stm32::pac::timer::vals::{Mms2, Ocm};
use embassy_stm32::peripherals::{ADC1, ADC2, TIM1};
use embassy_stm32::timer::Channel;
use embassy_stm32::timer::complementary_pwm::ComplementaryPwm;

use crate::board::*;
use crate::foc::{CurrentLoop, Pi};
use crate::motor::{ENABLE, iq_ref};

pub struct Current {
    pub pwm: ComplementaryPwm<'static, TIM1>,
    /// Phase U on ADC1, phase V on ADC2: one injected rank each, started by
    /// TIM1's TRGO2 ([`trigger_at_centre`]); ADC2's end raises the interrupt.
    pub phase_u: InjectedAdc<'static, ADC1, 1>,
    pub phase_v: InjectedAdc<'static, ADC2, 1>,
}

/// TIM1 channel 4 (no pin, internal only) in PWM mode 2 with CCR4 = ARR − 1:
/// OC4REF rises one timer clock (6 ns) before the counter's peak, and as
/// TRGO2 it starts the injected conversions there, once per PWM period.
pub fn trigger_at_centre() {
    let arr = pac::TIM1.arr().read().arr();
    pac::TIM1
        .ccr(3)
        .modify(|w| w.set_ccr(arr.saturating_sub(1) as _));
    pac::TIM1
        .ccmr_output(1)
        .modify(|w| w.set_ocm(1, Ocm::PWM_MODE2));
    pac::TIM1.cr2().modify(|w| w.set_mms2(Mms2::COMPARE_OC4));
}

/// Handed to the interrupt once, like the tick's state.
pub static CURRENT: AtomicPtr<Current> = AtomicPtr::new(core::ptr::null_mut());

fn set_outputs(pwm: &mut ComplementaryPwm<'static, TIM1>, duty: [f32; 3]) {
    let max = pwm.get_max_duty() as f32;
    for (ch, d) in [Channel::Ch1, Channel::Ch2, Channel::Ch3]
        .into_iter()
        .zip(duty)
    {
        pwm.set_duty(ch, (d.clamp(0.0, 1.0) * max) as u32);
    }
}

#[interrupt]
fn ADC1_2() {
    static mut LOOP: CurrentLoop = CurrentLoop {
        d: Pi {
            kp: CURRENT_KP,
            ki_dt: CURRENT_KI_DT,
            integral: 0.0,
        },
        q: Pi {
            kp: CURRENT_KP,
            ki_dt: CURRENT_KI_DT,
            integral: 0.0,
        },
    };
    static mut ALIGNED: u32 = 0;
    static mut ZERO: u16 = 0;
    // SAFETY: as for the tick: set once before the interrupt was enabled.
    let Some(c) = (unsafe { CURRENT.load(Ordering::Acquire).as_mut() }) else {
        // Clear the flag, or the interrupt stays pending.
        pac::ADC2.isr().write(|w| w.set_jeos(true));
        return;
    };
    // Both converters started on the same trigger with the same sample
    // time, so ADC1 is done when ADC2 is; reading clears both end flags.
    let [u] = c.phase_u.read_injected_samples();
    let [v] = c.phase_v.read_injected_samples();
    let on = ENABLE.load(Ordering::Relaxed);
    if !on {
        c.pwm.set_master_output_enable(false);
        LOOP.reset();
        return;
    }
    c.pwm.set_master_output_enable(true);
    let ia = (u as f32 - ZERO_CURRENT) * AMPS_PER_COUNT;
    let ib = (v as f32 - ZERO_CURRENT) * AMPS_PER_COUNT;
    // The encoder counter itself (TIM4), not the tick's copy: the angle must be fresh.
    let raw = pac::TIM4.cnt().read().cnt();
    let duty = if *ALIGNED < ALIGN_PERIODS {
        // Lock the rotor on the d axis at θ = 0, then take the encoder's zero.
        *ALIGNED += 1;
        *ZERO = raw;
        LOOP.d.kp = CURRENT_KP;
        let (sin, cos) = (0.0, 1.0);
        let (alpha, beta) = crate::foc::clarke(ia, ib);
        let (id, _) = crate::foc::park(alpha, beta, sin, cos);
        let vd = LOOP.d.step(ALIGN_CURRENT - id, 0.3);
        crate::foc::svpwm(vd, 0.0)
    } else {
        // COUNTS_PER_REV divides 2^16, so the 16-bit difference keeps the angle.
        let turns = raw.wrapping_sub(*ZERO) as f32 / COUNTS_PER_REV;
        let theta_e = TAU * libm::fmodf(turns * POLE_PAIRS, 1.0);
        LOOP.step(ia, ib, theta_e, iq_ref())
    };
    set_outputs(&mut c.pwm, duty);
}

/// Opaque channel type for the op-amp outputs.
pub fn channel<T: embassy_stm32::adc::Instance>(
    ch: impl AdcChannel<T> + 'static,
) -> embassy_stm32::adc::AnyAdcChannel<'static, T> {
    ch.degrade_adc()
}
