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
//!
//! | signal | pin | notes |
//! |---|---|---|
//! | USART1 TX | PA9 (AF7) | velocity frames, 115,200 baud 8N1 |
//! | USART1 RX | PA10 (AF7) | weights frames (the 5 x 5 grid at 30 frames a second needs 39,600 bit/s, 15 x 15 at 10 a second 93,200: docs/avoidance.md) |
//!
//! Priorities: the switch edge (0x00) above everything; the USART (0x40) above the detection tick
//! (0x80), because its one-byte data register must be read within a character time (87 us at
//! 115,200 baud) and the tick must not delay that; the step (0xC0) below the tick, so the
//! detection never waits for the avoidance.
//!
//! * Receive: the USART interrupt moves each byte into a 256-byte single-producer single-consumer
//!   queue (the interrupt writes `RX_HEAD`, the step `RX_TAIL`). A full queue turns the receive
//!   interrupt off (the step turns it back on after draining); on the part the next bytes then
//!   overrun (ORE, counted) and the receiver refuses the damaged frame by its CRC. In QEMU the model
//!   holds the input meanwhile (it offers a byte only when RXNE is clear).
//! * The step (its interrupt, priority 0xC0): drains the queue into the receiver's ring (`Receiver::push`), runs
//!   `Link::step` (which services at most `budget_bytes` of the ring), queues the velocity frame and
//!   starts sending it: bytes go to the data register while TXE is set, the rest from the TXE
//!   interrupt. QEMU 7.2's `stm32f2xx_usart` sends synchronously, keeps TXE set and raises no TXE
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
use core::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering::{Acquire, Relaxed, Release}};
use cortex_m::peripheral::NVIC;
use flinch_firmware::avoidance::link::{board_config, encode_velocity, StepDeadline, BOARD_PERIOD_MS, VEL_LEN};
use flinch_firmware::avoidance::{BoardReal, Link};

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
const BRR_115200_AT_16MHZ: u32 = 0x8B;

// Registers by address (RM0090 sec. 2.3 memory map; the register offsets of secs. 6.3, 8.4, 18.4
// and 30.6), 32-bit volatile accesses.
const RCC_APB2ENR: u32 = 0x4002_3800 + 0x44;
const GPIOA_MODER: u32 = 0x4002_0000;
const GPIOA_AFRH: u32 = 0x4002_0000 + 0x24;
const TIM2_CNT: u32 = 0x4000_0000 + 0x24;
const USART1: u32 = 0x4001_1000;
const USART_SR: u32 = USART1;
const USART_DR: u32 = USART1 + 0x04;
const USART_BRR: u32 = USART1 + 0x08;
const USART_CR1: u32 = USART1 + 0x0C;

#[inline(always)]
fn rd(addr: u32) -> u32 {
    // SAFETY: only the peripheral register addresses above, valid for the whole program.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}
#[inline(always)]
fn wr(addr: u32, v: u32) {
    // SAFETY: as above; every value written is a field value of RM0090 for that register.
    unsafe { core::ptr::write_volatile(addr as *mut u32, v) }
}
/// Read-modify-write of USART1's CR1: only at the USART's priority (its interrupt, or BASEPRI).
#[inline(always)]
fn cr1_modify(set: u32, clear: u32) {
    wr(USART_CR1, (rd(USART_CR1) & !clear) | set);
}
#[inline(always)]
fn tim2_now_us() -> u32 {
    rd(TIM2_CNT)
}

static LINK: IsrCell<Link<BoardReal>> = IsrCell::new();
/// Watched by the tick (`on_tick`), reset by the step.
/// 15 ticks between step ends, 1,000 (1 s) to the first.
static DEADLINE: StepDeadline = StepDeadline::new(15, 1000);
/// Ticks counted by `on_tick` (SysTick only).
static TICKS: AtomicU32 = AtomicU32::new(0);
/// The step is pended every this many ticks (1 ms each).
const TICKS_PER_STEP: u32 = PERIOD_MS;

// ---- Receive queue: the USART interrupt produces, the step consumes -----------------------------
const RXQ: usize = 256;
struct Bytes<const N: usize>(core::cell::UnsafeCell<[u8; N]>);
// SAFETY: the single-producer single-consumer protocol below: a slot is written only by the
// producer while it is outside [tail, head), read only by the consumer while it is inside.
unsafe impl<const N: usize> Sync for Bytes<N> {}
static RX_BUF: Bytes<RXQ> = Bytes(core::cell::UnsafeCell::new([0; RXQ]));
static RX_HEAD: AtomicUsize = AtomicUsize::new(0);
static RX_TAIL: AtomicUsize = AtomicUsize::new(0);
/// The receive interrupt is off because the queue was full.
static RX_PAUSED: AtomicBool = AtomicBool::new(false);
/// Receive overruns (ORE) seen.
pub static RX_OVERRUN: AtomicU32 = AtomicU32::new(0);

// ---- Transmit queue: the step produces (under BASEPRI = the USART's priority), the TXE interrupt
// and the step's start loop consume (at the USART's priority) ---------------------------------------
const TXQ: usize = 64;
static TX_BUF: Bytes<TXQ> = Bytes(core::cell::UnsafeCell::new([0; TXQ]));
static TX_HEAD: AtomicUsize = AtomicUsize::new(0);
static TX_TAIL: AtomicUsize = AtomicUsize::new(0);
/// Velocity frames dropped because the previous one was still being sent.
pub static TX_DROPPED: AtomicU32 = AtomicU32::new(0);

/// CR1 bits (RM0090 sec. 30.6.4).
const CR1_UE: u32 = 1 << 13;
const CR1_TXEIE: u32 = 1 << 7;
const CR1_RXNEIE: u32 = 1 << 5;
const CR1_TE: u32 = 1 << 3;
const CR1_RE: u32 = 1 << 2;
/// SR bits.
const SR_TXE: u32 = 1 << 7;
const SR_RXNE: u32 = 1 << 5;
const SR_ORE: u32 = 1 << 3;

/// Set up USART1 (PA9/PA10, 115,200 8N1, receive interrupt), the priorities of it and of the step's
/// interrupt, then unmask both. Call once from `main`, after the firmware is built and before
/// SysTick starts (the tick pends the step).
pub fn init(nvic: &mut NVIC) {
    // SAFETY: once, before the step's interrupt (its only user) is unmasked below.
    unsafe { LINK.init(Link::new(board_config())) };
    // RCC APB2ENR USART1EN (bit 4); GPIOA MODER 10 = alternate function
    // for PA9/PA10; AFRH AF7 = USART1 for both.
    wr(RCC_APB2ENR, rd(RCC_APB2ENR) | (1 << 4));
    cortex_m::asm::dsb(); // STM32F40x errata: the delay after an RCC clock enable
    wr(GPIOA_AFRH, (rd(GPIOA_AFRH) & !(0xFF << 4)) | (0x77 << 4));
    wr(GPIOA_MODER, (rd(GPIOA_MODER) & !(0b1111 << 18)) | (0b1010 << 18));
    wr(USART_BRR, BRR_115200_AT_16MHZ);
    wr(USART_CR1, CR1_UE | CR1_TE | CR1_RE | CR1_RXNEIE);
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

/// USART1: received bytes into the queue; the velocity frame's next bytes out.
fn usart_irq() {
    // Bounded: at most a queue's worth of bytes per entry (the model and the part offer one).
    for _ in 0..RXQ {
        let sr = rd(USART_SR);
        if sr & SR_ORE != 0 {
            RX_OVERRUN.fetch_add(1, Relaxed);
        }
        if sr & SR_RXNE == 0 {
            break;
        }
        let head = RX_HEAD.load(Relaxed);
        let tail = RX_TAIL.load(Acquire);
        if head.wrapping_sub(tail) >= RXQ {
            // Full: stop taking bytes until the step drains (the byte stays in DR).
            RX_PAUSED.store(true, Relaxed);
            cr1_modify(0, CR1_RXNEIE);
            break;
        }
        let b = rd(USART_DR) as u8; // reading DR after SR clears RXNE and ORE
        // SAFETY: slot `head` is outside [tail, head): the consumer does not read it.
        unsafe { (*RX_BUF.0.get())[head % RXQ] = b };
        RX_HEAD.store(head.wrapping_add(1), Release);
    }
    tx_pump();
}

/// Send queued bytes while the data register is empty; TXE interrupt on while bytes are left.
/// Only at the USART's priority (its interrupt, or the step under BASEPRI).
fn tx_pump() {
    for _ in 0..TXQ {
        let tail = TX_TAIL.load(Relaxed);
        if tail == TX_HEAD.load(Acquire) {
            cr1_modify(0, CR1_TXEIE);
            return;
        }
        if rd(USART_SR) & SR_TXE == 0 {
            cr1_modify(CR1_TXEIE, 0);
            return;
        }
        // SAFETY: slot `tail` is inside [tail, head): written by the producer before `head`.
        let b = unsafe { (*TX_BUF.0.get())[tail % TXQ] };
        wr(USART_DR, u32::from(b));
        TX_TAIL.store(tail.wrapping_add(1), Release);
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
    // SAFETY: the step's interrupt is the link's only user; initialised before it was unmasked.
    let link = unsafe { LINK.get() };
    // The queue's bytes into the receiver's ring (at most one queue's worth).
    let head = RX_HEAD.load(Acquire);
    let mut tail = RX_TAIL.load(Relaxed);
    let mut chunk = [0u8; 64];
    for _ in 0..(RXQ / 64 + 1) {
        let n = head.wrapping_sub(tail).min(chunk.len());
        if n == 0 {
            break;
        }
        for (k, slot) in chunk.iter_mut().take(n).enumerate() {
            // SAFETY: inside [tail, head): written by the producer before it published `head`.
            *slot = unsafe { (*RX_BUF.0.get())[tail.wrapping_add(k) % RXQ] };
        }
        link.receiver().push(chunk.get(..n).unwrap_or(&[]), now);
        tail = tail.wrapping_add(n);
        RX_TAIL.store(tail, Release);
    }
    if RX_PAUSED.swap(false, Relaxed) {
        with_usart_masked(|| cr1_modify(CR1_RXNEIE, 0));
    }
    let v = link.step(now);
    let frame = encode_velocity(&v);
    with_usart_masked(|| {
        let tail = TX_TAIL.load(Acquire);
        let head = TX_HEAD.load(Relaxed);
        if TXQ.saturating_sub(head.wrapping_sub(tail)) < VEL_LEN {
            TX_DROPPED.fetch_add(1, Relaxed);
        } else {
            for (k, b) in frame.iter().enumerate() {
                // SAFETY: outside [tail, head) (room checked): the consumer does not read it.
                unsafe { (*TX_BUF.0.get())[head.wrapping_add(k) % TXQ] = *b };
            }
            TX_HEAD.store(head.wrapping_add(VEL_LEN), Release);
        }
        tx_pump();
    });
    DEADLINE.step_done();
}

/// Run `f` with BASEPRI at the USART's priority: the USART interrupt (and everything below it)
/// waits, the switch edge (priority 0) does not.
fn with_usart_masked(f: impl FnOnce()) {
    let old = cortex_m::register::basepri::read();
    // SAFETY: raising BASEPRI only masks; restored below.
    unsafe { cortex_m::register::basepri::write(PRIO_USART) };
    f();
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
