//! The current loop: TIM1's update interrupt at 20 kHz (centre-aligned PWM,
//! repetition counter 1), highest priority. Reads phases U and V through the
//! on-board op-amps, runs the field-oriented PI loop and writes the duties.
//! The power stage is on only when the node enabled it and the axis is homed.

use core::f32::consts::TAU;
use core::sync::atomic::{AtomicPtr, Ordering};

use embassy_stm32::adc::{Adc, AdcChannel, SampleTime};
use embassy_stm32::interrupt;
use embassy_stm32::pac;
use embassy_stm32::peripherals::{ADC1, ADC2, TIM1};
use embassy_stm32::timer::Channel;
use embassy_stm32::timer::complementary_pwm::ComplementaryPwm;

use crate::board::*;
use crate::encoder::HOMED;
use crate::foc::{CurrentLoop, Pi};
use crate::motor::{ENABLE, iq_ref};

pub struct Current {
    pub pwm: ComplementaryPwm<'static, TIM1>,
    pub adc1: Adc<'static, ADC1>,
    pub adc2: Adc<'static, ADC2>,
    pub phase_u: embassy_stm32::adc::AnyAdcChannel<'static, ADC1>,
    pub phase_v: embassy_stm32::adc::AnyAdcChannel<'static, ADC2>,
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
fn TIM1_UP_TIM16() {
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
    pac::TIM1.sr().modify(|w| w.set_uif(false));
    // SAFETY: as for the tick: set once before the interrupt was enabled.
    let Some(c) = (unsafe { CURRENT.load(Ordering::Acquire).as_mut() }) else {
        return;
    };
    let on = ENABLE.load(Ordering::Relaxed) && HOMED.load(Ordering::Acquire);
    if !on {
        c.pwm.set_master_output_enable(false);
        LOOP.reset();
        return;
    }
    c.pwm.set_master_output_enable(true);
    let ia = (c.adc1.blocking_read(&mut c.phase_u, SampleTime::CYCLES2_5) as f32 - ZERO_CURRENT)
        * AMPS_PER_COUNT;
    let ib = (c.adc2.blocking_read(&mut c.phase_v, SampleTime::CYCLES2_5) as f32 - ZERO_CURRENT)
        * AMPS_PER_COUNT;
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
