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
//! | stop out          | PD12 | high = energised = go; low = controlled stop (fit an external pull-down: a reset or dead MCU floats the pin) |
//! | escalation out    | PD13 | high = energised; low = category-0 stop                           |
//! | sensor supply out | PD14 | high = powered; switched off by the start-up stuck-input test     |
//!
//! Time: TIM2, a 32-bit counter at 1 MHz, is the firmware's `Clock`. SysTick interrupts every
//! `TICK_US` and calls `Firmware::tick`.
//!
//! Priorities (a bounded edge-to-stop): EXTI0, the switch edge, has the highest priority (0) and
//! preempts everything else. It does not touch the `Firmware` object: it reads the switch (IDR) and
//! whether the stop is energised (ODR: it is only while armed), writes the stop low through BSRR,
//! clears its pending bit, and pends the bookkeeping interrupt (UART5's line, unused otherwise),
//! which runs `Firmware::edge_stopped` (timestamp, budget, latch, log) or `Firmware::on_edge` at
//! SysTick's priority (0x80). SysTick and the bookkeeping share that priority, so `IsrCell`'s rule
//! (no two `&mut` at once, `support/isr_cell.rs`) holds between them; the edge shares only atomics.
//! The core runs on the 16 MHz HSI, the reset default: no PLL code to get wrong, and the detection
//! path is short enough at that speed (the QEMU build measures it in instructions).
//!
//! Failure handling: the independent watchdog (IWDG, LSI) is fed from the tick; a firmware that stops
//! ticking resets the MCU within about 8 ms, and the reset state de-energises the outputs. The panic,
//! HardFault and default (NMI, any unexpected interrupt) handlers write the stop and escalation pins
//! low before anything else and record `Cause::FaultHandler` in the retained latch.
//!
//! Start-up integrity (`flinch_firmware::integrity`): first in `main`, the stop, escalation and
//! sensor-supply pins driven low by register writes (no RAM used), then a March C- RAM test over
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
mod board {
    use super::isr_cell::IsrCell;
    use core::convert::Infallible;
    use core::ptr::{read_volatile, write_volatile};
    use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
    use cortex_m::peripheral::scb::SystemHandler;
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m::peripheral::NVIC;
    use cortex_m_rt::{entry, exception, ExceptionFrame};
    use defmt_rtt as _;
    use embedded_hal::digital::{ErrorType, InputPin, OutputPin};
    use flinch_firmware::option_bytes::{self, BorOutcome, OptionBytes};
    use flinch_firmware::{backup, integrity};
    use flinch_firmware::{
        BackupRam, Boot, EventLog, BudgetConfig, Cause, Clock, ClockCheck, Config, DualSwitch, Edm, Firmware, Micros, ResetCause, Retained,
        SwitchKind,
    };

    // ---- Registers: the `stm32f4` PAC (feature stm32f407, generated from ST's SVD; RM0090 Rev 19) ---
    use stm32f4::stm32f407 as pac;
    /// GPIOA's and GPIOD's base addresses (RM0090 sec. 2.3), as the pins' const-generic port; the
    /// registers behind them are the PAC's (`gpio`).
    const GPIOA: u32 = 0x4002_0000;
    const GPIOD: u32 = 0x4002_0C00;

    /// The PAC's register blocks. SAFETY (all of them): fixed peripheral addresses of this part,
    /// valid for the whole program; every access through them is a volatile register access.
    #[inline(always)]
    fn rcc() -> &'static pac::rcc::RegisterBlock {
        unsafe { &*pac::RCC::ptr() }
    }
    #[inline(always)]
    fn tim2() -> &'static pac::tim2::RegisterBlock {
        unsafe { &*pac::TIM2::ptr() }
    }
    #[inline(always)]
    fn iwdg() -> &'static pac::iwdg::RegisterBlock {
        unsafe { &*pac::IWDG::ptr() }
    }
    #[inline(always)]
    fn tim5() -> &'static pac::tim5::RegisterBlock {
        unsafe { &*pac::TIM5::ptr() }
    }
    #[inline(always)]
    fn exti() -> &'static pac::exti::RegisterBlock {
        unsafe { &*pac::EXTI::ptr() }
    }
    #[inline(always)]
    fn syscfg() -> &'static pac::syscfg::RegisterBlock {
        unsafe { &*pac::SYSCFG::ptr() }
    }
    #[inline(always)]
    fn flash() -> &'static pac::flash::RegisterBlock {
        unsafe { &*pac::FLASH::ptr() }
    }
    #[inline(always)]
    fn pwr() -> &'static pac::pwr::RegisterBlock {
        unsafe { &*pac::PWR::ptr() }
    }
    /// A GPIO port's registers (GPIOA..GPIOI share one layout, RM0090 sec. 8.4; `PORT` is GPIOA or
    /// GPIOD above). Only MODER/PUPDR (modify), IDR/ODR (read) and BSRR (write from 0) are used, so
    /// GPIOA's reset values in the PAC's type never leak into another port.
    #[inline(always)]
    fn gpio(port: u32) -> &'static pac::gpioa::RegisterBlock {
        unsafe { &*(port as *const pac::gpioa::RegisterBlock) }
    }
    const EXTI0_IRQ: u16 = 6; // RM0090 Table 61
    const EXTI4_IRQ: u16 = 10;
    /// The bookkeeping interrupt: UART5's line (RM0090 Table 61), pended by software only.
    const BOOK_IRQ: u16 = 53;
    /// TIM5's line (RM0090 Table 61): its channel 4 captures the LSI (the clock check's reference).
    const TIM5_IRQ: u16 = 50;
    /// NVIC priorities (upper 4 bits on the F407; lower number = more urgent).
    const PRIO_EDGE: u8 = 0x00;
    const PRIO_TICK: u8 = 0x80;

    /// The core clock (SysTick) and TIM2's input clock: the 16 MHz HSI on the board. QEMU 7.2's
    /// netduinoplus2 clocks the core at 168 MHz and its timers at 1 GHz whatever RCC says, so the
    /// `qemu-io` build scales both to keep a 1 MHz `Clock` and a `TICK_US` tick there.
    #[cfg(not(feature = "qemu-clock"))]
    const CORE_HZ: u32 = 16_000_000;
    #[cfg(not(feature = "qemu-clock"))]
    const TIM2_HZ: u32 = 16_000_000;
    #[cfg(feature = "qemu-clock")]
    const CORE_HZ: u32 = 168_000_000;
    #[cfg(feature = "qemu-clock")]
    const TIM2_HZ: u32 = 1_000_000_000;
    const TICK_US: u32 = 1_000;

    // ---- The three pin accesses: GPIO in the production build, the QEMU bench's RAM with
    // `qemu-io` (QEMU 7.2 does not model the F405's GPIO; `support/board_bench.rs`) -------------------
    /// A port's input register.
    #[inline(always)]
    fn idr(port: u32) -> u32 {
        #[cfg(not(feature = "qemu-io"))]
        return gpio(port).idr().read().bits();
        #[cfg(feature = "qemu-io")]
        return if port == GPIOA { super::bench::PINS.load(Relaxed) } else { gpio(port).idr().read().bits() };
    }
    /// A port's output register (the stop's read-back).
    #[inline(always)]
    fn odr(port: u32) -> u32 {
        #[cfg(not(feature = "qemu-io"))]
        return gpio(port).odr().read().bits();
        #[cfg(feature = "qemu-io")]
        return if port == GPIOD { super::bench::ODR_D.load(Relaxed) } else { gpio(port).odr().read().bits() };
    }
    /// A write to a port's bit set/reset register.
    #[inline(always)]
    fn bsrr(port: u32, v: u32) {
        // SAFETY: BSRR takes any bit pattern (a set or reset request per pin).
        gpio(port).bsrr().write(|w| unsafe { w.bits(v) });
        #[cfg(feature = "qemu-io")]
        if port == GPIOD {
            super::bench::bsrr(v);
        }
    }

    // ---- Pins: zero-sized, the port and pin are constants, so a write is a single `str` ------------
    /// A push-pull output on `PORT`, pin `N`, written through BSRR (atomic, no read-modify-write).
    pub struct Out<const PORT: u32, const N: u32>;
    impl<const PORT: u32, const N: u32> ErrorType for Out<PORT, N> {
        type Error = Infallible;
    }
    impl<const PORT: u32, const N: u32> OutputPin for Out<PORT, N> {
        #[inline(always)]
        fn set_low(&mut self) -> Result<(), Infallible> {
            bsrr(PORT, 1 << (N + 16));
            Ok(())
        }
        #[inline(always)]
        fn set_high(&mut self) -> Result<(), Infallible> {
            bsrr(PORT, 1 << N);
            Ok(())
        }
    }
    /// An input on `PORT`, pin `N`, read from IDR.
    pub struct In<const PORT: u32, const N: u32>;
    impl<const PORT: u32, const N: u32> ErrorType for In<PORT, N> {
        type Error = Infallible;
    }
    impl<const PORT: u32, const N: u32> InputPin for In<PORT, N> {
        #[inline(always)]
        fn is_high(&mut self) -> Result<bool, Infallible> {
            Ok(idr(PORT) & (1 << N) != 0)
        }
        #[inline(always)]
        fn is_low(&mut self) -> Result<bool, Infallible> {
            Ok(idr(PORT) & (1 << N) == 0)
        }
    }

    /// TIM2 as a 1 MHz, 32-bit free-running counter.
    pub struct Tim2;
    impl Clock for Tim2 {
        #[inline(always)]
        fn now(&mut self) -> Micros {
            Micros(tim2().cnt().read().bits())
        }
        /// LSI periods counted by TIM5's channel 4 (`lsi_capture`): the independent reference.
        fn reference_ticks(&mut self) -> Option<u32> {
            Some(LSI_PERIODS.load(Relaxed))
        }
    }

    /// The clock check's reference: the LSI (the IWDG's own RC oscillator, independent of the HSI
    /// behind TIM2 and SysTick). The F4 can only route it to TIM5's channel 4 capture input
    /// (`TIM5_OR.TI4_RMP = 01`, RM0090 sec. 18.4.21), which timestamps edges and does not count
    /// them; the counting adapter is the capture interrupt: every 8th LSI rising edge
    /// (`IC4PSC = /8`) captures, and `lsi_capture` adds 8 (16 if the capture before was overwritten).
    /// 4 kHz of a short interrupt at the tick's priority, below the edge.
    static LSI_PERIODS: AtomicU32 = AtomicU32::new(0);
    /// Nominal LSI, hertz; DS8626 specifies 17 to 47 kHz, hence the wide tolerance in `config`.
    const LSI_HZ: u32 = 32_000;

    fn lsi_capture() {
        let t = tim5();
        let _ = t.ccr4().read(); // reading CCR4 clears CC4IF
        let sr = t.sr().read().bits();
        let mut n = 8;
        if sr & (1 << 12) != 0 {
            // CC4OF: a capture was overwritten before this one was read: 8 more periods.
            n += 8;
            // SAFETY: rc_w0 flags: write 0 to CC4OF only, 1 elsewhere leaves the others.
            t.sr().write(|w| unsafe { w.bits(!(1 << 12)) });
        }
        LSI_PERIODS.fetch_add(n, Relaxed);
    }

    type Switch = DualSwitch<In<GPIOA, 0>, In<GPIOA, 4>, Out<GPIOD, 14>>;
    type Fw = Firmware<Tim2, Switch, Out<GPIOD, 12>, Out<GPIOD, 13>, In<GPIOA, 1>, 16, Edm<In<GPIOA, 2>, In<GPIOA, 3>>>;
    static FW: IsrCell<Fw> = IsrCell::new();

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

    /// Drop both outputs with raw register writes (usable from any context, even before init).
    #[inline(always)]
    fn emergency_stop() {
        bsrr(GPIOD, (1 << (12 + 16)) | (1 << (13 + 16)));
    }

    // ---- Start-up integrity checks (`flinch_firmware::integrity`) ---------------------------------
    /// The CRC-32 of the flash image with this word counted as zeros; written into the ELF after the
    /// link by `cargo xtask` (`patch_flash_crc`). An image that was not patched (0) or was changed
    /// after patching fails the check and never arms.
    #[no_mangle]
    #[used]
    static FLINCH_FLASH_CRC: u32 = 0;
    /// The production build checks its image with the production seed; every `qemu-clock` build
    /// (the `qemu-io` bench and the serial test: their tick is scaled for QEMU), which must never run
    /// the machine, is patched (xtask) and checked with its own, so its stored CRC fails the
    /// production check (`integrity::Seed`; host test `a_bench_image_fails_the_production_check`).
    #[cfg(not(feature = "qemu-clock"))]
    const FLASH_SEED: integrity::Seed = integrity::Seed::Production;
    #[cfg(feature = "qemu-clock")]
    const FLASH_SEED: integrity::Seed = integrity::Seed::QemuBench;

    extern "C" {
        // cortex-m-rt's linker script (link.x): .data's run and load addresses, the end of .bss.
        static mut __sdata: u32;
        static mut __edata: u32;
        static mut __ebss: u32;
        static __sidata: u32;
    }
    const FLASH_START: u32 = 0x0800_0000;
    const RAM_START: u32 = 0x2000_0000;
    /// Stack kept out of the RAM test: main's and the test's own frames live there.
    const STACK_KEEP: u32 = 1024;

    /// The flash image: the vector table, .text and .rodata (contiguous from the start of flash, as
    /// cortex-m-rt's link.x lays them out and xtask checks), then .data's load image.
    fn flash_crc_ok() -> bool {
        let end = core::ptr::addr_of!(__sidata) as u32 + (core::ptr::addr_of!(__edata) as u32 - core::ptr::addr_of!(__sdata) as u32);
        let crc_at = core::ptr::addr_of!(FLINCH_FLASH_CRC) as u32;
        // SAFETY: flash from its start to the end of .data's load image: mapped, read-only,
        // never written while running.
        let image = unsafe { core::slice::from_raw_parts(FLASH_START as *const u8, (end - FLASH_START) as usize) };
        // SAFETY: a static in flash; volatile so that the compiler does not fold in the 0 it was
        // linked with (xtask patched the ELF afterwards).
        let stored = unsafe { read_volatile(core::ptr::addr_of!(FLINCH_FLASH_CRC)) };
        integrity::image_crc_seeded(image, (crc_at - FLASH_START) as usize, FLASH_SEED) == stored
    }

    /// March C- with four data backgrounds over the RAM the firmware will use: .data and .bss, and
    /// the stack region below the frames in use now (flip-link puts the stack at the bottom of RAM);
    /// not the top `STACK_KEEP` bytes of the stack (the latch and the log are in backup SRAM, not RAM).
    /// Restores .data from its load image afterwards (the test leaves zeros, which is .bss's value).
    ///
    /// # Safety
    /// Only as the first thing in `main`: no reference to a static may be live.
    unsafe fn ram_test() -> bool {
        let sdata = core::ptr::addr_of_mut!(__sdata);
        let data_words = (core::ptr::addr_of!(__edata) as usize - sdata as usize) / 4;
        let ram_words = (core::ptr::addr_of!(__ebss) as usize - sdata as usize) / 4;
        let sp = cortex_m::register::msp::read();
        let stack_words = (sp.saturating_sub(STACK_KEEP).saturating_sub(RAM_START) / 4) as usize;
        let statics_ok = integrity::march_c_minus(&mut integrity::RawRam::new(sdata, ram_words), &integrity::BACKGROUNDS).is_ok();
        let stack_ok = integrity::march_c_minus(&mut integrity::RawRam::new(RAM_START as *mut u32, stack_words), &integrity::BACKGROUNDS).is_ok();
        let sidata = core::ptr::addr_of!(__sidata);
        for i in 0..data_words {
            write_volatile(sdata.wrapping_add(i), read_volatile(sidata.wrapping_add(i)));
        }
        statics_ok && stack_ok
    }

    /// What failed at start-up: the [`Cause::SelfCheck`] event's flags.
    const SELF_RAM: u8 = 1;
    const SELF_FLASH: u8 = 2;
    const SELF_BOR: u8 = 3;
    /// A `qemu-clock` image (bench or serial test) found real GPIO (it runs on silicon, not in QEMU).
    #[cfg(feature = "qemu-clock")]
    const SELF_NOT_QEMU: u8 = 4;

    /// The backup SRAM word the qemu-clock guard writes and reads back: past every record (the
    /// latch, the log, the BOR-pending mark at word 96), inside the 1 KB QEMU maps.
    #[cfg(feature = "qemu-clock")]
    const NOT_QEMU_PROBE_AT: usize = BKPSRAM_WORDS - 1;
    #[cfg(feature = "qemu-clock")]
    const NOT_QEMU_PROBE: u32 = 0x5153_4D55; // "QEMU"

    /// The qemu-clock guard: `None` only when two independent checks both say "QEMU". (1) GPIOD's
    /// MODER, written by `early_outputs_low` after the clock enable and a DSB, reads back the
    /// outputs on silicon and 0 in QEMU 7.2 (GPIO not modelled). (2) A test word written to the
    /// backup SRAM (clocked and opened by `backup_on`, with DSBs) reads back on silicon and 0 in QEMU
    /// (unimplemented device: writes ignored). Any non-zero read of either stops: on silicon a lost
    /// write leaves the other check, and a backup SRAM whose write was lost reads its old (power-on:
    /// arbitrary) content. The flags' detail: bit 0 = MODER, bit 1 = backup SRAM.
    #[cfg(feature = "qemu-clock")]
    fn not_qemu() -> Option<i32> {
        let moder = gpio(GPIOD).moder().read().bits() & (0b11_11_11 << 24) != 0;
        let mut b = Bkp;
        b.write(NOT_QEMU_PROBE_AT, NOT_QEMU_PROBE);
        cortex_m::asm::dsb();
        let bkp = b.read(NOT_QEMU_PROBE_AT) != 0;
        let which = i32::from(moder) | (i32::from(bkp) << 1);
        if which != 0 {
            Some(which)
        } else {
            None
        }
    }

    /// The option bytes through the flash interface's registers (`flinch_firmware::option_bytes`:
    /// BOR level 3 programmed once, error flags checked, verified at the next boot).
    struct OptionRegs;
    impl OptionBytes for OptionRegs {
        fn bor_level(&mut self) -> u8 {
            flash().optcr().read().bor_lev().bits()
        }
        fn status(&mut self) -> u32 {
            flash().sr().read().bits()
        }
        fn clear_status(&mut self, flags: u32) {
            // SAFETY: FLASH_SR's flags are write-1-to-clear; only error flags are passed.
            flash().sr().write(|w| unsafe { w.bits(flags & option_bytes::SR_ERRORS) });
        }
        fn unlock(&mut self) {
            // SAFETY (both): the option-byte unlock keys of RM0090 sec. 3.6.2.
            flash().optkeyr().write(|w| unsafe { w.optkeyr().bits(0x0819_2A3B) });
            flash().optkeyr().write(|w| unsafe { w.optkeyr().bits(0x4C5D_6E7F) });
        }
        fn program_bor(&mut self, level: u8) {
            // SAFETY: a 2-bit BOR_LEV value; read-modify-write keeps RDP, WRP and the user bits.
            flash().optcr().modify(|_, w| unsafe { w.bor_lev().bits(level) });
            flash().optcr().modify(|_, w| w.optstrt().set_bit());
        }
        fn lock(&mut self) {
            flash().optcr().modify(|_, w| w.optlock().set_bit());
        }
    }
    /// The bound on the wait for FLASH_SR.BSY after OPTSTRT: status reads, about 10 cycles each at
    /// 16 MHz, so about 10 s (an option-byte write takes milliseconds).
    const BOR_BUSY_SPINS: u32 = 16_000_000;

    // ---- Backup SRAM: the latch and the event log across resets (`flinch_firmware::backup`) -----
    /// The backup SRAM (RM0090 sec. 2.3 and 5.1.2): 4 KB at 0x4002_4000 in the backup domain, which
    /// no system reset clears (watchdog, software, pin, a brown-out with VDD back). Only its first
    /// 1 KB is used (the records need 72 words): QEMU 7.2's netduinoplus2 maps 1 KB there, as an
    /// unimplemented device (reads 0, writes ignored).
    const BKPSRAM: u32 = 0x4002_4000;
    const BKPSRAM_WORDS: usize = 256;

    /// The backup SRAM as the library's `BackupRam`.
    struct Bkp;
    impl BackupRam for Bkp {
        fn len(&self) -> usize {
            BKPSRAM_WORDS
        }
        fn read(&mut self, i: usize) -> u32 {
            if i >= BKPSRAM_WORDS {
                return 0;
            }
            // SAFETY: a word in the backup SRAM's first KB, clocked by `backup_on`.
            unsafe { read_volatile((BKPSRAM as *const u32).wrapping_add(i)) }
        }
        fn write(&mut self, i: usize, v: u32) {
            if i < BKPSRAM_WORDS {
                // SAFETY: as for `read`; DBP set by `backup_on`.
                unsafe { write_volatile((BKPSRAM as *mut u32).wrapping_add(i), v) }
            }
        }
    }

    /// Clock the backup SRAM and open the backup domain to writes: PWREN, BKPSRAMEN, PWR_CR.DBP
    /// (RM0090 sec. 5.1.2). Register writes only, no RAM: usable before the RAM test has passed and
    /// from the fault handlers. The backup regulator (BRE) is left off: without a VBAT cell the
    /// content does not survive a power cycle, and what a power-on leaves fails the records' CRCs,
    /// i.e. reads as a clean power-on (`backup.rs`).
    fn backup_on() {
        rcc().apb1enr().modify(|_, w| w.pwren().set_bit());
        rcc().ahb1enr().modify(|_, w| w.bkpsramen().set_bit());
        // STM32F40x errata (ES0182, "Delay after an RCC peripheral clock enabling"): an access right
        // after the enable can be lost; the DSB completes the enable first.
        cortex_m::asm::dsb();
        pwr().cr().modify(|_, w| w.dbp().set_bit());
        cortex_m::asm::dsb();
    }

    /// The log's `next_seq` as `main` stored it (before any interrupt runs), for the drain.
    static SAVED_SEQ: AtomicU32 = AtomicU32::new(u32::MAX);

    /// The last latch written to the backup SRAM (cause, boot count): a store only when it changes,
    /// so the tick writes 4 words of backup SRAM only on a change of the latch.
    static STORED_CAUSE: AtomicU32 = AtomicU32::new(u32::MAX);
    static STORED_BOOTS: AtomicU32 = AtomicU32::new(u32::MAX);

    fn retained_store(r: Retained) {
        // Called from SysTick and the bookkeeping, which share one priority (EXTI0 never calls it).
        if STORED_CAUSE.load(Relaxed) == r.words[1] && STORED_BOOTS.load(Relaxed) == r.words[2] {
            return;
        }
        backup::store_latch(&mut Bkp, r);
        STORED_CAUSE.store(r.words[1], Relaxed);
        STORED_BOOTS.store(r.words[2], Relaxed);
    }

    /// The boot count of the record in the backup SRAM (0 if there is none).
    fn stored_boots() -> u32 {
        backup::load_latch(&mut Bkp).decode().map_or(0, |(_, n)| n)
    }

    /// A fault handler ran: outputs low first, then latch `FaultHandler` for the next start.
    #[inline(always)]
    fn fault_handler_stop() {
        emergency_stop();
        backup_on();
        backup::store_latch(&mut Bkp, Retained::new(Some(Cause::FaultHandler), stored_boots()));
    }

    /// A start-up integrity check failed: outputs low, the `SelfCheck` latch and an event (`what`,
    /// `detail`) in the backup SRAM, then stopped for good. Nothing can re-arm: the IWDG is started
    /// only after these checks (so no watchdog reset re-runs them), no interrupt is enabled, and no
    /// `Firmware` exists; only a power cycle or the NRST pin starts the part again, and that start
    /// is latched by the record until a reset press. Uses no static: after a failed RAM test
    /// .data and .bss hold test patterns.
    fn integrity_failed(what: u8, detail: i32) -> ! {
        emergency_stop();
        backup_on();
        let mut b = Bkp;
        backup::store_latch(&mut b, Retained::new(Some(Cause::SelfCheck), stored_boots()));
        let mut log: EventLog<16> = backup::load_log(&mut b).unwrap_or_default();
        log.push(Cause::SelfCheck, what, Micros(0), Micros(0), detail);
        backup::store_log(&mut b, &log);
        loop {
            emergency_stop();
            cortex_m::asm::wfi(); // no interrupt is enabled: sleeps for good
        }
    }

    /// Before anything else, by register writes that need no RAM: GPIOD clocked, the stop,
    /// escalation and sensor-supply pins written low (BSRR) and made outputs. A RAM test that fails
    /// or hangs from here on leaves the outputs driven low, not floating.
    #[inline(always)]
    fn early_outputs_low() {
        rcc().ahb1enr().modify(|_, w| w.gpioden().set_bit());
        // The errata's delay after an RCC clock enable (see `backup_on`): without it the MODER write
        // below can be lost on silicon, which would also blind the qemu-clock guard's MODER check.
        cortex_m::asm::dsb();
        // SAFETY: BSRR takes any pattern (reset PD12..14); MODER: two-bit fields, 0b01 = output.
        gpio(GPIOD).bsrr().write(|w| unsafe { w.bits(0b111 << (12 + 16)) });
        gpio(GPIOD).moder().modify(|r, w| unsafe { w.bits((r.bits() & !(0b11_11_11 << 24)) | (0b01_01_01 << 24)) });
    }

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
        // Clocks for GPIOA, GPIOD, TIM2, SYSCFG.
        rcc().ahb1enr().modify(|_, w| w.gpioaen().set_bit().gpioden().set_bit());
        rcc().apb1enr().modify(|_, w| w.tim2en().set_bit().tim5en().set_bit());
        rcc().apb2enr().modify(|_, w| w.syscfgen().set_bit());
        cortex_m::asm::dsb(); // the errata's delay after an RCC clock enable (see `backup_on`)
        // Outputs low before they become outputs, so they never glitch high.
        emergency_stop();
        // SAFETY (the three): two-bit mode fields, 0b01 = output, 0b00 = input; pull 0b10 = down, 0b01 = up.
        gpio(GPIOD).moder().modify(|r, w| unsafe { w.bits((r.bits() & !(0b11_11_11 << 24)) | (0b01_01_01 << 24)) }); // PD12..14 output
        gpio(GPIOA).moder().modify(|r, w| unsafe { w.bits(r.bits() & !0x3FF) }); // PA0..PA4 input
        gpio(GPIOA).pupdr().modify(|r, w| unsafe { w.bits((r.bits() & !0x3FF) | 0b01_10_10_10_10) }); // PA0..PA3 pull-down, PA4 pull-up
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

        let sensor = DualSwitch::new(In::<GPIOA, 0>, SWITCH_KIND, In::<GPIOA, 4>, SWITCH_KIND_B, SWITCH_TRAVEL_UM, DISCREPANCY_US)
            .with_supply(Out::<GPIOD, 14>);
        match Firmware::after_reset(config(), boot, Tim2, sensor, Out, Out, In) {
            Ok(fw) => {
                // The log saved before the reset first, then this start's reset-cause event.
                let fw = fw.with_feedback(Edm::new(In::<GPIOA, 2>, In::<GPIOA, 3>)).with_saved_log(backup::load_log(&mut Bkp));
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
        // The bench plays the world in thread mode and runs the drain on every pass.
        #[cfg(feature = "qemu-io")]
        super::bench::run_scenario(|| tim2().cnt().read().bits(), || drain.run());
        #[cfg(not(feature = "qemu-io"))]
        loop {
            drain.run();
            cortex_m::asm::wfi();
        }
    }

    /// Logging from thread mode only. The library's own messages are compiled out on the board
    /// (`DEFMT_LOG` in firmware/.cargo/config.toml: `flinch_firmware=off`), because they would run in
    /// the tick and the bookkeeping interrupts; instead the tick and the bookkeeping fill the
    /// firmware's event log (a fixed 16-entry ring, `EventLog`) and this drain, in thread mode between
    /// ticks, copies the new entries and the state out under a priority ceiling (BASEPRI = the tick's
    /// priority: the tick and the bookkeeping cannot run meanwhile, the edge interrupt still can) and
    /// logs them afterwards, with every interrupt enabled. defmt-rtt runs with `drop-on-contention`
    /// (no critical section: logging never masks the edge) and starts non-blocking (a full buffer
    /// truncates the message; only an attached probe-rs switches it to blocking).
    struct LogDrain {
        /// The drain's own copy of the firmware's log, brought up to date from a snapshot of the new
        /// events only (`EventLog::snapshot`/`follow`; its cursor is `None` until the first one, so
        /// the whole restored log is new then; sequence numbers compare wrap-safely and continue
        /// across resets). The backup SRAM store is made from this copy, with interrupts enabled.
        copy: EventLog<16>,
        state: Option<flinch_firmware::State>,
        /// The log's `next_seq` when it was last written to the backup SRAM.
        saved_seq: Option<u16>,
    }

    impl LogDrain {
        fn run(&mut self) {
            // SAFETY: BASEPRI = PRIO_TICK masks SysTick and the bookkeeping, FW's only other users
            // (the edge, at priority 0, never touches FW), so this is the one reference meanwhile.
            // Masked: at most DRAIN_BATCH new events (usually none), two counters and the state; this
            // section is measured as `drain_masked` (`src/bin/qemu.rs`, README). A burst of events is
            // taken over a few runs (one per interrupt), so it reaches the backup SRAM a few ticks
            // later (the latch is stored at once by the tick and the bookkeeping).
            let (snap, state) = unsafe {
                cortex_m::register::basepri::write(PRIO_TICK);
                let fw = FW.get();
                let snap = fw.log().snapshot(self.copy.cursor(), flinch_firmware::event_log::DRAIN_BATCH);
                let state = fw.state();
                cortex_m::register::basepri::write(0);
                (snap, state)
            };
            self.copy.follow(&snap);
            // The log into the backup SRAM, with every interrupt enabled (the latch is stored by the
            // tick and the bookkeeping themselves, 4 words, at once). The drain runs after every
            // interrupt (`wfi`), so an event reaches the backup SRAM within a few ticks; a reset in the
            // middle of the store loses the log (its CRC), never the latch (`backup.rs`).
            // Only a copy that has caught up is stored: a partial one (a burst taken one event a
            // run) would replace a whole record with a prefix of it.
            if snap.complete && self.saved_seq != Some(self.copy.next_seq()) {
                backup::store_log(&mut Bkp, &self.copy);
                self.saved_seq = Some(self.copy.next_seq());
            }
            let batch = &snap.new;
            for e in batch {
                defmt::warn!(
                    "event {=u16}: {=str} flags {=u8:#x} at {=u32} us (first seen {=u32} us), travel {=i32} um",
                    e.seq,
                    e.cause.name(),
                    e.flags,
                    e.at.0,
                    e.first_seen.0,
                    e.travel_um
                );
            }
            if self.state != Some(state) {
                self.state = Some(state);
                match state {
                    flinch_firmware::State::SelfTest(_) => defmt::info!("state: self-test"),
                    flinch_firmware::State::Armed => defmt::info!("state: armed"),
                    flinch_firmware::State::Tripped => defmt::warn!("state: tripped (stopped)"),
                    flinch_firmware::State::Fault(c) => defmt::warn!("state: fault {=str} (stopped)", c.name()),
                }
            }
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

    /// A switch edge (EXTI0: channel A, EXTI4: channel B; `line` is its EXTI_PR bit), highest
    /// priority: the detect-to-stop path. Armed (the stop reads back energised), unfiltered and either
    /// channel at its trip level (1oo2): the stop write first, then this line's pending bit, then the
    /// hand-over. Everything else is the bookkeeping's, at the tick's priority.
    #[inline(always)]
    fn edge(line: u32) {
        let idr = idr(GPIOA);
        if EDGE_FAST.load(Relaxed)
            && odr(GPIOD) & (1 << 12) != 0
            && (idr & 1 == TRIP_A || idr & (1 << 4) == TRIP_B)
        {
            bsrr(GPIOD, 1 << (12 + 16)); // the stop
            // SAFETY (both PR writes): one pending bit, write 1 to clear.
            exti().pr().write(|w| unsafe { w.bits(line) }); // right after the stop write: a new edge from here on pends again
            EDGE_AT.store(tim2().cnt().read().bits(), Relaxed);
            EDGE_STOPPED.store(true, Relaxed);
        } else {
            exti().pr().write(|w| unsafe { w.bits(line) });
        }
        NVIC::pend(Book);
    }

    /// The bookkeeping of an edge, at SysTick's priority.
    fn book() {
        // SAFETY: same priority as SysTick (the only other user), initialised before unmasking.
        let fw = unsafe { FW.get() };
        if EDGE_STOPPED.swap(false, Relaxed) {
            fw.edge_stopped(Micros(EDGE_AT.load(Relaxed)));
        } else {
            fw.on_edge();
        }
        retained_store(fw.retained());
    }

    #[exception]
    fn SysTick() {
        // SAFETY: same priority as the bookkeeping (the only other user), initialised before SysTick
        // was enabled.
        let fw = unsafe { FW.get() };
        fw.tick();
        retained_store(fw.retained());
        // The tick ran and the avoidance step kept its deadline: feed the watchdog (SAFETY: the reload key).
        if super::board_avoid::on_tick() {
            iwdg().kr().write(|w| unsafe { w.key().bits(0xAAAA) });
        }
    }

    #[exception]
    unsafe fn HardFault(_ef: &ExceptionFrame) -> ! {
        fault_handler_stop();
        loop {
            cortex_m::asm::nop(); // the IWDG resets the part
        }
    }

    #[panic_handler]
    fn panic(_info: &core::panic::PanicInfo) -> ! {
        fault_handler_stop();
        defmt::error!("panic: outputs de-energised");
        loop {
            cortex_m::asm::nop(); // the IWDG resets the part
        }
    }

    /// NMI and every interrupt without a handler: de-energise and latch, then let the IWDG reset.
    #[exception]
    unsafe fn DefaultHandler(_irqn: i16) {
        fault_handler_stop();
        loop {
            cortex_m::asm::nop();
        }
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
        lsi_capture()
    }
    unsafe extern "C" fn book_entry() {
        book()
    }
    #[link_section = ".vector_table.interrupts"]
    #[no_mangle]
    pub static __INTERRUPTS: [Vector; 82] = vectors();
}
