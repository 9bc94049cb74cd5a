//! The board's USART receive interrupt as a function of the status and data registers
//! ([`UsartRx`]), so that the host tests the corners the part has and QEMU does not model: the
//! overrun (ORE) with and without a received byte, and a full queue.
//!
//! STM32F4 USART (RM0090 sec. 30.6.1): RXNE says the data register holds a byte; ORE says a byte
//! was lost because the previous one was not read in time. Both raise the receive interrupt while
//! RXNEIE is set, and ORE is cleared only by a read of SR *followed by* a read of DR. The corner: the
//! interrupt reads SR (RXNE, no ORE yet), a byte arrives and overruns, the interrupt reads DR (RXNE
//! clear, ORE still set: its SR read came before the overrun). The next entry sees ORE without RXNE;
//! a handler that reads DR only when RXNE is set never clears ORE, and the interrupt is raised again
//! at once, for good: at the USART's priority (above the detection tick) that starves the tick. Here
//! every entry that sees ORE reads DR after its SR read, which clears it; a value read without RXNE
//! is stale and is dropped (the frame it belonged to is refused by its CRC, counted in `overruns`).

/// The receive side of a USART.
pub trait UsartRx {
    /// Read the status register (SR).
    fn status(&mut self) -> u32;
    /// Read the data register (DR): the received byte, and the second half of the ORE clear.
    fn data(&mut self) -> u8;
}

/// Where the received bytes go (the board's `heapless::spsc` producer).
pub trait RxSink {
    /// One more byte fits.
    fn room(&self) -> bool;
    /// Take a byte (called only after `room`).
    fn push(&mut self, byte: u8);
}

impl<const N: usize> RxSink for heapless::Vec<u8, N> {
    fn room(&self) -> bool {
        !self.is_full()
    }
    fn push(&mut self, byte: u8) {
        let _ = heapless::Vec::push(self, byte);
    }
}

/// SR's "read data register not empty" bit.
pub const SR_RXNE: u32 = 1 << 5;
/// SR's overrun bit.
pub const SR_ORE: u32 = 1 << 3;

/// What one call of [`service`] did.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct RxServiced {
    /// Bytes handed to the queue.
    pub bytes: u32,
    /// Overruns seen (each lost at least one byte).
    pub overruns: u32,
    /// Bytes read and dropped because the queue was full (the frame they belong to is refused by
    /// its CRC, as after an overrun).
    pub dropped: u32,
}

/// The receive interrupt's work: at most `max` passes, each reading SR, then DR when SR shows RXNE
/// or ORE, the bytes into `sink` (or dropped and counted when it is full: the data register is
/// always read, so the interrupt request is always withdrawn, on the part and in QEMU's model, whose
/// interrupt line does not drop when RXNEIE is cleared). Returns with neither RXNE nor ORE pending
/// (so the interrupt is not raised again by what it saw).
pub fn service<U: UsartRx, S: RxSink>(usart: &mut U, sink: &mut S, max: u32) -> RxServiced {
    let mut did = RxServiced::default();
    for _ in 0..max {
        let sr = usart.status();
        if sr & SR_ORE != 0 {
            did.overruns = did.overruns.saturating_add(1);
        }
        if sr & SR_RXNE == 0 {
            if sr & SR_ORE != 0 {
                // ORE without a byte: this SR read and the DR read clear it; the value is stale.
                let _ = usart.data();
                continue;
            }
            return did;
        }
        let b = usart.data(); // SR then DR: clears RXNE and ORE
        if sink.room() {
            sink.push(b);
            did.bytes = did.bytes.saturating_add(1);
        } else {
            did.dropped = did.dropped.saturating_add(1);
        }
    }
    did
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A USART receiver as RM0090 describes it: one data register, RXNE, ORE cleared by an SR read
    /// followed by a DR read (an SR read that did not see ORE does not count).
    #[derive(Default)]
    struct FakeUsart {
        dr: u8,
        rxne: bool,
        ore: bool,
        sr_saw_ore: bool,
    }
    impl FakeUsart {
        fn receive(&mut self, b: u8) {
            if self.rxne {
                self.ore = true; // the new byte is lost, DR keeps the old one
            } else {
                self.dr = b;
                self.rxne = true;
            }
        }
        /// The interrupt line: RXNE or ORE (RXNEIE on).
        fn pending(&self) -> bool {
            self.rxne || self.ore
        }
    }
    impl UsartRx for FakeUsart {
        fn status(&mut self) -> u32 {
            self.sr_saw_ore = self.ore;
            (if self.rxne { SR_RXNE } else { 0 }) | (if self.ore { SR_ORE } else { 0 })
        }
        fn data(&mut self) -> u8 {
            self.rxne = false;
            if self.sr_saw_ore {
                self.ore = false;
            }
            self.dr
        }
    }

    fn run(u: &mut FakeUsart, q: &mut heapless::Vec<u8, 8>) -> RxServiced {
        service(u, q, 16)
    }

    #[test]
    fn bytes_in_order_one_per_entry() {
        let (mut u, mut q) = (FakeUsart::default(), heapless::Vec::new());
        for b in [1u8, 2, 3] {
            u.receive(b);
            assert_eq!(run(&mut u, &mut q), RxServiced { bytes: 1, overruns: 0, dropped: 0 });
            assert!(!u.pending());
        }
        assert_eq!(&q[..], &[1, 2, 3]);
    }

    #[test]
    fn usart_overrun_with_a_byte_keeps_the_byte_and_clears_the_flag() {
        let (mut u, mut q) = (FakeUsart::default(), heapless::Vec::new());
        u.receive(7);
        u.receive(8); // lost: overrun
        assert_eq!(run(&mut u, &mut q), RxServiced { bytes: 1, overruns: 1, dropped: 0 });
        assert_eq!(&q[..], &[7]);
        assert!(!u.pending(), "ORE cleared by the SR-then-DR read");
    }

    #[test]
    fn usart_overrun_without_rxne_is_cleared_so_the_interrupt_does_not_re_raise() {
        // The race: an entry reads SR (RXNE only), the next byte overruns, the entry reads DR.
        let (mut u, mut q) = (FakeUsart::default(), heapless::Vec::<u8, 8>::new());
        u.receive(1);
        assert_eq!(u.status(), SR_RXNE);
        u.receive(2); // overrun after the SR read
        let _ = q.push(u.data());
        assert!(u.ore && !u.rxne && u.pending(), "ORE without RXNE, still raising the interrupt");
        // The next entries: the handler must clear it in one entry, and queue nothing stale.
        let mut entries = 0;
        while u.pending() && entries < 10 {
            let did = run(&mut u, &mut q);
            assert_eq!(did.bytes, 0, "no stale byte queued");
            entries += 1;
        }
        assert_eq!(entries, 1, "one entry clears it: no interrupt storm above the tick");
        assert_eq!(&q[..], &[1]);
        // A handler that reads DR only when RXNE is set (main before issue 25) never clears it.
        let mut old = FakeUsart { ore: true, ..Default::default() };
        for _ in 0..10 {
            let sr = old.status();
            if sr & SR_RXNE != 0 {
                let _ = old.data();
            }
        }
        assert!(old.pending(), "the old handler leaves the interrupt raised for good");
    }

    #[test]
    fn a_full_queue_drops_and_counts_and_the_interrupt_is_withdrawn() {
        let (mut u, mut q) = (FakeUsart::default(), heapless::Vec::new());
        for b in 0..8u8 {
            u.receive(b);
            run(&mut u, &mut q);
        }
        u.receive(100);
        assert_eq!(run(&mut u, &mut q), RxServiced { bytes: 0, overruns: 0, dropped: 1 });
        assert!(!u.pending(), "the byte read and dropped: no request left");
        q.clear();
        u.receive(101);
        assert_eq!(run(&mut u, &mut q), RxServiced { bytes: 1, overruns: 0, dropped: 0 });
        assert_eq!(&q[..], &[101]);
    }

    #[test]
    fn an_entry_is_bounded() {
        struct Stuck;
        impl UsartRx for Stuck {
            fn status(&mut self) -> u32 {
                SR_RXNE | SR_ORE
            }
            fn data(&mut self) -> u8 {
                0
            }
        }
        let mut q: heapless::Vec<u8, 32> = heapless::Vec::new();
        let did = service(&mut Stuck, &mut q, 16);
        assert_eq!((did.bytes, did.overruns), (16, 16));
    }
}
