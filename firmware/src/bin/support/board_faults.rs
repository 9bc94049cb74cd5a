//! How the board's faults end: the MPU stack guard, the fault entry that needs no stack, the panic
//! and default handlers. Every one of them masks the interrupts, writes the three outputs low,
//! latches `Cause::FaultHandler` in the backup SRAM and never feeds the watchdog again: the IWDG
//! resets the part about 8 ms later, the reset releases every pin, and the next start finds the latch.
//!
//! **Stack overflow.** flip-link puts the stack at the bottom of RAM, so an overflow runs below
//! 0x2000_0000 instead of over the statics. Without more, the fault it raises cannot be taken: the
//! exception entry pushes its frame onto the same exhausted stack, the push faults again inside the
//! HardFault entry, and the core locks up with the outputs as they were until the IWDG fires. So:
//!
//! * an MPU region (`GUARD_BYTES` at the bottom of RAM, no access) makes the overflow a precise
//!   MemManage fault at the guard;
//! * MemManage, BusFault and UsageFault are enabled at priority 0, above every interrupt (the edge
//!   is at 0x10), so the fault is taken, not escalated, in any context; its own frame push lands in
//!   the guard too, which the core handles as a derived fault, escalated to HardFault at the same
//!   entry without a second push (ARMv7-M ARM B1.5.15; QEMU's `v7m_push_stack` does the same);
//! * the four fault vectors enter `flinch_fault_entry` (assembly): it masks the interrupts and moves
//!   the stack pointer to `FAULT_STACK` (in .bss, above the stack with flip-link) before any push,
//!   then calls `fault_stop`. It needs nothing of the stack it came from.

use crate::backup::{backup_on, stored_boots, Bkp};
use crate::hw::{emergency_stop, GUARD_BYTES};
use core::sync::atomic::{AtomicBool, Ordering::Relaxed};
use flinch_firmware::{backup, Cause, Retained};

/// Set by every fault path: the tick must never feed the watchdog again, even if it still runs (a
/// panic in thread mode leaves the interrupts running until the handler masks them).
pub(crate) static STARVE: AtomicBool = AtomicBool::new(false);

const RAM_START: u32 = 0x2000_0000;

/// The fault handlers' own stack.
#[repr(C, align(8))]
pub(crate) struct FaultStack([u8; FAULT_STACK_BYTES]);
const FAULT_STACK_BYTES: usize = 1024;
#[no_mangle]
static mut FLINCH_FAULT_STACK: FaultStack = FaultStack([0; FAULT_STACK_BYTES]);

/// The stack guard and the fault priorities: MPU region 0 = `GUARD_BYTES` at the bottom of RAM, no
/// access and never executable, the default map for everything else (PRIVDEFENA); MemManage,
/// BusFault and UsageFault enabled at priority 0. Call after the RAM test (which writes the guard).
pub(crate) fn stack_guard_on(cp: &mut cortex_m::Peripherals) {
    use cortex_m::peripheral::scb::SystemHandler;
    // PM0214 4.2: RASR SIZE = log2(bytes) - 1 (bits 5:1), AP = 000 no access (bits 26:24), XN (bit
    // 28), ENABLE (bit 0); RBAR ADDR | VALID (bit 4) | REGION 0.
    const SIZE: u32 = GUARD_BYTES.trailing_zeros() - 1;
    const _: () = assert!(GUARD_BYTES.is_power_of_two() && GUARD_BYTES >= 32);
    // SAFETY: the MPU's and SCB's registers from cortex-m; region 0 covers only the guard, the
    // default map (PRIVDEFENA) stays in force elsewhere; the DSB/ISB make the MPU take effect
    // before the next access (PM0214 4.2.9).
    unsafe {
        cp.MPU.rnr.write(0);
        cp.MPU.rbar.write(RAM_START | (1 << 4));
        cp.MPU.rasr.write((1 << 28) | (SIZE << 1) | 1);
        cp.MPU.ctrl.write((1 << 2) | 1); // PRIVDEFENA | ENABLE (HFNMIENA 0: off in the handlers)
        cortex_m::asm::dsb();
        cortex_m::asm::isb();
        cp.SCB.set_priority(SystemHandler::MemoryManagement, 0);
        cp.SCB.set_priority(SystemHandler::BusFault, 0);
        cp.SCB.set_priority(SystemHandler::UsageFault, 0);
    }
    cp.SCB.enable(cortex_m::peripheral::scb::Exception::MemoryManagement);
    cp.SCB.enable(cortex_m::peripheral::scb::Exception::BusFault);
    cp.SCB.enable(cortex_m::peripheral::scb::Exception::UsageFault);
}

// The four fault vectors (cortex-m-rt's link.x takes these symbols over its defaults): interrupts
// masked, the stack pointer moved to the fault stack's top, then `fault_stop`; no push before.
core::arch::global_asm!(
    ".section .text.flinch_fault_entry,\"ax\",%progbits",
    ".syntax unified",
    ".global HardFault",
    ".global MemoryManagement",
    ".global BusFault",
    ".global UsageFault",
    ".type HardFault,%function",
    ".type MemoryManagement,%function",
    ".type BusFault,%function",
    ".type UsageFault,%function",
    ".thumb_func",
    "HardFault:",
    "    b flinch_fault_entry",
    ".thumb_func",
    "MemoryManagement:",
    "    b flinch_fault_entry",
    ".thumb_func",
    "BusFault:",
    "    b flinch_fault_entry",
    ".thumb_func",
    "UsageFault:",
    "    b flinch_fault_entry",
    ".thumb_func",
    "flinch_fault_entry:",
    "    cpsid i",
    "    movw r0, :lower16:{stack}",
    "    movt r0, :upper16:{stack}",
    "    add.w r0, r0, #{size}",
    "    msr msp, r0",
    "    isb",
    "    bl {stop}",
    "    b .",
    stack = sym FLINCH_FAULT_STACK,
    size = const FAULT_STACK_BYTES,
    stop = sym fault_stop,
);

/// After a fault, on the fault stack: the outputs low, the latch, then nothing (the IWDG resets).
extern "C" fn fault_stop() -> ! {
    fault_handler_stop();
    #[cfg(feature = "qemu-io")]
    crate::bench::fault_report("a fault handler (HardFault, MemManage, BusFault or UsageFault)");
    #[cfg(not(feature = "qemu-io"))]
    loop {
        cortex_m::asm::nop(); // the IWDG resets the part
    }
}

/// A fault handler ran: outputs low first, then latch `FaultHandler` for the next start; the
/// watchdog is never fed again. Registers and the backup SRAM only.
#[inline(always)]
pub(crate) fn fault_handler_stop() {
    emergency_stop();
    STARVE.store(true, Relaxed);
    backup_on();
    backup::store_latch(&mut Bkp, Retained::new(Some(Cause::FaultHandler), stored_boots()));
}

/// A panic in any context (thread mode too: no panicking path is meant to exist, the lints keep
/// them out, this is the last line): every interrupt masked first, so the tick can never feed the
/// watchdog again, then the outputs low and the latch; the IWDG resets the part.
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    STARVE.store(true, Relaxed);
    fault_handler_stop();
    defmt::error!("panic: outputs de-energised");
    #[cfg(feature = "qemu-io")]
    crate::bench::fault_report("the panic handler");
    #[cfg(not(feature = "qemu-io"))]
    loop {
        cortex_m::asm::nop(); // the IWDG resets the part
    }
}

/// NMI and every interrupt without a handler: masked, de-energise and latch, then let the IWDG reset.
#[cortex_m_rt::exception]
unsafe fn DefaultHandler(_irqn: i16) {
    cortex_m::interrupt::disable();
    fault_handler_stop();
    loop {
        cortex_m::asm::nop();
    }
}
