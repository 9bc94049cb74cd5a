//! A serial link fake for the avoidance weights (`embedded-io` 0.6 `Read`/`ReadReady`/`Write`).
//!
//! [`SimSerial::pair`] gives two ends of one full-duplex line, the host's and the MCU's. Bytes
//! written on one end are read on the other, in order. Faults are injected on the host-to-MCU
//! direction: flip one bit of the n-th byte written, drop a run of bytes, or cut the line (everything
//! written afterwards is lost) — what the firmware's frame receiver must reject.
//!
//! `read` never blocks: with nothing buffered it returns `Ok(0)`; use `ReadReady` first, as the
//! firmware's `Receiver::poll` does.

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

#[derive(Default)]
struct Line {
    to_mcu: VecDeque<u8>,
    to_host: VecDeque<u8>,
    written_by_host: u64,
    fault: Option<SerialFault>,
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
                    l.to_host.len()
                } else {
                    l.to_mcu.len()
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
        let q = if self.is_host { &mut l.to_host } else { &mut l.to_mcu };
        let n = buf.len().min(q.len());
        for (slot, b) in buf.iter_mut().zip(q.drain(..n)) {
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
        if !self.is_host {
            l.to_host.extend(buf.iter().copied());
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
            if let Some(b) = out {
                l.to_mcu.push_back(b);
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
        let h = fw::FrameHeader {
            session: 0,
            nx: 15,
            ny: 15,
            seq,
            age_ms: 5,
            x0_q16: 2294,      // 0.035 m
            y0_q16: 2294,
            spacing_q16: 4588, // 0.07 m
            sigma_q16: 3441,   // 0.0525 m (1.5 x spacing / 2)
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

        // No new weights: full speed, then slower, then stopped.
        assert_eq!(wd.factor::<I16F16>(rx.weights_age_ms(50)), I16F16::ONE);
        let slow = wd.factor::<I16F16>(rx.weights_age_ms(200)).to_f64();
        assert!(slow > 0.0 && slow < 1.0);
        assert_eq!(wd.factor::<I16F16>(rx.weights_age_ms(400)), I16F16::ZERO);

        // The line heals and frame 4 is applied.
        host.inject(SerialFault::None);
        host.write_all(&frame(4, 6554)).unwrap();
        rx.poll(&mut mcu, 410).unwrap();
        assert_eq!((rx.stats.good, rx.grid().seq), (2, 4));
        assert_eq!(wd.factor::<I16F16>(rx.weights_age_ms(420)), I16F16::ONE);

        // The MCU can answer on the same line.
        mcu.write_all(b"ok").unwrap();
        let mut b = [0u8; 4];
        assert_eq!(host.read(&mut b).unwrap(), 2);
        assert_eq!(&b[..2], b"ok");
    }
}
