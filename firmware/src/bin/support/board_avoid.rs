//! The avoidance step on the board (`flinch_firmware::avoidance::Link`): weights frames in over
//! USART1, one step every 10 ms (an interrupt on TIM3's line that the 1 ms SysTick tick pends every
//! tenth tick), a velocity frame with a status word back over USART1, and the step's deadline
//! watched by the tick that feeds the independent watchdog.
//!
//! Why the tick and not TIM3's own update: the step's period and its deadline are then counted on
//! one clock, so the deadline holds however the timers are clocked. (Measured: in QEMU 7.2 TIM3's
//! update came every 50-90 ms with a 10 ms setting, against SysTick's modelled rate.)
//!
//! Kept out of `board.rs` (it only calls [`init`] and [`on_tick`] and lists the two vectors).
//! Registers through the `stm32f4` PAC (`board_hw.rs`), as in the rest of the board.
//!
//! | signal | pin | notes |
//! |---|---|---|
//! | USART1 TX | PA9 (AF7) | velocity frames (44 bytes every 10 ms: 44,000 bit/s), 115,200 baud 8N1 |
//! | USART1 RX | PA10 (AF7) | weights frames, protocol v3 (5 x 5, 188 bytes, at 30 frames a second: 56,400 bit/s; 15 x 15, 988 bytes: at most 11 a second at this baud, see `BRR_115200_AT_16MHZ`) |
//!
//! Priorities: the switch edge (0x00) above everything; the USART (0x40) above the detection tick
//! (0x80), because its one-byte data register must be read within a character time (87 us at
//! 115,200 baud) and the tick must not delay that; the step (0xC0) below the tick, so the
//! detection never waits for the avoidance.
//!
//! * Receive: the USART interrupt (`flinch_firmware::serial_rx::service`: host-tested, including the
//!   overrun without a received byte, which it clears so the interrupt is not raised again above
//!   the tick) moves each byte into a 255-byte `heapless::spsc` queue (its producer is the
//!   interrupt's, its consumer the step's). A full queue drops the byte (read, counted): the
//!   receiver refuses the damaged frame by its CRC. The data register is always read, so the request
//!   is always withdrawn (turning RXNEIE off instead left QEMU 7.2's interrupt line high: an
//!   interrupt storm above the tick once the queue filled).
//! * The step (its interrupt, priority 0xC0): drains the queue into the receiver's ring (`Receiver::push`), runs
//!   `Link::step_with` with the detection firmware's latch (`board_held.rs`: held, i.e. any state
//!   but armed, the frame says `stopped: latched` with a zero command and the dead-reckoned
//!   position stands still; the step services at most `budget_bytes` of the ring), queues the velocity frame
//!   (a 63-byte `heapless::spsc` queue, one 44-byte frame: the step produces, the USART side consumes) and starts
//!   sending it: bytes go to the data register while TXE is set, the rest from the TXE interrupt. QEMU 7.2's `stm32f2xx_usart` sends synchronously, keeps TXE set and raises no TXE
//!   interrupt, so in QEMU the whole frame leaves from the step's loop; the TXE interrupt path runs
//!   on the part only.
//! * Deadline: every tick (1 ms) counts the ticks since the last step ended (`StepDeadline`); at 15
//!   (one and a half periods) the tick stops feeding the IWDG for good, and the IWDG resets the MCU
//!   within about 8 ms: the outputs de-energise (stop) and the board waits for a reset press, and
//!   no velocity frame comes any more (the robot side must stop on a missing frame). QEMU 7.2 does
//!   not model the IWDG; the deadline's logic is tested on the host (`avoidance::link` tests).
//! * Time: milliseconds for the receiver come from TIM2 (1 MHz, 32 bits), accumulated as
//!   differences, so they wrap at 2^32 ms like the receiver expects.

use super::isr_cell::IsrCell;
use crate::hw::{gpio, rcc, tim2, usart1, PA};
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering::Relaxed};
use cortex_m::peripheral::NVIC;
use flinch_firmware::avoidance::cell::board_config;
use flinch_firmware::avoidance::link::{encode_velocity, StepDeadline, BOARD_PERIOD_MS, VEL_LEN};
use flinch_firmware::avoidance::{BoardReal, Link};
use flinch_firmware::serial_rx::{self, UsartRx};
use heapless::spsc::{Consumer, Producer, Queue};

/// USART1's line (RM0090 Table 61).
pub const USART1_IRQ: u16 = 37;
/// The step's interrupt: TIM3's line (RM0090 Table 61), pended by the tick every `TICKS_PER_STEP`
/// ticks (TIM3 itself is not enabled).
pub const TIM3_IRQ: u16 = 29;
const STEP_IRQ: u16 = TIM3_IRQ;
const PRIO_USART: u8 = 0x40;
const PRIO_STEP: u8 = 0xC0;
/// The control period, ms (the library's, which `board_config` runs at).
const PERIOD_MS: u32 = BOARD_PERIOD_MS;
/// 16 MHz / 115,200 = 138.9: BRR 0x8B (mantissa 8, fraction 11/16), 115,108 baud (-0.08 %).
///
/// **Open:** the board's cell (`avoidance::cell::BOARD_CELL`: 15 x 15 frames of 988 bytes at
/// 30 Hz) needs 296,400 bit/s; at 115,200 baud it carries them at up to 11 Hz, and faster frames
/// build a backlog until the receiver forgets the weights (the robot stops: safe, but it stops the
/// work). A faster line brings more USART entries into the detection tick's window (14 bytes in
/// its 1.2 ms at 115,200, 55 at 460,800, against the 24 entries `xtask`'s worst-case stage and
/// `hal-sim`'s latency bound allow), so the baud goes up only with that bound re-derived.
const BRR_115200_AT_16MHZ: u16 = 0x8B;

#[inline(always)]
fn tim2_now_us() -> u32 {
    tim2().cnt().read().bits()
}

static LINK: IsrCell<Link<BoardReal>> = IsrCell::new();
/// Watched by the tick (`on_tick`), reset by the step.
/// 15 ticks between step ends, 1,000 (1 s) to the first.
static DEADLINE: StepDeadline = StepDeadline::new(15, 1000);
/// Ticks counted by `on_tick` (SysTick only).
static TICKS: AtomicU32 = AtomicU32::new(0);
/// The step is pended every this many ticks (1 ms each).
const TICKS_PER_STEP: u32 = PERIOD_MS;

// ---- The byte queues (`heapless::spsc`): split once in `init`, each end kept by the one context
// that uses it (`IsrCell`: one priority each, or the other masked) ------------------------------------
/// Receive: 255 bytes (heapless keeps one slot free). Produced by the USART interrupt, consumed by
/// the step.
const RXQ: usize = 256;
static mut RX_QUEUE: Queue<u8, RXQ> = Queue::new();
static RX_PROD: IsrCell<Producer<'static, u8>> = IsrCell::new();
static RX_CONS: IsrCell<Consumer<'static, u8>> = IsrCell::new();
/// Receive overruns (ORE) seen.
pub static RX_OVERRUN: AtomicU32 = AtomicU32::new(0);
/// Bytes dropped because the receive queue was full.
pub static RX_DROPPED: AtomicU32 = AtomicU32::new(0);

/// Transmit: 63 bytes, one velocity frame (36) at a time. Produced by the step, consumed by the
/// USART interrupt and by the step's start of sending, which runs with the USART masked (BASEPRI).
const TXQ: usize = 64;
static mut TX_QUEUE: Queue<u8, TXQ> = Queue::new();
static TX_PROD: IsrCell<Producer<'static, u8>> = IsrCell::new();
static TX_CONS: IsrCell<Consumer<'static, u8>> = IsrCell::new();
/// Velocity frames dropped because the previous one was still being sent.
pub static TX_DROPPED: AtomicU32 = AtomicU32::new(0);

/// Set up USART1 (PA9/PA10, 115,200 8N1, receive interrupt), the priorities of it and of the step's
/// interrupt, then unmask both. Call once from `main`, after the firmware is built and before
/// SysTick starts (the tick pends the step).
pub fn init(nvic: &mut NVIC) {
    // SAFETY (all the inits): once, before the interrupts that use them are unmasked below; each
    // queue is split once, and its `&'static mut` is the only reference ever made to it.
    unsafe {
        let mut link = Link::new(board_config());
        // This boot's byte (the boot count `main` stored in the backup SRAM before this runs, as it
        // keeps it: no second read of the SRAM, the boot's register trace unchanged): a weights frame
        // echoing an earlier boot's clock is not used.
        link.set_boot(crate::backup::STORED_BOOTS.load(Relaxed) as u8);
        LINK.init(link);
        let (p, c) = (*core::ptr::addr_of_mut!(RX_QUEUE)).split();
        RX_PROD.init(p);
        RX_CONS.init(c);
        let (p, c) = (*core::ptr::addr_of_mut!(TX_QUEUE)).split();
        TX_PROD.init(p);
        TX_CONS.init(c);
    }
    rcc().apb2enr().modify(|_, w| w.usart1en().set_bit());
    cortex_m::asm::dsb(); // STM32F40x errata: the delay after an RCC clock enable
    // PA9/PA10: AF7 = USART1 (AFRH fields 1 and 2), mode 10 = alternate function.
    // SAFETY (both): four-bit AF fields and two-bit mode fields of those two pins only.
    gpio(PA).afrh().modify(|r, w| unsafe { w.bits((r.bits() & !(0xFF << 4)) | (0x77 << 4)) });
    gpio(PA).moder().modify(|r, w| unsafe { w.bits((r.bits() & !(0b1111 << 18)) | (0b1010 << 18)) });
    // SAFETY: BRR is a 16-bit mantissa/fraction; the value above.
    usart1().brr().write(|w| unsafe { w.bits(BRR_115200_AT_16MHZ) });
    usart1().cr1().write(|w| w.ue().set_bit().te().set_bit().re().set_bit().rxneie().set_bit());
    // SAFETY: priorities, then unmask; the handlers' data is initialised above.
    unsafe {
        nvic.set_priority(Irq(USART1_IRQ), PRIO_USART);
        nvic.set_priority(Irq(TIM3_IRQ), PRIO_STEP);
        NVIC::unmask(Irq(USART1_IRQ));
        NVIC::unmask(Irq(TIM3_IRQ));
    }
}

/// From SysTick, every tick: `false` once the step has missed its deadline (and forever after):
/// the tick must then stop feeding the IWDG.
#[inline(always)]
pub fn on_tick() -> bool {
    let n = TICKS.load(Relaxed).wrapping_add(1);
    TICKS.store(n, Relaxed);
    if n.is_multiple_of(TICKS_PER_STEP) {
        NVIC::pend(Irq(STEP_IRQ));
    }
    DEADLINE.tick()
}

#[derive(Copy, Clone)]
struct Irq(u16);
// SAFETY: 29 and 37 are TIM3's and USART1's positions in the STM32F407 vector table.
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// USART1's receive side for `serial_rx::service`.
struct Usart1Rx;
impl UsartRx for Usart1Rx {
    fn status(&mut self) -> u32 {
        u32::from(usart1().sr().read().bits())
    }
    fn data(&mut self) -> u8 {
        usart1().dr().read().dr().bits() as u8
    }
}

/// The receive queue's producer as `serial_rx`'s sink.
struct RxQueue<'a>(&'a mut Producer<'static, u8>);
impl serial_rx::RxSink for RxQueue<'_> {
    fn room(&self) -> bool {
        self.0.ready()
    }
    fn push(&mut self, byte: u8) {
        let _ = self.0.enqueue(byte); // `room` said it fits
    }
}

/// USART1: received bytes into the queue; the velocity frame's next bytes out.
fn usart_irq() {
    #[cfg(feature = "qemu-io")]
    let t0 = crate::bench::start();
    // SAFETY: the receive producer's only user (the USART's priority), initialised before unmasking.
    let prod = unsafe { RX_PROD.get() };
    // Bounded: at most a queue's worth of bytes per entry (the model and the part offer one).
    let did = serial_rx::service(&mut Usart1Rx, &mut RxQueue(prod), RXQ as u32);
    if did.overruns != 0 {
        RX_OVERRUN.fetch_add(did.overruns, Relaxed);
    }
    if did.dropped != 0 {
        RX_DROPPED.fetch_add(did.dropped, Relaxed);
    }
    tx_pump();
    #[cfg(feature = "qemu-io")]
    {
        if did.bytes + did.dropped <= 1 {
            crate::bench::note(&crate::bench::W_USART_1, t0, false);
        }
        crate::bench::note(&crate::bench::W_USART, t0, true);
        // After the notes: an entry counts for the code it preempted, not for its own window.
        crate::bench::N_USART.fetch_add(1, Relaxed);
    }
}

/// Send queued bytes while the data register is empty; TXE interrupt on while bytes are left.
/// Only at the USART's priority (its interrupt, or the step under BASEPRI).
fn tx_pump() {
    // SAFETY: the transmit consumer is used only at the USART's priority (see above).
    let cons = unsafe { TX_CONS.get() };
    for _ in 0..TXQ {
        if !cons.ready() {
            usart1().cr1().modify(|_, w| w.txeie().clear_bit());
            return;
        }
        if usart1().sr().read().txe().bit_is_clear() {
            usart1().cr1().modify(|_, w| w.txeie().set_bit());
            return;
        }
        if let Some(b) = cons.dequeue() {
            // SAFETY: DR takes a 9-bit value; a byte.
            usart1().dr().write(|w| unsafe { w.dr().bits(u16::from(b)) });
        }
    }
}

/// Wrap-safe milliseconds from TIM2's microseconds (the step is the only caller).
struct Millis {
    last_us: u32,
    rem_us: u32,
    ms: u32,
}
static MILLIS: IsrCell<Millis> = IsrCell::new();
static MILLIS_INIT: AtomicBool = AtomicBool::new(false);

fn now_ms() -> u32 {
    let now = tim2_now_us();
    if !MILLIS_INIT.swap(true, Relaxed) {
        // SAFETY: the step is the only user, and this is its first call.
        unsafe { MILLIS.init(Millis { last_us: now, rem_us: 0, ms: 0 }) };
    }
    // SAFETY: only the step (one priority) uses MILLIS, initialised above.
    let m = unsafe { MILLIS.get() };
    let d = now.wrapping_sub(m.last_us).saturating_add(m.rem_us);
    m.last_us = now;
    m.ms = m.ms.wrapping_add(d / 1000);
    m.rem_us = d % 1000;
    m.ms
}

/// The step's interrupt (pended by the tick every 10 ms): one avoidance step.
fn step_irq() {
    let now = now_ms();
    // SAFETY: the step's interrupt is the link's and the receive consumer's only user; both were
    // initialised before it was unmasked.
    let (link, cons) = unsafe { (LINK.get(), RX_CONS.get()) };
    // The queue's bytes into the receiver's ring (at most one queue's worth, 64 at a time).
    let mut chunk = [0u8; 64];
    for _ in 0..(RXQ / 64 + 1) {
        let mut n = 0;
        for slot in chunk.iter_mut() {
            match cons.dequeue() {
                Some(b) => {
                    *slot = b;
                    n += 1;
                }
                None => break,
            }
        }
        if n == 0 {
            break;
        }
        link.receiver().push(chunk.get(..n).unwrap_or(&[]), now);
    }
    // The detection firmware's latch (published by the tick and the bookkeeping, `board_held.rs`):
    // held, the frame says `stopped: latched` with a zero command.
    let v = link.step_with(now, crate::held::held());
    let frame = encode_velocity(&v);
    #[cfg(feature = "qemu-io")]
    crate::bench::velocity_sent(v.status as u32, v.good);
    // SAFETY: the transmit producer's only user is the step.
    let prod = unsafe { TX_PROD.get() };
    if prod.capacity().saturating_sub(prod.len()) < VEL_LEN {
        TX_DROPPED.fetch_add(1, Relaxed);
    } else {
        for b in frame.iter() {
            let _ = prod.enqueue(*b); // room checked above: the consumer only takes bytes out
        }
    }
    with_usart_masked(tx_pump);
    DEADLINE.step_done();
}

/// Run `f` with BASEPRI at the USART's priority: the USART interrupt (and everything below it)
/// waits, the switch edge (priority 0x10) does not.
fn with_usart_masked(f: impl FnOnce()) {
    let old = cortex_m::register::basepri::read();
    // SAFETY: raising BASEPRI only masks; restored below.
    unsafe { cortex_m::register::basepri::write(PRIO_USART) };
    #[cfg(feature = "qemu-io")]
    let t0 = crate::bench::start();
    f();
    #[cfg(feature = "qemu-io")]
    crate::bench::note(&crate::bench::W_MASK_STEP, t0, false);
    // SAFETY: the value read above.
    unsafe { cortex_m::register::basepri::write(old) };
}

/// USART1's vector.
pub unsafe extern "C" fn usart1_entry() {
    usart_irq()
}
/// TIM3's vector.
pub unsafe extern "C" fn tim3_entry() {
    step_irq()
}
