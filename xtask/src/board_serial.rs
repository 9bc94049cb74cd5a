//! The board's avoidance over its serial port in QEMU: weights frames in, velocity frames out.

use crate::common::{read_expected, target_dir, TARGET};
use crate::firmware::qemu_io_dir;
use std::fs;
use std::process::{Command, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

/// How long the whole serial conversation may take (QEMU's virtual clock follows the host's).
const SERIAL_TIMEOUT: Duration = Duration::from_secs(120);

/// A 5 x 5 protocol-v3 weights frame over the 1.05 m work plane (centres 0.21 m apart from
/// 0.105 m, sigma 0.105 m), every weight `w_m`: 0.5 m puts the field at the tool far above the
/// board's stop height (the hand over the tool), 0 is an empty field. It echoes the clock and boot
/// of `last`, the newest velocity frame read before it was made (as a host does before each
/// capture), the tool where `last` had it, and a person `person_mm` away in sector `sector` (none:
/// nothing sensed).
fn weights_frame(seq: u32, w_m: f64, last: &flinch_firmware::avoidance::link::VelocityFrame, person: Option<(usize, u16)>, boot: u8) -> Vec<u8> {
    use flinch_firmware::avoidance::frame::{encode_frame, FrameHeader, MAX_FRAME, NOTHING_MM};
    let q = |v: f64| (v * 65536.0).round() as i32;
    let tool = [f64::from(last.x_um) * 1e-6, f64::from(last.y_um) * 1e-6];
    let mut person_mm = [NOTHING_MM; 8];
    let mut nearest = [tool[0] + 10.0, tool[1]];
    if let Some((k, mm)) = person {
        person_mm[k] = mm;
        // On the sector's centre line, the separation plus the wrist's 45 mm from the tool's centre.
        let a = (22.5 + 45.0 * k as f64).to_radians();
        let r = f64::from(mm) * 1e-3 + 0.045;
        nearest = [tool[0] + r * a.cos(), tool[1] + r * a.sin()];
    }
    let h = FrameHeader {
        session: 1,
        nx: 5,
        ny: 5,
        seq,
        age_ms: 5,
        x0_q16: q(0.105),
        y0_q16: q(0.105),
        spacing_q16: q(0.21),
        sigma_q16: q(0.105),
        echo_ms: last.t_ms,
        echo_boot: boot,
        tool_q16: [q(tool[0]), q(tool[1])],
        nearest_q16: [q(nearest[0]), q(nearest[1])],
        person_mm,
        ..FrameHeader::default()
    };
    let mut out = vec![0u8; MAX_FRAME];
    let n = encode_frame(&h, &[q(w_m); 25], &mut out).unwrap_or(0);
    out.truncate(n);
    out
}

/// One velocity frame as the expected file writes it; `full` adds the numbers that depend only on
/// the frames sent (not on when QEMU delivered them).
fn velocity_line(what: &str, f: &flinch_firmware::avoidance::link::VelocityFrame, full: bool) -> String {
    if full {
        format!(
            "{what}: status={} monitor={} seq={} vx_umps={} vy_umps={} x_um={} y_um={} good={} refused={}",
            f.status.name(), f.monitor.name(), f.seq, f.vx_umps, f.vy_umps, f.x_um, f.y_um, f.good, f.refused
        )
    } else {
        format!("{what}: status={} monitor={} seq={}", f.status.name(), f.monitor.name(), f.seq)
    }
}

/// The board ELF's velocity frames against the library's `Link` on the host (the type `flinch
/// avoid --mcu` runs), from the board's own configuration: a fresh `Link` gets each weights frame
/// the host sent just before the step whose counters first show it (applied or refused: a 5 x 5
/// frame is parsed within one step once its bytes are in, and until then no output depends on
/// them), and the detection latch as the board's frame reported it; every velocity frame must come
/// out byte for byte the same (`f32` on both: IEEE single on the M4F's FPU and on the host, no fused
/// operations). `None` when they all agree, else the first difference.
fn replay(raw: &[[u8; flinch_firmware::avoidance::link::VEL_LEN]], sent: &[Vec<u8>]) -> Result<usize, String> {
    use flinch_firmware::avoidance::cell::board_config;
    use flinch_firmware::avoidance::link::{decode_velocity, encode_velocity, Link, Status};
    let first = raw.first().and_then(|b| decode_velocity(b)).ok_or("no velocity frame to replay")?;
    let mut link = Link::<flinch_firmware::avoidance::BoardReal>::new(board_config());
    link.set_boot(first.boot);
    let mut pushed = 0usize;
    for (k, bytes) in raw.iter().enumerate() {
        let f = decode_velocity(bytes).ok_or_else(|| format!("velocity frame {k} does not decode"))?;
        if f.step as usize != k + 1 {
            return Err(format!("velocity frame {k} is step {}: a frame was lost, the replay needs every step from the first", f.step));
        }
        let seen = usize::from(f.good) + usize::from(f.refused);
        while pushed < seen {
            let frame = sent.get(pushed).ok_or_else(|| format!("step {}: the board counts {seen} frames, the host sent {}", f.step, sent.len()))?;
            link.receiver().push(frame, f.t_ms);
            pushed += 1;
        }
        let v = link.step_with(f.t_ms, f.status == Status::StoppedLatched);
        let mine = encode_velocity(&v);
        if &mine != bytes {
            return Err(format!("step {}: the board sent {:?}\n the host's Link {:?}", f.step, f, decode_velocity(&mine)));
        }
    }
    Ok(raw.len())
}

/// The board's avoidance over its serial port: the `qemu-io` board ELF (the board's code; its GPIO
/// played by the bench, `board_bench.rs`, in its `serial` mode, which presses reset and moves the
/// obstacle, as the production ELF cannot be released in QEMU: its inputs read 0) on netduinoplus2,
/// USART1 connected to a Unix socket this function listens on. Weights frames go in, the board's
/// velocity frames come back and are decoded; the conversation waits for the board's answer before
/// each next frame, and the bench waits for the frames' statuses before it acts, so the lines
/// compared do not depend on the host's timing. Compared with `firmware/qemu/board-serial.txt`; a
/// mismatch, a missing frame, a bench failure or a timeout fails.
pub fn board_serial() -> Result<String, String> {
    use flinch_firmware::avoidance::link::{decode_velocity, Status, VelocityFrame, VEL_LEN, VEL_SYNC0, VEL_SYNC1};
    use std::io::{Read, Write};
    use std::os::unix::net::UnixListener;
    let sock = target_dir().join("board-serial.sock");
    let _ = fs::remove_file(&sock);
    let listener = UnixListener::bind(&sock).map_err(|e| format!("binding {}: {e}", sock.display()))?;
    let log = target_dir().join("board-serial.log");
    let out_path = target_dir().join("board-serial.out");
    let out_file = fs::File::create(&out_path).map_err(|e| format!("{}: {e}", out_path.display()))?;
    let elf = qemu_io_dir().join(TARGET).join("release").join("board");
    let mut child = Command::new("qemu-system-arm")
        .args(["-M", "netduinoplus2", "-nographic", "-monitor", "none"])
        .args(["-semihosting-config", "enable=on,target=native,arg=board,arg=serial", "-icount", "shift=3", "-chardev"])
        .arg(format!("socket,id=s0,path={}", sock.display()))
        .args(["-serial", "chardev:s0", "-d", "unimp,guest_errors", "-D"])
        .arg(&log)
        .arg("-kernel")
        .arg(&elf)
        .stdin(Stdio::null())
        .stdout(out_file)
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("could not start qemu-system-arm: {e}"))?;
    let start = Instant::now();
    type Conversation = (Vec<String>, Vec<[u8; flinch_firmware::avoidance::link::VEL_LEN]>, Vec<Vec<u8>>);
    let result = (|| -> Result<Conversation, String> {
        listener.set_nonblocking(true).map_err(|e| e.to_string())?;
        let mut stream = loop {
            match listener.accept() {
                Ok((s, _)) => break s,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                    if start.elapsed() > SERIAL_TIMEOUT {
                        return Err("QEMU never connected to the serial socket".into());
                    }
                    sleep(Duration::from_millis(20));
                }
                Err(e) => return Err(format!("accepting QEMU's serial connection: {e}")),
            }
        };
        stream.set_nonblocking(false).map_err(|e| e.to_string())?;
        stream.set_read_timeout(Some(Duration::from_millis(100))).map_err(|e| e.to_string())?;
        let mut buf: Vec<u8> = Vec::new();
        let mut frames = 0usize;
        // Every latched frame since the trip must hold the tool where the first one had it.
        let mut held_at: Option<(i32, i32)> = None;
        let mut moved_while_latched = 0usize;
        // Every velocity frame as received (the replay needs them all), and every weights frame sent.
        let mut raw: Vec<[u8; VEL_LEN]> = Vec::new();
        let mut sent: Vec<Vec<u8>> = Vec::new();
        // The next velocity frame that satisfies `want` (frames before it are read and dropped).
        let mut wait = |stream: &mut std::os::unix::net::UnixStream, what: &str, want: &dyn Fn(&VelocityFrame) -> bool| -> Result<VelocityFrame, String> {
            loop {
                while buf.len() >= VEL_LEN {
                    if buf[0] == VEL_SYNC0 && buf[1] == VEL_SYNC1 {
                        if let Some(f) = decode_velocity(&buf[..VEL_LEN]) {
                            let mut one = [0u8; VEL_LEN];
                            one.copy_from_slice(&buf[..VEL_LEN]);
                            raw.push(one);
                            buf.drain(..VEL_LEN);
                            frames += 1;
                            if f.status == Status::StoppedLatched {
                                if f.vx_umps != 0 || f.vy_umps != 0 || held_at.is_some_and(|p| p != (f.x_um, f.y_um)) {
                                    moved_while_latched += 1;
                                }
                                held_at.get_or_insert((f.x_um, f.y_um));
                            } else {
                                held_at = None;
                            }
                            if want(&f) {
                                return Ok(f);
                            }
                            continue;
                        }
                    }
                    buf.remove(0);
                }
                if start.elapsed() > SERIAL_TIMEOUT {
                    return Err(format!("timed out after {} s waiting for {what} ({frames} velocity frames read)", SERIAL_TIMEOUT.as_secs()));
                }
                let mut chunk = [0u8; 512];
                match stream.read(&mut chunk) {
                    Ok(0) => return Err(format!("QEMU closed the serial port waiting for {what}")),
                    Ok(n) => buf.extend_from_slice(&chunk[..n]),
                    Err(e) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                    Err(e) => return Err(format!("reading the serial port: {e}")),
                }
            }
        };
        let mut lines = Vec::new();
        let mut send = |stream: &mut std::os::unix::net::UnixStream, frame: Vec<u8>| -> Result<(), String> {
            stream.write_all(&frame).map_err(|e| e.to_string())?;
            sent.push(frame);
            Ok(())
        };
        let f = wait(&mut stream, "the first velocity frame", &|_| true)?;
        lines.push(velocity_line("the start latch, before the reset press", &f, true));
        let f = wait(&mut stream, "the latch released by the bench's reset press", &|f| f.status != Status::StoppedLatched)?;
        lines.push(velocity_line("armed after the reset press, before any weights frame", &f, true));
        let boot = f.boot;
        send(&mut stream, weights_frame(1, 0.5, &f, None, boot))?;
        let f = wait(&mut stream, "frame 1 in use", &|f| f.seq == 1)?;
        lines.push(velocity_line("frame 1 (field 0.5 m weights: the hand over the tool)", &f, true));
        let mut bad = weights_frame(2, 0.0, &f, None, boot);
        bad[100] ^= 0x01;
        send(&mut stream, bad)?;
        let f = wait(&mut stream, "frame 2 refused", &|f| f.refused >= 1)?;
        lines.push(velocity_line("frame 2 (one bit flipped)", &f, true));
        send(&mut stream, weights_frame(3, 0.0, &f, None, boot))?;
        let f = wait(&mut stream, "frame 3 in use", &|f| f.seq == 3)?;
        lines.push(velocity_line("frame 3 (empty field)", &f, true));
        let f = wait(&mut stream, "the weights slowing with age", &|f| f.status != Status::Ok)?;
        lines.push(velocity_line("the line silent, the weights ageing", &f, false));
        let f = wait(&mut stream, "the weights stale", &|f| f.status == Status::StoppedStale)?;
        lines.push(format!("{}, vx_umps={} vy_umps={}", velocity_line("the line still silent", &f, false), f.vx_umps, f.vy_umps));
        let f = wait(&mut stream, "the bench's obstacle tripping the switch", &|f| f.status == Status::StoppedLatched)?;
        lines.push(format!("{}, vx_umps={} vy_umps={}", velocity_line("the obstacle trips the switch (the collision latch)", &f, false), f.vx_umps, f.vy_umps));
        send(&mut stream, weights_frame(4, 0.0, &f, None, boot))?;
        let f = wait(&mut stream, "frame 4 in use while latched", &|f| f.seq == 4)?;
        let line = velocity_line("frame 4 (empty field) while latched", &f, false);
        lines.push(format!("{line}, vx_umps={} vy_umps={} good={} refused={}", f.vx_umps, f.vy_umps, f.good, f.refused));
        let f = wait(&mut stream, "the latch released by the bench's second reset press", &|f| f.status != Status::StoppedLatched)?;
        lines.push(format!("{}, vx_umps={} vy_umps={}", velocity_line("released by a reset press, frame 4 aged meanwhile", &f, false), f.vx_umps, f.vy_umps));
        send(&mut stream, weights_frame(5, 0.0, &f, None, boot))?;
        let f = wait(&mut stream, "frame 5 in use after the release", &|f| f.seq == 5)?;
        let line = velocity_line("frame 5 (empty field) after the release", &f, false);
        lines.push(format!("{line}, vx_umps={} vy_umps={} good={} refused={}", f.vx_umps, f.vy_umps, f.good, f.refused));
        // The monitor (ISO/TS 15066 5.5.4 + 5.5.5, the board's cell): a person 0.30 m ahead along
        // the module's axis (inside the protective separation: PFL carries the cruise speed), one
        // 0.10 m behind (moving away: not limited), a frame echoing another boot's clock (its age
        // unknown: stale), and a plain frame again.
        send(&mut stream, weights_frame(6, 0.0, &f, Some((0, 300)), boot))?;
        let f = wait(&mut stream, "frame 6 in use", &|f| f.seq == 6)?;
        lines.push(format!("{}, vx_umps={} vy_umps={}", velocity_line("frame 6 (a person 0.30 m ahead, along the module's axis)", &f, false), f.vx_umps, f.vy_umps));
        send(&mut stream, weights_frame(70, 0.0, &f, Some((0, 40)), boot))?;
        let f = wait(&mut stream, "frame 70 in use", &|f| f.seq == 70)?;
        lines.push(format!("{}, vy {}", velocity_line("frame 70 (a person 0.04 m ahead: the steering turns, across the axis only the rigid PFL speed)", &f, false), if f.vy_umps.unsigned_abs() <= 63_500 { "within the rigid PFL speed" } else { "OVER the rigid PFL speed" }));
        send(&mut stream, weights_frame(71, 0.0, &f, Some((4, 100)), boot))?;
        let f = wait(&mut stream, "frame 71 in use", &|f| f.seq == 71)?;
        // (The command's direction now depends on where the turn left the tool: timing.)
        lines.push(velocity_line("frame 71 (a person 0.10 m behind, moving away)", &f, false));
        send(&mut stream, weights_frame(80, 0.0, &f, None, boot.wrapping_add(1)))?;
        let f = wait(&mut stream, "frame 80 in use", &|f| f.seq == 80)?;
        lines.push(format!("{}, vx_umps={} vy_umps={}", velocity_line("frame 80 (echoing another boot's clock)", &f, false), f.vx_umps, f.vy_umps));
        send(&mut stream, weights_frame(90, 0.0, &f, None, boot))?;
        let f = wait(&mut stream, "frame 90 in use", &|f| f.seq == 90)?;
        let line = velocity_line("frame 90 (nothing sensed)", &f, false);
        lines.push(format!("{line}, good={} refused={}", f.good, f.refused));
        // The frames the board sends until the bench ends the run, for the replay.
        let _ = wait(&mut stream, "the end of the run", &|_| false);
        lines.push(format!("latched frames with a command or a moved position: {moved_while_latched}"));
        Ok((lines, raw, sent))
    })();
    // The bench ends the run itself once it has seen `ok` after the release.
    let mut status = None;
    while result.is_ok() && start.elapsed() < SERIAL_TIMEOUT {
        if let Ok(Some(s)) = child.try_wait() {
            status = Some(s);
            break;
        }
        sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    let _ = fs::remove_file(&sock);
    let (got, raw, sent) = result?;
    // The same frames through the host's `Link` (the `--mcu` engine's type): the same bytes back.
    let replayed = replay(&raw, &sent).map_err(|e| format!("the board ELF and the host's Link differ: {e}"))?;
    let bench = fs::read_to_string(&out_path).unwrap_or_default();
    for l in bench.lines().chain(got.iter().map(|l| l.as_str())) {
        println!("board serial: {l}");
    }
    if !status.is_some_and(|s| s.success()) || !bench.contains("bench: PASS") {
        return Err(format!("the board bench (serial) did not pass ({status:?}):\n{bench}"));
    }
    let want = read_expected("firmware/qemu/board-serial.txt")?;
    if got != want {
        return Err(format!(
            "the board's velocity frames differ from firmware/qemu/board-serial.txt:\n--- got\n{}\n--- expected\n{}",
            got.join("\n"),
            want.join("\n")
        ));
    }
    Ok(format!("board ELF (qemu-io, bench mode serial) on netduinoplus2: protocol-v3 weights frames over USART1, {} velocity lines as in firmware/qemu/board-serial.txt (ok/slowed/stale after a reset press, stopped: latched while latched, the monitor's PFL, a person behind, another boot's echo); all {replayed} velocity frames byte for byte those of the host's Link on the same frames", got.len()))
}

/// USART1 traffic for a QEMU run: a Unix socket QEMU connects to as its serial chardev, and a thread
/// that writes bytes into it as fast as it takes them (and reads the velocity frames out, so QEMU
/// never blocks on a full socket) until `stop`. The bytes 0..=199 over and over, never a frame (each
/// costs the receive interrupt its full path), 64 every 20 ms of wall time, 4,000 in all: an
/// unpaced flood (QEMU models no baud rate) starves the thread-mode bench through the avoidance
/// step (reported to the avoidance's owner, firmware-report.md).
pub struct Traffic {
    path: std::path::PathBuf,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<usize>,
}

impl Traffic {
    /// Bind the socket `name` in the target directory and start the writer.
    pub fn start(name: &str) -> Result<Traffic, String> {
        use std::io::{Read, Write};
        use std::os::unix::net::UnixListener;
        use std::sync::atomic::{AtomicBool, Ordering};
        let path = target_dir().join(name);
        let _ = fs::remove_file(&path);
        let listener = UnixListener::bind(&path).map_err(|e| format!("binding {}: {e}", path.display()))?;
        listener.set_nonblocking(true).map_err(|e| e.to_string())?;
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            let start = Instant::now();
            let mut stream = loop {
                if flag.load(Ordering::Relaxed) || start.elapsed() > SERIAL_TIMEOUT {
                    return 0;
                }
                match listener.accept() {
                    Ok((s, _)) => break s,
                    Err(_) => sleep(Duration::from_millis(5)),
                }
            };
            let _ = stream.set_nonblocking(true);
            let mut sent = 0usize;
            let mut sink = [0u8; 1024];
            let frame: Vec<u8> = (0..200u8).collect();
            // Bounded and spread: 64 bytes every 20 ms of wall time, 4,000 bytes in all (QEMU models
            // no baud rate; an unpaced flood starves the thread-mode bench, see above).
            while !flag.load(Ordering::Relaxed) && sent < 4_000 {
                sleep(Duration::from_millis(20));
                let frame = &frame[(sent % 200)..][..64.min(200 - sent % 200)];
                let mut off = 0;
                while off < frame.len() && !flag.load(Ordering::Relaxed) {
                    match stream.write(&frame[off..]) {
                        Ok(n) => {
                            off += n;
                            sent += n;
                        }
                        Err(_) => sleep(Duration::from_millis(1)),
                    }
                    let _ = stream.read(&mut sink);
                }
            }
            // Keep reading the velocity frames out until the run ends.
            while !flag.load(Ordering::Relaxed) {
                let _ = stream.read(&mut sink);
                sleep(Duration::from_millis(5));
            }
            sent
        });
        Ok(Traffic { path, stop, thread })
    }

    /// The socket's path, for QEMU's `-chardev socket,path=`.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }

    /// Stop the writer; the bytes written into the socket.
    pub fn stop(self) -> usize {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        let sent = self.thread.join().unwrap_or(0);
        let _ = fs::remove_file(&self.path);
        sent
    }
}
