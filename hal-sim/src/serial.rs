//! A serial link fake for the avoidance weights (`embedded-io` 0.6 `Read`/`ReadReady`/`Write`).
//!
//! [`SimSerial::pair`] gives two ends of one full-duplex line, the host's and the MCU's. Bytes
//! written on one end are read on the other, in order. Faults are injected on the host-to-MCU
//! direction: flip one bit of the n-th byte written, drop a run of bytes, or cut the line (everything
//! written afterwards is lost) — what the firmware's frame receiver must reject.
//!
//! `read` never blocks: with nothing buffered it returns `Ok(0)`; use `ReadReady` first, as the
//! firmware's `Receiver::poll` does.
//!
//! Line rate. [`SimSerial::pair_at`] gives a line of a given baud rate, 8N1: every byte takes 10 bit
//! times, one after another in each direction, from when it is written (or from when the byte before
//! it has gone, if later); the reading end sees it only once its last bit is in. The line's clock is
//! the simulation's: set it with [`SimSerial::set_time_us`] (either end; it never goes back).
//! [`SimSerial::pair`] is an ideal line (every byte there at once), for tests of framing alone.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use embedded_io::{ErrorKind, ErrorType, Read, ReadReady, Write, WriteReady};

/// A fault on the host-to-MCU direction.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum SerialFault {
    /// Healthy line.
    None,
    /// Flip bit `bit` of the byte with index `at` (counting every byte ever written by the host).
    FlipBit {
        /// Index of the byte.
        at: u64,
        /// Bit, 0..8.
        bit: u8,
    },
    /// Lose `len` bytes starting at index `at`.
    Drop {
        /// First byte lost.
        at: u64,
        /// Bytes lost.
        len: u64,
    },
    /// Lose every byte from index `at` on.
    Cut {
        /// First byte lost.
        at: u64,
    },
}

/// The error type of the fake (it never fails; a poisoned lock reads as `Other`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct SerialError;

impl embedded_io::Error for SerialError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// One direction: bytes with the time (us) their last bit arrives, and when the line is free.
#[derive(Default)]
struct Wire {
    bytes: VecDeque<(u64, u8)>,
    free_at_ns: u64,
}

impl Wire {
    /// Queue `b`, written at `now_ns`; it takes `byte_ns` after the line is free.
    fn send(&mut self, b: u8, now_ns: u64, byte_ns: Option<u64>) {
        let at = match byte_ns {
            Some(d) => {
                let done = self.free_at_ns.max(now_ns).saturating_add(d);
                self.free_at_ns = done;
                done
            }
            None => now_ns,
        };
        self.bytes.push_back((at, b));
    }

    /// Bytes whole by `now_ns`.
    fn ready(&self, now_ns: u64) -> usize {
        // Arrival times never decrease along the queue.
        self.bytes.iter().take_while(|(at, _)| *at <= now_ns).count()
    }
}

#[derive(Default)]
struct Line {
    to_mcu: Wire,
    to_host: Wire,
    written_by_host: u64,
    fault: Option<SerialFault>,
    /// Time of one byte (10 bits) in ns, rounded up; `None`: an ideal line.
    byte_ns: Option<u64>,
    now_ns: u64,
}

/// One end of the link.
#[derive(Clone)]
pub struct SimSerial {
    line: Arc<Mutex<Line>>,
    is_host: bool,
}

impl SimSerial {
    /// The host's end and the MCU's end of a new line.
    pub fn pair() -> (SimSerial, SimSerial) {
        let line = Arc::new(Mutex::new(Line::default()));
        (SimSerial { line: line.clone(), is_host: true }, SimSerial { line, is_host: false })
    }

    /// The two ends of a line at `baud` (8N1: 10 bits a byte, at least 1 baud), its clock at 0.
    pub fn pair_at(baud: u32) -> (SimSerial, SimSerial) {
        let byte_ns = 10_000_000_000u64.div_ceil(u64::from(baud.max(1)));
        let line = Arc::new(Mutex::new(Line { byte_ns: Some(byte_ns), ..Line::default() }));
        (SimSerial { line: line.clone(), is_host: true }, SimSerial { line, is_host: false })
    }

    /// Set the line's clock, us (a time before the current one is ignored).
    pub fn set_time_us(&self, t_us: u64) {
        if let Ok(mut l) = self.line.lock() {
            l.now_ns = l.now_ns.max(t_us.saturating_mul(1000));
        }
    }

    /// Set the fault on the host-to-MCU direction (either end may set it).
    pub fn inject(&self, fault: SerialFault) {
        if let Ok(mut l) = self.line.lock() {
            l.fault = Some(fault);
        }
    }

    /// Bytes waiting to be read at this end.
    pub fn available(&self) -> usize {
        match self.line.lock() {
            Ok(l) => {
                if self.is_host {
                    l.to_host.ready(l.now_ns)
                } else {
                    l.to_mcu.ready(l.now_ns)
                }
            }
            Err(_) => 0,
        }
    }
}

impl ErrorType for SimSerial {
    type Error = SerialError;
}

impl Read for SimSerial {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, SerialError> {
        let mut l = self.line.lock().map_err(|_| SerialError)?;
        let now = l.now_ns;
        let q = if self.is_host { &mut l.to_host } else { &mut l.to_mcu };
        let n = buf.len().min(q.ready(now));
        for (slot, (_, b)) in buf.iter_mut().zip(q.bytes.drain(..n)) {
            *slot = b;
        }
        Ok(n)
    }
}

impl ReadReady for SimSerial {
    fn read_ready(&mut self) -> Result<bool, SerialError> {
        Ok(self.available() > 0)
    }
}

impl Write for SimSerial {
    fn write(&mut self, buf: &[u8]) -> Result<usize, SerialError> {
        let mut l = self.line.lock().map_err(|_| SerialError)?;
        let (now, byte_ns) = (l.now_ns, l.byte_ns);
        if !self.is_host {
            for &b in buf {
                l.to_host.send(b, now, byte_ns);
            }
            return Ok(buf.len());
        }
        for &b in buf {
            let k = l.written_by_host;
            l.written_by_host += 1;
            let out = match l.fault {
                Some(SerialFault::FlipBit { at, bit }) if at == k => Some(b ^ (1 << (bit % 8))),
                Some(SerialFault::Drop { at, len }) if k >= at && k < at + len => None,
                Some(SerialFault::Cut { at }) if k >= at => None,
                _ => Some(b),
            };
            match out {
                Some(b) => l.to_mcu.send(b, now, byte_ns),
                // A lost byte still took its time on the line (the receiver saw noise or nothing).
                None => {
                    if let Some(d) = byte_ns {
                        l.to_mcu.free_at_ns = l.to_mcu.free_at_ns.max(now).saturating_add(d);
                    }
                }
            }
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), SerialError> {
        Ok(())
    }
}

impl WriteReady for SimSerial {
    fn write_ready(&mut self) -> Result<bool, SerialError> {
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flinch_firmware::avoidance::{self as fw, num::I16F16, Real};

    fn frame(seq: u32, w0: i32) -> Vec<u8> {
        frame_in(3, seq, w0)
    }

    fn frame_in(session: u8, seq: u32, w0: i32) -> Vec<u8> {
        let h = fw::FrameHeader {
            session,
            nx: 15,
            ny: 15,
            seq,
            age_ms: 5,
            x0_q16: 2294,      // 0.035 m
            y0_q16: 2294,
            spacing_q16: 4588, // 0.07 m
            sigma_q16: 3441,   // 0.0525 m (1.5 x spacing / 2)
            ..fw::FrameHeader::default()
        };
        let mut w = vec![0i32; 225];
        w[7 * 15 + 7] = w0;
        let mut out = vec![0u8; fw::frame::MAX_FRAME];
        let n = fw::encode_frame(&h, &w, &mut out).unwrap();
        out.truncate(n);
        out
    }

    /// Host -> line -> firmware receiver -> step, with a corrupted frame, a cut frame and a silence.
    #[test]
    fn weights_cross_the_link_and_bad_frames_are_not_applied() {
        let (mut host, mut mcu) = SimSerial::pair();
        let mut rx = Box::new(fw::Receiver::<I16F16>::new(100, 20));
        let wd = fw::Watchdog { slow_after_ms: 100, stop_after_ms: 300 };
        let len = frame(1, 0).len() as u64;

        host.write_all(&frame(1, 13107)).unwrap(); // 0.2 m
        rx.poll(&mut mcu, 0).unwrap();
        assert_eq!(rx.stats.good, 1);
        let centre = I16F16::from_f64(0.035 + 7.0 * 0.07);
        let h1 = fw::sample(rx.grid(), &fw::GaussLut::new(), centre, centre).height;
        assert!((h1.to_f64() - 0.2).abs() < 1e-3, "{h1}");

        // Frame 2 has a flipped bit: refused, frame 1 stays.
        host.inject(SerialFault::FlipBit { at: len + 100, bit: 3 });
        host.write_all(&frame(2, 26214)).unwrap();
        rx.poll(&mut mcu, 10).unwrap();
        assert_eq!((rx.stats.good, rx.stats.bad_crc), (1, 1));
        assert_eq!(rx.grid().seq, 1);

        // Frame 3 is cut short; the line goes quiet, the receiver drops it as short.
        host.inject(SerialFault::Cut { at: 2 * len + 500 });
        host.write_all(&frame(3, 26214)).unwrap();
        rx.poll(&mut mcu, 20).unwrap();
        rx.tick(60);
        assert_eq!(rx.stats.short, 1);
        assert_eq!(rx.grid().seq, 1);

        // No new weights: full speed, then slower, then stopped (the age counts from frame 1's
        // first byte, polled at 0 ms, less its 5 ms age).
        assert_eq!(wd.factor::<I16F16>(rx.weights_age_ms(50)), I16F16::ONE);
        let slow = wd.factor::<I16F16>(rx.weights_age_ms(200)).to_f64();
        assert!(slow > 0.0 && slow < 1.0);
        assert_eq!(wd.factor::<I16F16>(rx.weights_age_ms(400)), I16F16::ZERO);

        // The line heals and frame 4 is applied (the MCU polls every step meanwhile).
        host.inject(SerialFault::None);
        for t in (70..=400).step_by(10) {
            rx.poll(&mut mcu, t).unwrap();
        }
        host.write_all(&frame(4, 6554)).unwrap();
        rx.poll(&mut mcu, 410).unwrap();
        assert_eq!((rx.stats.good, rx.grid().seq), (2, 4));
        assert_eq!(wd.factor::<I16F16>(rx.weights_age_ms(420)), I16F16::ONE);
        // A second host on the port (another session) is refused while the weights are fresh.
        host.write_all(&frame_in(4, 1, 6554)).unwrap();
        rx.poll(&mut mcu, 420).unwrap();
        assert_eq!((rx.stats.good, rx.stats.old_session, rx.grid().seq), (2, 1, 4));

        // The MCU can answer on the same line.
        mcu.write_all(b"ok").unwrap();
        let mut b = [0u8; 4];
        assert_eq!(host.read(&mut b).unwrap(), 2);
        assert_eq!(&b[..2], b"ok");
    }

    /// The line takes its time: 10 bits a byte at the baud rate, one byte after another, in both
    /// directions; the receiver sees a 15 x 15 frame (988 bytes, protocol v3) whole only after
    /// 988 x 10 / 115200 s = 85.8 ms, and the weights' age counts from its first byte.
    #[test]
    fn bytes_take_their_time_at_the_baud_rate() {
        let (mut host, mcu) = SimSerial::pair_at(115_200);
        let f = frame(1, 13107);
        assert_eq!(f.len(), 988);
        host.write_all(&f).unwrap();
        assert_eq!(mcu.available(), 0);
        host.set_time_us(10_000);
        // floor(10 ms / 86.806 us) = 115 bytes.
        assert_eq!(mcu.available(), 115);
        host.set_time_us(80_000);
        assert_eq!(mcu.available(), 921);
        // 86,806 ns a byte: the 988th is in at 85,764,328 ns.
        host.set_time_us(85_764);
        assert_eq!(mcu.available(), 987);
        host.set_time_us(85_765);
        assert_eq!(mcu.available(), 988);
        // Written while the line is busy: queued behind, not sent at once.
        host.write_all(&[0x55]).unwrap();
        assert_eq!(mcu.available(), 988);
        host.set_time_us(85_852);
        assert_eq!(mcu.available(), 989);

        // Through the receiver, polled every 10 ms step: applied at the first step after 85.8 ms.
        let (mut host, mut mcu) = SimSerial::pair_at(115_200);
        let mut rx = Box::new(fw::Receiver::<I16F16>::new(100, 20));
        host.write_all(&f).unwrap();
        let mut applied = None;
        for t in (0..200u32).step_by(10) {
            mcu.set_time_us(u64::from(t) * 1000);
            rx.poll(&mut mcu, t).unwrap();
            if rx.stats.good == 1 && applied.is_none() {
                applied = Some(t);
            }
        }
        assert_eq!(applied, Some(90));
        // Age at 90 ms: from the poll before the first byte (0 ms) plus the frame's 5 ms.
        assert_eq!(rx.weights_age_ms(90), Some(95));

        // The MCU's answer takes its time too.
        mcu.write_all(b"ok").unwrap();
        assert_eq!(host.available(), 0);
        host.set_time_us(200_000 + 174);
        assert_eq!(host.available(), 2);
    }
}
