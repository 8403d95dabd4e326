//! triquint drive firmware for the ST B-G431B-ESC1: one axis per board.
//!
//! Interrupts, highest first: the current loop (end of the ADC conversions
//! that TIM1 starts at the PWM centre, 20 kHz), the
//! control tick (TIM6 update, 10 kHz, owns the node), embassy's own handlers
//! (CAN controller, limit switch, time driver), then the embassy executor
//! in thread mode (CAN receive / transmit, limit switch, flash). All motion
//! logic is the target-independent core (`triquint-firmware`).
#![no_std]
#![no_main]

mod board;
mod can;
mod ccm;
mod control;
mod current;
mod encoder;
mod foc;
mod halt;
mod homing;
mod motor;
mod storage;
mod watchdog;

use embassy_embedded_hal::adapter::BlockingAsync;
use embassy_executor::Spawner;
use embassy_stm32::adc::{Adc, AdcConfig, Exten, SampleTime};
use embassy_stm32::exti::ExtiInput;
use embassy_stm32::flash::Flash;
use embassy_stm32::gpio::{OutputType, Pull};
use embassy_stm32::interrupt::{InterruptExt, Priority};
use embassy_stm32::opamp::OpAmp;
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::complementary_pwm::{ComplementaryPwm, ComplementaryPwmPin};
use embassy_stm32::timer::low_level::{CountingMode, RoundTo, Timer};
use embassy_stm32::timer::qei::{Config as QeiConfig, Qei};
use embassy_stm32::timer::simple_pwm::PwmPin;
use embassy_stm32::{Config, bind_interrupts, can as fdcan, interrupt, peripherals, rcc};
use heapless::spsc::Queue;
use static_cell::StaticCell;
use triquint_firmware::inbox::{INBOX_SLOTS, Item};
use triquint_firmware::{Drive, Receiver};
use triquint_shared::protocol::Frame;

bind_interrupts!(struct Irqs {
    FDCAN1_IT0 => fdcan::IT0InterruptHandler<peripherals::FDCAN1>;
    FDCAN1_IT1 => fdcan::IT1InterruptHandler<peripherals::FDCAN1>;
    EXTI9_5 => embassy_stm32::exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
});

static INBOX: StaticCell<Queue<Item, INBOX_SLOTS>> = StaticCell::new();
/// Three frames a tick to the transmit task, more than the bus carries in
/// 100 µs; what waits longer waits in the drive's own outbox.
static TX_QUEUE: StaticCell<Queue<Frame, 4>> = StaticCell::new();
static TICK_STATE: StaticCell<control::Tick> = StaticCell::new();
static CURRENT_STATE: StaticCell<current::Current> = StaticCell::new();
static OPAMP1: StaticCell<OpAmp<'static, peripherals::OPAMP1>> = StaticCell::new();
static OPAMP2: StaticCell<OpAmp<'static, peripherals::OPAMP2>> = StaticCell::new();

/// 170 MHz from the 16 MHz HSI (the board's 8 MHz crystal is not needed);
/// FDCAN from PLL Q at 85 MHz.
fn clocks() -> Config {
    let mut config = Config::default();
    config.rcc.pll = Some(rcc::Pll {
        source: rcc::PllSource::HSI,
        prediv: rcc::PllPreDiv::DIV4,
        mul: rcc::PllMul::MUL85,
        divp: None,
        divq: Some(rcc::PllQDiv::DIV4),
        divr: Some(rcc::PllRDiv::DIV2),
    });
    config.rcc.sys = rcc::Sysclk::PLL1_R;
    config.rcc.boost = true;
    config.rcc.mux.fdcansel = rcc::mux::Fdcansel::PLL1_Q;
    config
}

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let p = embassy_stm32::init(clocks());

    // Node id and configuration live in flash.
    let mut flash: storage::Storage = BlockingAsync::new(Flash::new_blocking(p.FLASH));
    let node_id = match storage::node_id(&mut flash).await {
        Some(id @ 1..=15) if option_env!("TRIQUINT_NODE_ID").is_none() => id,
        _ => {
            storage::store_node_id(&mut flash, board::DEFAULT_NODE_ID).await;
            board::DEFAULT_NODE_ID
        }
    };

    // Encoder: TIM4 quadrature on PB6/PB7 (J8 A/B).
    let qei = Qei::new(p.TIM4, p.PB6, p.PB7, QeiConfig::default());
    let encoder = encoder::QuadratureEncoder::new(qei);

    // Power stage: TIM1 CH1-3 with complementary outputs, centre-aligned 20 kHz.
    let mut pwm = ComplementaryPwm::new(
        p.TIM1,
        Some(PwmPin::new(p.PA8, OutputType::PushPull)),
        Some(ComplementaryPwmPin::new(p.PC13, OutputType::PushPull)),
        Some(PwmPin::new(p.PA9, OutputType::PushPull)),
        Some(ComplementaryPwmPin::new(p.PA12, OutputType::PushPull)),
        Some(PwmPin::new(p.PA10, OutputType::PushPull)),
        Some(ComplementaryPwmPin::new(p.PB15, OutputType::PushPull)),
        None,
        None,
        Hertz(board::PWM_HZ),
        CountingMode::CenterAlignedBothInterrupts,
    );
    pwm.set_dead_time(100); // ≈ 590 ns at 170 MHz
    pwm.set_repetition_counter(1); // one update per PWM period
    pwm.set_master_output_enable(false);
    for ch in [
        embassy_stm32::timer::Channel::Ch1,
        embassy_stm32::timer::Channel::Ch2,
        embassy_stm32::timer::Channel::Ch3,
    ] {
        pwm.set_duty(ch, pwm.get_max_duty() / 2);
        pwm.enable(ch);
    }

    // Phase currents: op-amps 1 and 2 as wired on the board (external gain),
    // outputs into ADC1 and ADC2.
    let op1 = OPAMP1.init(OpAmp::new(
        p.OPAMP1,
        embassy_stm32::opamp::OpAmpSpeed::HighSpeed,
    ));
    let op2 = OPAMP2.init(OpAmp::new(
        p.OPAMP2,
        embassy_stm32::opamp::OpAmpSpeed::HighSpeed,
    ));
    let out_u = op1.standalone_ext(p.PA1, p.PA3, p.PA2);
    let out_v = op2.standalone_ext(p.PA7, p.PA5, p.PA6);
    // Injected conversions started by TIM1 at the PWM centre (TRGO2); the
    // end of ADC2's raises the current loop's interrupt.
    let phase_u = Adc::new(p.ADC1, AdcConfig::default()).setup_injected_conversions(
        [(current::channel(out_u), SampleTime::CYCLES2_5)],
        embassy_stm32::triggers::TIM1_TRGO2,
        Exten::RISING_EDGE,
        false,
    );
    let phase_v = Adc::new(p.ADC2, AdcConfig::default()).setup_injected_conversions(
        [(current::channel(out_v), SampleTime::CYCLES2_5)],
        embassy_stm32::triggers::TIM1_TRGO2,
        Exten::RISING_EDGE,
        true,
    );
    current::trigger_at_centre();
    let cur = current::Current {
        pwm,
        phase_u,
        phase_v,
    };
    let cur = CURRENT_STATE.init(cur);
    current::CURRENT.store(cur, core::sync::atomic::Ordering::Release);

    // CAN-FD: PA11 RX, PB9 TX. The tick reads the controller's error counters.
    let mut cfg = fdcan::CanConfigurator::new(p.FDCAN1, p.PA11, p.PB9, Irqs);
    can::configure(&mut cfg);
    let (can_tx, can_rx, can_props) = cfg.into_normal_mode().split();

    // Queues between the CAN tasks and the tick.
    let (inbox_prod, inbox_cons) = INBOX.init(Queue::new()).split();
    let (tx_prod, tx_cons) = TX_QUEUE.init(Queue::new()).split();

    // Built in place: the state (its segment queue and outbox) is larger
    // than the stack.
    let tick = TICK_STATE.init_with(|| control::Tick {
        // Position unknown at power-on: the host homes it (Home command).
        drive: Drive::new_unhomed(node_id),
        encoder,
        motor: motor::TorqueToCurrent {
            // Until a configuration brings Kt: no current at all.
            kt: f32::INFINITY,
            max_current: board::MAX_CURRENT,
        },
        inbox: inbox_cons,
        tx: tx_prod,
        can: can_props,
    });
    control::TICK.store(tick, core::sync::atomic::Ordering::Release);

    // Control tick: TIM6 at 10 kHz, below the current loop, above everything else.
    let tim6 = Timer::new(p.TIM6);
    tim6.set_frequency(Hertz(board::TICK_HZ), RoundTo::Faster);
    tim6.enable_update_interrupt(true);
    interrupt::ADC1_2.set_priority(Priority::P0);
    interrupt::TIM6_DAC.set_priority(Priority::P1);
    // embassy leaves its own handlers at P0, the reset value: the CAN
    // controller, the limit switch's EXTI and the time driver's timer
    // (TIM15) would then hold off the current loop and preempt the tick.
    // The CAN frames keep their hardware timestamps, and the time driver
    // only needs its handler within half its counter's period.
    for irq in [
        interrupt::FDCAN1_IT0,
        interrupt::FDCAN1_IT1,
        interrupt::EXTI9_5,
        interrupt::TIM1_BRK_TIM15,
    ] {
        irq.set_priority(Priority::P2);
    }
    // SAFETY: both handlers own their state (moved in above) and share only atomics.
    unsafe {
        interrupt::ADC1_2.enable();
        interrupt::TIM6_DAC.enable();
    }
    tim6.start();
    core::mem::forget(tim6);

    let home = ExtiInput::new(p.PB8, p.EXTI8, Pull::Down, Irqs);
    spawner.spawn(can::receive(can_rx, Receiver::new(node_id), inbox_prod).expect("spawn can rx"));
    spawner.spawn(can::transmit(can_tx, tx_cons).expect("spawn can tx"));
    spawner.spawn(homing::watch(home).expect("spawn limit switch"));
    spawner.spawn(storage::keep(flash, node_id).expect("spawn storage"));
    spawner.spawn(watchdog::feed(p.IWDG).expect("spawn watchdog"));
}
