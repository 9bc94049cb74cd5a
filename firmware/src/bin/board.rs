//! Board binary: the Flinch firmware on an STM32F407VGTx (Cortex-M4F, e.g. an STM32F4-Discovery).
//!
//! A thin shell around `flinch_firmware::Firmware`: it owns the registers, the library owns the logic.
//!
//! | signal            | pin  | notes                                                             |
//! |-------------------|------|-------------------------------------------------------------------|
//! | travel switch A   | PA0  | EXTI0 on both edges; NC channel, high at rest; pull-down, so a cut wire reads low = trip |
//! | travel switch B   | PA4  | EXTI4 on both edges; the antivalent channel (a powered sensor driving low at rest, high when tripped); pull-up, so a cut wire or an unpowered sensor reads high = trip, and the start-up test sees both channels trip with the supply off |
//! | reset input       | PA1  | pull-down, active high; acts on release (`flinch_firmware::reset`) |
//! | EDM K1, K2        | PA2, PA3 | the stop relays' force-guided NC mirror contacts, high = released; pull-down (`flinch_firmware::edm`) |
//! | stop K1 out       | PD12 | GPIOD (AHB1ENR bit 3); drives relay K1; high = energised = go, low = controlled stop; external pull-down: a reset or dead MCU leaves it an input, the relay released |
//! | stop K2 out       | PE12 | GPIOE (AHB1ENR bit 4); drives relay K2 (contacts in series with K1's); the same rules |
//! | escalation out    | PB12 | GPIOB (AHB1ENR bit 1); high = energised; low = category-0 stop (drive power off); external pull-down |
//! | sensor supply out | PD14 | high = powered; switched off by the start-up stuck-input test     |
//!
//! Each output is read back at its pin (IDR) every tick, and each relay at its mirror contact (EDM,
//! PA2/PA3): `flinch_firmware::output_monitor`. firmware/README.md, "Output architecture", has the
//! wiring and the diagnostic coverage claimed per channel.
//!
//! Time: TIM2, a 32-bit counter at 1 MHz, is the firmware's `Clock`. SysTick interrupts every
//! `TICK_US` and calls `Firmware::tick`.
//!
//! Priorities (a bounded edge-to-stop): EXTI0, the switch edge, has the highest priority (0) and
//! preempts every other interrupt. It does not touch the `Firmware` object: it reads the switch
//! (IDR), writes both stop channels low through their ports' BSRR (K1, then K2), clears its pending
//! bit, and pends the bookkeeping interrupt (UART5's line, unused otherwise),
//! which runs `Firmware::edge_stopped` (timestamp, budget, latch, log) or `Firmware::on_edge` at
//! SysTick's priority (0x80). SysTick and the bookkeeping share that priority, so `IsrCell`'s rule
//! (no two `&mut` at once, `support/isr_cell.rs`) holds between them; the edge shares only atomics.
//! The core runs on the 16 MHz HSI, the reset default: no PLL code to get wrong, and the detection
//! path is short enough at that speed (the QEMU build measures it in instructions).
//!
//! Failure handling: the independent watchdog (IWDG, LSI) is fed from the tick, and only while the
//! firmware is healthy and armed or healthy and stopped (`Firmware::feeds_watchdog`): every latched
//! fault starves it, and so does a firmware that stops ticking, a missed avoidance step or a fault
//! handler; the reset follows within about 8 ms, the reset state releases every pin (the relays
//! de-energise through the external pull-downs) and the next start finds the latch. The panic,
//! HardFault and default (NMI, any unexpected interrupt) handlers mask every interrupt, write the
//! outputs low before anything else and record `Cause::FaultHandler` in the retained latch.
//!
//! Start-up integrity (`flinch_firmware::integrity`): first in `main`, the two stop channels, the
//! escalation and the sensor-supply pins driven low by register writes (no RAM used), then a March C- RAM test over
//! .data/.bss and the stack region, a CRC-32 of the flash image against `FLINCH_FLASH_CRC` (patched
//! into the ELF by `cargo xtask`, with the `qemu-io` build's own seed), and the brown-out level (BOR
//! level 3, `flinch_firmware::option_bytes`: programmed once, verified from the option bytes at the
//! next boot). Any failure is a permanent stop with `SelfCheck` latched and logged in backup SRAM,
//! before the IWDG is started.
//!
//! Resets (`flinch_firmware::reset`, `flinch_firmware::backup`): `main` reads why the part reset from
//! `RCC_CSR` (then clears the flags with RMVF), and the latch and the event log from the backup SRAM
//! (`Bkp`, 0x4002_4000; PWREN, BKPSRAMEN, DBP), which no system reset clears; a power cycle without
//! VBAT leaves garbage that the records' CRCs reject (a clean power-on). The latch is stored by the
//! tick and the bookkeeping when it changes, the log by the thread-mode drain. Every start waits for a
//! reset press and release (`StartPolicy::ManualReset`). QEMU's netduinoplus2 maps the backup SRAM and
//! PWR as unimplemented devices (reads 0): there every start reads "no record".
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "flinch board firmware: this binary runs on the MCU. Build it with\n  \
         cd firmware && cargo build --release --target thumbv7em-none-eabihf"
    );
}

#[cfg(target_os = "none")]
#[path = "support/isr_cell.rs"]
mod isr_cell;

#[cfg(all(target_os = "none", feature = "qemu-io"))]
#[path = "support/board_bench.rs"]
mod bench;

// The avoidance step (USART1 in and out, TIM3 every 10 ms, its deadline on the IWDG's tick).
#[cfg(target_os = "none")]
#[path = "support/board_avoid.rs"]
mod board_avoid;

#[cfg(target_os = "none")]
#[path = "support/board_hw.rs"]
mod hw;

// Whether the firmware holds the robot stopped, for the velocity frames (a leaf: board.rs writes it,
// board_avoid.rs reads it).
#[cfg(target_os = "none")]
#[path = "support/board_held.rs"]
mod held;

#[cfg(target_os = "none")]
#[path = "support/board_pins.rs"]
mod pins;

#[cfg(all(target_os = "none", feature = "qemu-io"))]
#[path = "support/board_pin_image.rs"]
mod pin_image;

// The firmware's one instance and its interrupt priorities, which the handlers here and the
// diagnostics and log drain share.
#[cfg(target_os = "none")]
#[path = "support/board_fw.rs"]
mod fw;

#[cfg(target_os = "none")]
#[path = "support/board_startup.rs"]
mod startup;

#[cfg(target_os = "none")]
#[path = "support/board_backup.rs"]
mod backup;

#[cfg(target_os = "none")]
#[path = "support/board_log.rs"]
mod log_drain;

#[cfg(target_os = "none")]
#[path = "support/board_faults.rs"]
mod faults;

#[cfg(target_os = "none")]
#[path = "support/board_diag.rs"]
mod diag;

#[cfg(target_os = "none")]
mod board {
    use crate::fw::{Esc, FW, K1, K2, PRIO_EDGE, PRIO_TICK};
    use crate::backup::{backup_on, retained_store, Bkp, SAVED_SEQ};
    use crate::hw::{
        bsrr, emergency_stop, exti, gpio, idr, iwdg, lsi_capture, rcc, syscfg, tim2, tim5, In, Out, Tim2, CORE_HZ,
        K1_PIN, K1_PORT, K2_PIN, K2_PORT, LSI_HZ, PA, SUPPLY_PIN, SUPPLY_PORT, TICK_US, TIM2_HZ,
    };
    #[cfg(feature = "qemu-clock")]
    use crate::startup::{not_qemu, SELF_NOT_QEMU};
    use crate::startup::{early_outputs_low, flash_crc_ok, integrity_failed, ram_test, OptionRegs, BOR_BUSY_SPINS, SELF_BOR, SELF_FLASH, SELF_RAM};
    use crate::log_drain::LogDrain;
    use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
    use cortex_m::peripheral::scb::SystemHandler;
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m::peripheral::NVIC;
    use crate::faults::{stack_guard_on, STARVE};
    use cortex_m_rt::{entry, exception};
    use defmt_rtt as _;
    use flinch_firmware::option_bytes::{self, BorOutcome};
    use flinch_firmware::backup;
    use flinch_firmware::{
        Boot, EventLog, BudgetConfig, ClockCheck, Config, DualSwitch, Edm, Firmware, Micros, Outputs, ResetCause,
        SwitchKind,
    };

    const EXTI0_IRQ: u16 = 6; // RM0090 Table 61
    const EXTI4_IRQ: u16 = 10;
    /// The bookkeeping interrupt: UART5's line (RM0090 Table 61), pended by software only.
    const BOOK_IRQ: u16 = 53;
    /// TIM5's line (RM0090 Table 61): its channel 4 captures the LSI (the clock check's reference).
    const TIM5_IRQ: u16 = 50;
    /// The installation's configuration. The numbers are those of the thesis's Ch. 3 set-up and
    /// must be replaced by the real cell's: V_c = 0.05 m/s and DT = 16 ms (Tables 5-7, Viper scan
    /// cycle), d_sw = 5 mm (Ch. 3 simulations); deceleration 1 m/s^2 and a 10 mm stroke are
    /// placeholders for the robot's braking and the module's C1 + C2.
    const fn config() -> Config {
        let mut c = Config::new(
            TICK_US,
            BudgetConfig { robot_speed_um_per_s: 50_000, dead_time_us: 16_000, decel_um_per_s2: 1_000_000, stroke_um: 10_000 },
        );
        // The LSI's spread (17..47 kHz around 32 kHz, DS8626) sets the tolerance: +-50 % catches a
        // stopped, halved or doubled HSI or a wrong prescaler, not a drift of a few percent (that
        // needs an HSE crystal as the reference). 100 ms windows: about 3,200 LSI periods each.
        c.clock_check = Some(ClockCheck { reference_hz: LSI_HZ, window_us: 100_000, tolerance_pct: 50 });
        c
    }
    const SWITCH_TRAVEL_UM: i32 = 5_000;
    /// Channel A (PA0): the inductive switch, high at rest, low when tripped (a cut wire too).
    const SWITCH_KIND: SwitchKind = SwitchKind::Inductive;
    /// Channel B (PA4): its antivalent partner, high when tripped.
    const SWITCH_KIND_B: SwitchKind = SwitchKind::Magnetic { trip_high: true };
    /// How long the two channels may disagree before it is a fault, microseconds.
    const DISCREPANCY_US: u32 = 20_000;
    /// PA0's and PA4's IDR bits when each channel reads "tripped".
    const TRIP_A: u32 = if SWITCH_KIND.level_for(true) { 1 << 0 } else { 0 };
    const TRIP_B: u32 = if SWITCH_KIND_B.level_for(true) { 1 << 4 } else { 0 };

    /// `Firmware::edge_stops_directly`, stored once before EXTI0 is unmasked.
    static EDGE_FAST: AtomicBool = AtomicBool::new(false);
    /// The edge handler wrote the stop, at `EDGE_AT` (TIM2): for the bookkeeping.
    static EDGE_STOPPED: AtomicBool = AtomicBool::new(false);
    static EDGE_AT: AtomicU32 = AtomicU32::new(0);

    defmt::timestamp!("{=u32:us}", tim2().cnt().read().bits());




    #[entry]
    fn main() -> ! {
        early_outputs_low();
        // Then, before anything uses RAM: the start-up integrity checks (`flinch_firmware::integrity`).
        // SAFETY: nothing has used .data/.bss yet (no reference to a static is live); `ram_test`
        // restores .data and leaves .bss zeroed, as the start-up code left them.
        if !unsafe { ram_test() } {
            integrity_failed(SELF_RAM, 0);
        }
        // The bench build measures the board's stack use: paint the region the RAM test zeroed.
        #[cfg(feature = "qemu-io")]
        super::bench::paint_stack();
        if !flash_crc_ok() {
            integrity_failed(SELF_FLASH, 0);
        }
        backup_on();
        // A qemu-clock build (its tick scaled for QEMU) must never drive a machine (`not_qemu`).
        #[cfg(feature = "qemu-clock")]
        if let Some(which) = not_qemu() {
            integrity_failed(SELF_NOT_QEMU, which);
        }
        // The brown-out level, only with a good flash image, before the IWDG runs.
        match option_bytes::ensure_bor_level(&mut OptionRegs, &mut Bkp, BOR_BUSY_SPINS) {
            (BorOutcome::InEffect, _) => {}
            // Programmed: reset, so that the next boot reads the option bytes actually in effect.
            (BorOutcome::ResetToVerify, _) => cortex_m::peripheral::SCB::sys_reset(),
            (BorOutcome::Failed(why), sr) => integrity_failed(SELF_BOR, i32::from(why as u8) | ((sr as i32) << 8)),
        }
        let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| loop {
            emergency_stop();
        });
        // The stack guard and the fault priorities, before any interrupt can run (the RAM test,
        // which writes the guard region, is done).
        stack_guard_on(&mut cp);
        // Clocks for GPIOA (inputs), GPIOB, GPIOD, GPIOE (the three output ports), TIM2, TIM5, SYSCFG.
        rcc().ahb1enr().modify(|_, w| w.gpioaen().set_bit().gpioben().set_bit().gpioden().set_bit().gpioeen().set_bit());
        rcc().apb1enr().modify(|_, w| w.tim2en().set_bit().tim5en().set_bit());
        rcc().apb2enr().modify(|_, w| w.syscfgen().set_bit());
        cortex_m::asm::dsb(); // the errata's delay after an RCC clock enable (see `backup_on`)
        // Outputs low before they become outputs, so they never glitch high.
        emergency_stop();
        crate::startup::outputs_mode();
        // SAFETY (both): two-bit fields, mode 0b00 = input; pull 0b10 = down, 0b01 = up.
        gpio(PA).moder().modify(|r, w| unsafe { w.bits(r.bits() & !0x3FF) }); // PA0..PA4 input
        gpio(PA).pupdr().modify(|r, w| unsafe { w.bits((r.bits() & !0x3FF) | 0b01_10_10_10_10) }); // PA0..PA3 pull-down, PA4 pull-up
        // TIM2: 16 MHz / 16 = 1 MHz, full 32-bit range.
        // SAFETY: PSC is 16 bits (15 here, 999 in the qemu-io build); ARR takes any 32-bit value.
        tim2().psc().write(|w| unsafe { w.psc().bits((TIM2_HZ / 1_000_000 - 1) as u16) });
        tim2().arr().write(|w| unsafe { w.arr().bits(u32::MAX) });
        tim2().egr().write(|w| w.ug().set_bit()); // load the prescaler
        tim2().cr1().write(|w| w.cen().set_bit());
        // TIM5 channel 4 captures every 8th rising edge of the LSI (remap TI4 <- LSI); the LSI itself
        // runs once the IWDG is started below, LSION makes it explicit.
        rcc().csr().modify(|_, w| w.lsion().set_bit());
        // SAFETY (all): field values of RM0090 sec. 18.4: TI4_RMP 01 = LSI, CC4S 01 = input TI4,
        // IC4PSC 11 = every 8th edge.
        tim5().or().write(|w| unsafe { w.it4_rmp().bits(0b01) });
        tim5().ccmr2_input().write(|w| unsafe { w.cc4s().bits(0b01).ic4psc().bits(0b11) });
        tim5().ccer().write(|w| w.cc4e().set_bit());
        tim5().dier().write(|w| w.cc4ie().set_bit());
        tim5().cr1().write(|w| w.cen().set_bit());
        // Independent watchdog: LSI ~32 kHz / 4 = 8 kHz, reload 64 -> about 8 ms.
        // SAFETY: the key values of RM0090 sec. 21.4.1, prescaler /4 (0), a 12-bit reload.
        iwdg().kr().write(|w| unsafe { w.key().bits(0x5555) });
        iwdg().pr().write(|w| unsafe { w.pr().bits(0) });
        iwdg().rlr().write(|w| unsafe { w.rl().bits(64) });
        iwdg().kr().write(|w| unsafe { w.key().bits(0xCCCC) });

        // Why did the part reset? Read the flags, then clear them so the next reset reads its own.
        let cause = ResetCause::from_rcc_csr(rcc().csr().read().bits());
        rcc().csr().modify(|_, w| w.rmvf().set_bit());
        let boot = Boot { cause, retained: backup::load_latch(&mut Bkp) };

        let sensor = DualSwitch::new(In::<PA, 0>, SWITCH_KIND, In::<PA, 4>, SWITCH_KIND_B, SWITCH_TRAVEL_UM, DISCREPANCY_US)
            .with_supply(Out::<SUPPLY_PORT, SUPPLY_PIN>);
        let outputs = Outputs { k1: K1 {}, k2: K2 {}, escalation: Esc {} };
        match Firmware::after_reset(config(), boot, Tim2, sensor, outputs, In) {
            Ok(fw) => {
                // The log saved before the reset first, then this start's reset-cause event.
                let fw = fw.with_feedback(Edm::new(In::<PA, 2>, In::<PA, 3>)).with_saved_log(backup::load_log(&mut Bkp));
                retained_store(fw.retained());
                backup::store_log(&mut Bkp, fw.log());
                SAVED_SEQ.store(u32::from(fw.log().next_seq()), Relaxed);
                EDGE_FAST.store(fw.edge_stops_directly(), Relaxed);
                // SAFETY: once, before SysTick and the bookkeeping interrupt are enabled below.
                unsafe { FW.init(fw) }
            }
            Err(e) => {
                defmt::error!("bad configuration: {=str}", e.message());
                loop {
                    emergency_stop();
                }
            }
        }

        // EXTI0 <- PA0, EXTI4 <- PA4 (EXTICRx field 0 is port A), both edges.
        // SAFETY (both): field value 0 selects port A.
        syscfg().exticr1().modify(|_, w| unsafe { w.exti0().bits(0) });
        syscfg().exticr2().modify(|_, w| unsafe { w.exti4().bits(0) });
        exti().rtsr().modify(|_, w| w.tr0().set_bit().tr4().set_bit());
        exti().ftsr().modify(|_, w| w.tr0().set_bit().tr4().set_bit());
        exti().imr().modify(|_, w| w.mr0().set_bit().mr4().set_bit());
        // The edge above the tick and the bookkeeping, set before any of them can run.
        // SAFETY: priorities only; the sharing they allow is the one described at the top.
        unsafe {
            cp.NVIC.set_priority(Exti0, PRIO_EDGE);
            cp.NVIC.set_priority(Exti4, PRIO_EDGE);
            cp.NVIC.set_priority(Book, PRIO_TICK);
            cp.NVIC.set_priority(Tim5, PRIO_TICK);
            cp.SCB.set_priority(SystemHandler::SysTick, PRIO_TICK);
        }
        // SAFETY: the bookkeeping's data (FW) is initialised; EXTI0 uses atomics only.
        unsafe {
            NVIC::unmask(Book);
            NVIC::unmask(Tim5);
            NVIC::unmask(Exti0);
            NVIC::unmask(Exti4);
        }

        super::board_avoid::init(&mut cp.NVIC);
        cp.SYST.set_clock_source(SystClkSource::Core);
        cp.SYST.set_reload(CORE_HZ / 1_000_000 * TICK_US - 1);
        cp.SYST.clear_current();
        cp.SYST.enable_interrupt();
        cp.SYST.enable_counter();
        defmt::info!("flinch board up, tick {=u32} us", TICK_US);
        let mut drain = LogDrain { copy: EventLog::new(), state: None, saved_seq: u16::try_from(SAVED_SEQ.load(Relaxed)).ok() };
        // The periodic self-tests, one step a tick, after the drain (`support/board_diag.rs`).
        let mut diag = crate::diag::Diag::new();
        // The bench plays the world in thread mode and runs the drain and the self-tests on every pass.
        #[cfg(feature = "qemu-io")]
        super::bench::run_scenario(|| tim2().cnt().read().bits(), || {
            drain.run();
            diag.run();
        });
        #[cfg(not(feature = "qemu-io"))]
        loop {
            drain.run();
            diag.run();
            cortex_m::asm::wfi();
        }
    }

    #[derive(Copy, Clone)]
    struct Exti0;
    // SAFETY: 6 is EXTI0's position in the STM32F407 vector table (RM0090 Table 61).
    unsafe impl cortex_m::interrupt::InterruptNumber for Exti0 {
        fn number(self) -> u16 {
            EXTI0_IRQ
        }
    }

    #[derive(Copy, Clone)]
    struct Exti4;
    // SAFETY: 10 is EXTI4's position in the STM32F407 vector table (RM0090 Table 61).
    unsafe impl cortex_m::interrupt::InterruptNumber for Exti4 {
        fn number(self) -> u16 {
            EXTI4_IRQ
        }
    }

    #[derive(Copy, Clone)]
    struct Tim5;
    // SAFETY: 50 is TIM5's position in the STM32F407 vector table (RM0090 Table 61).
    unsafe impl cortex_m::interrupt::InterruptNumber for Tim5 {
        fn number(self) -> u16 {
            TIM5_IRQ
        }
    }

    #[derive(Copy, Clone)]
    struct Book;
    // SAFETY: 53 is UART5's position in the STM32F407 vector table; UART5 is not enabled.
    unsafe impl cortex_m::interrupt::InterruptNumber for Book {
        fn number(self) -> u16 {
            BOOK_IRQ
        }
    }

    /// A switch edge (EXTI0: channel A, EXTI4: channel B; `line` is its EXTI_PR bit), the highest
    /// interrupt priority: the detect-to-stop path. Unfiltered and either channel at its trip level
    /// (1oo2): both stop channels written low first (K1, then K2, each on its own port, whatever the
    /// state: a stop write is harmless when stopped, and needs no read of the outputs, which a frozen
    /// port would falsify), then this line's pending bit, then the hand-over. Everything else is the
    /// bookkeeping's, at the tick's priority (`Firmware::edge_stopped` commits a trip only if armed).
    #[inline(always)]
    fn edge(line: u32) {
        let idr = idr(PA);
        if EDGE_FAST.load(Relaxed) && (idr & 1 == TRIP_A || idr & (1 << 4) == TRIP_B) {
            bsrr(K1_PORT, 1 << (K1_PIN + 16)); // the stop, channel 1
            bsrr(K2_PORT, 1 << (K2_PIN + 16)); // channel 2
            #[cfg(feature = "qemu-io")]
            crate::bench::edge_stop_written();
            // SAFETY (both PR writes): one pending bit, write 1 to clear.
            exti().pr().write(|w| unsafe { w.bits(line) }); // right after the stop writes: a new edge from here on pends again
            EDGE_AT.store(tim2().cnt().read().bits(), Relaxed);
            EDGE_STOPPED.store(true, Relaxed);
        } else {
            exti().pr().write(|w| unsafe { w.bits(line) });
        }
        NVIC::pend(Book);
        #[cfg(feature = "qemu-io")]
        crate::bench::edge_end();
    }

    /// The bookkeeping of an edge, at SysTick's priority.
    fn book() {
        #[cfg(feature = "qemu-io")]
        let t0 = crate::bench::start();
        // SAFETY: same priority as SysTick (the only other user), initialised before unmasking.
        let fw = unsafe { FW.get() };
        if EDGE_STOPPED.swap(false, Relaxed) {
            fw.edge_stopped(Micros(EDGE_AT.load(Relaxed)));
        } else {
            fw.on_edge();
        }
        retained_store(fw.retained());
        crate::held::publish(fw.state());
        #[cfg(feature = "qemu-io")]
        crate::bench::note(&crate::bench::W_BOOK, t0, true);
    }

    #[exception]
    fn SysTick() {
        #[cfg(feature = "qemu-io")]
        let t0 = crate::bench::start();
        // SAFETY: same priority as the bookkeeping (the only other user), initialised before SysTick
        // was enabled.
        let fw = unsafe { FW.get() };
        fw.tick();
        // A periodic self-test (thread mode, `board_diag.rs`) failed: latch it.
        if let Some((check, detail)) = crate::diag::take_failure() {
            fw.diagnostic_failed(check, detail);
        }
        crate::diag::TICKS.fetch_add(1, Relaxed);
        retained_store(fw.retained());
        crate::held::publish(fw.state());
        // Every tick counts for the avoidance step's deadline (and pends the step).
        let step_on_time = super::board_avoid::on_tick();
        // Feed the watchdog only if the tick ran, the firmware is healthy and armed or healthy and
        // stopped (every latched fault starves it: the reset releases the pins), no fault handler
        // has run, and the avoidance step kept its deadline (SAFETY: the reload key).
        if fw.feeds_watchdog() && step_on_time && !STARVE.load(Relaxed) {
            iwdg().kr().write(|w| unsafe { w.key().bits(0xAAAA) });
        }
        #[cfg(feature = "qemu-io")]
        crate::bench::note(&crate::bench::W_TICK, t0, true);
    }

    // ---- Vector table: the 82 STM32F407 interrupts, EXTI0 wired, the rest to DefaultHandler --------
    #[derive(Copy, Clone)]
    #[repr(C)]
    pub union Vector {
        handler: unsafe extern "C" fn(),
        reserved: usize,
    }
    extern "C" {
        fn DefaultHandler();
    }
    const DEFAULT: Vector = Vector { handler: DefaultHandler };
    const fn vectors() -> [Vector; 82] {
        let mut v = [DEFAULT; 82];
        v[EXTI0_IRQ as usize] = Vector { handler: exti0_entry };
        v[EXTI4_IRQ as usize] = Vector { handler: exti4_entry };
        v[BOOK_IRQ as usize] = Vector { handler: book_entry };
        v[TIM5_IRQ as usize] = Vector { handler: tim5_entry };
        v[super::board_avoid::USART1_IRQ as usize] = Vector { handler: super::board_avoid::usart1_entry };
        v[super::board_avoid::TIM3_IRQ as usize] = Vector { handler: super::board_avoid::tim3_entry };
        v
    }
    unsafe extern "C" fn exti0_entry() {
        edge(1 << 0)
    }
    unsafe extern "C" fn exti4_entry() {
        edge(1 << 4)
    }
    unsafe extern "C" fn tim5_entry() {
        #[cfg(feature = "qemu-io")]
        let t0 = crate::bench::start();
        lsi_capture();
        #[cfg(feature = "qemu-io")]
        crate::bench::note(&crate::bench::W_TIM5, t0, true);
    }
    unsafe extern "C" fn book_entry() {
        book()
    }
    #[link_section = ".vector_table.interrupts"]
    #[no_mangle]
    pub static __INTERRUPTS: [Vector; 82] = vectors();
}
