//! The board ELF in QEMU (netduinoplus2): its boot register trace, vectors, a corrupted flash image
//! that must stop, and the `qemu-io` build's edge bench.

use crate::common::{elf_path, read_expected, repo_root, run_captured, target_dir, QEMU_TIMEOUT, TARGET};
use crate::firmware::qemu_io_dir;
use crate::flash::flash_image;
use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};
use std::thread::sleep;
use std::time::Duration;

/// How long the board ELF runs in QEMU (wall time; SysTick runs on QEMU's virtual clock).
const BOARD_RUN: Duration = Duration::from_secs(3);

/// Run the real board ELF (`board`, built for the STM32F407) on QEMU's `netduinoplus2`, an STM32F405
/// with the same core, RCC, GPIO, EXTI, TIM2 and IWDG addresses. QEMU 7.2 does not model the F405's
/// RCC, GPIO or IWDG: it logs every access to them (`-d unimp`), so the log is the board's register
/// trace. GPIO inputs read 0, i.e. the switch reads "tripped", the reset button is not pressed and
/// both EDM relays read "not released" while the stop channels are low: the firmware must stay
/// stopped for the whole run, and latch a fault (on the part the EDM would; in QEMU, whose core
/// clock is not the board's, the tick supervision first), which must starve the watchdog for good
/// (`Firmware::feeds_watchdog`).
pub fn run_board_qemu() -> Result<String, String> {
    run_board_elf(&elf_path("board"), "board-qemu.log")
}

pub fn run_board_elf(elf: &Path, log_name: &str) -> Result<String, String> {
    let log = target_dir().join(log_name);
    let _ = fs::remove_file(&log);
    let mut child = Command::new("qemu-system-arm")
        .args(["-M", "netduinoplus2", "-nographic", "-monitor", "none", "-serial", "none", "-d", "unimp,guest_errors", "-D"])
        .arg(&log)
        .arg("-kernel")
        .arg(elf)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("could not start qemu-system-arm: {e}"))?;
    sleep(BOARD_RUN);
    if let Ok(Some(status)) = child.try_wait() {
        return Err(format!("qemu-system-arm -M netduinoplus2 exited early with {status} (see {})", log.display()));
    }
    let _ = child.kill();
    let _ = child.wait();
    fs::read_to_string(&log).map_err(|e| format!("reading {}: {e}", log.display()))
}

/// The three outputs' BSRR pages and "set" bits (PD12 K1, PE12 K2, PB12 escalation): a write that
/// sets one of them energises it ("go" or no category 0).
const OUTPUT_SETS: [(&str, u32, &str); 3] = [("GPIOD:", 1 << 12, "PD12 K1"), ("GPIOE:", 1 << 12, "PE12 K2"), ("GPIOB:", 1 << 12, "PB12 escalation")];

/// Check the board's register trace (`-d unimp`): the boot sequence against
/// `firmware/qemu/board-boot.txt`; no output is ever energised; the tick keeps running (it reads the
/// switch, GPIOA IDR, every tick); and the EDM latch (the relays read "not released" in QEMU) is
/// stored in the backup SRAM after the settle time, after which the IWDG is never fed again.
pub fn check_board_log(log: &str) -> Result<String, String> {
    let lines: Vec<&str> = log.lines().collect();
    let value = |l: &str| l.rsplit("value 0x").next().and_then(|v| u32::from_str_radix(v.trim_end_matches(')'), 16).ok());
    let is_write = |l: &str| l.contains("unimplemented device write");
    for (page, bit, name) in OUTPUT_SETS {
        let go = lines.iter().filter(|l| is_write(l)).filter(|l| l.starts_with(page) && l.contains("offset 0x018")).filter(|l| value(l).is_some_and(|v| v & bit != 0)).count();
        if go != 0 {
            return Err(format!("the board energised {name} {go} times with the reset never pressed"));
        }
    }
    let ticks = lines.iter().filter(|l| l.starts_with("GPIOA:") && l.contains("read") && l.contains("offset 0x010")).count();
    if ticks < 100 {
        return Err(format!("only {ticks} ticks (switch reads) in {} s: the board is not running", BOARD_RUN.as_secs()));
    }
    // The IWDG (QEMU names its page I2S2ext) is fed with 0xAAAA by a tick that finds the firmware
    // healthy. The first latched fault (the backup SRAM's latch word, offset 4, a cause other than
    // 8 = the start latch) ends the feeds for good. In QEMU the production build's clocks are not
    // QEMU's (SysTick runs from the 168 MHz core, the board assumes 16 MHz), so its tick supervision
    // latches at once; on the part the EDM would (the relays read "not released" in QEMU).
    let feed = |l: &&&str| l.starts_with("I2S2ext:") && is_write(l) && value(l) == Some(0xAAAA);
    let latch = lines
        .iter()
        .position(|l| l.starts_with("BKPSRAM:") && is_write(l) && l.contains("offset 0x004") && value(l).is_some_and(|c| c != 8))
        .ok_or("no fault latched in the backup SRAM in 3 s: the relays never read released in QEMU, so at least EDM must latch")?;
    let cause = value(lines[latch]).unwrap_or(0);
    let fed_before = lines[..latch].iter().filter(feed).count();
    let fed_after = lines[latch..].iter().filter(feed).count();
    if fed_before == 0 || fed_after != 0 {
        return Err(format!("IWDG feeds: {fed_before} before the first latched fault (cause {cause}) (want > 0), {fed_after} after it (want 0: a latched fault starves the watchdog)"));
    }
    // The boot: every access up to the first tick's first read of an input register (the output
    // read-back or the switch).
    let boot: Vec<&str> = log.lines().take_while(|l| !(l.starts_with("GPIO") && l.contains("read") && l.contains("offset 0x010"))).collect();
    let expected_path = repo_root().join("firmware/qemu/board-boot.txt");
    let expected = fs::read_to_string(&expected_path).map_err(|e| format!("reading {}: {e}", expected_path.display()))?;
    let want: Vec<&str> = expected.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()).collect();
    if !trace_matches(&boot, &want) {
        return Err(format!(
            "the board's boot register trace differs from firmware/qemu/board-boot.txt:\n--- got\n{}\n--- expected\n{}",
            boot.join("\n"),
            want.join("\n")
        ));
    }
    Ok(format!(
        "board ELF on netduinoplus2: boot trace as expected ({} accesses), {ticks} ticks, no output ever energised, a fault (cause {cause}) latched after {fed_before} fed ticks and the IWDG never fed again",
        boot.len()
    ))
}

/// The board ELF's stack bound, bytes: asserted on the `qemu-io` build's painted stack (main, the
/// log drain, the bench in thread mode, every interrupt), firmware/README.md "board stack": measured
/// 15316 B with the avoidance link (3280 B before it; 15308 B before the review fixes): `Link::new` builds the 12,144 B link (the
/// receiver's ring and two 30 x 30 grids) on the stack once, before it is moved into its static. The
/// bound leaves about a quarter on top (a fault handler); the part has 128 KiB of SRAM, the statics
/// take 14 KiB, and flip-link puts the stack below them so an overflow faults.
const BOARD_STACK_LIMIT: u32 = 20480;

/// The board ELF's painted stack use from the bench's `bench: stack used=N B` line.
fn check_board_stack(out: &str) -> Result<u32, String> {
    let line = out.lines().find(|l| l.starts_with("bench: stack used=")).ok_or("no 'bench: stack used=' line from the board bench")?;
    let n: u32 = line
        .strip_prefix("bench: stack used=")
        .and_then(|r| r.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| format!("unreadable: {line}"))?;
    if n == 0 || n > BOARD_STACK_LIMIT {
        return Err(format!("board stack used {n} B: want 0 < used <= {BOARD_STACK_LIMIT} B ({line})"));
    }
    Ok(n)
}

/// A register trace against its expected lines; an expected line ending in `value *)` matches any
/// value (a timestamp, or a CRC over one, that the free-running QEMU clock makes vary).
fn trace_matches<A: AsRef<str>, B: AsRef<str>>(got: &[A], want: &[B]) -> bool {
    got.len() == want.len()
        && got.iter().zip(want).all(|(g, w)| {
            let (g, w) = (g.as_ref(), w.as_ref());
            match w.strip_suffix("value *)") {
                Some(prefix) => g.starts_with(prefix) && g.ends_with(')'),
                None => g == w,
            }
        })
}

/// The start-up flash CRC acts: a copy of the board ELF with one byte of .rodata flipped (the CRC
/// word left as patched) must stop right after the boot's register set-up: the boot trace up to
/// the brown-out read, then one write of both outputs low, and nothing after it (no tick, no
/// de-energise by the library, no "go": the firmware is never built).
pub fn check_board_corrupt() -> Result<String, String> {
    use object::{Object, ObjectSection};
    let good = elf_path("board");
    let mut b = fs::read(&good).map_err(|e| format!("{}: {e}", good.display()))?;
    let (_, crc_file, _) = flash_image(&b, true)?;
    let off = {
        let elf = object::File::parse(&*b).map_err(|e| format!("not an ELF object: {e}"))?;
        let ro = elf.section_by_name(".rodata").ok_or("no .rodata in the board ELF")?;
        let (start, size) = ro.file_range().ok_or(".rodata has no file data")?;
        let mid = (start + size / 2) as usize;
        if (crc_file..crc_file + 4).contains(&mid) { mid + 8 } else { mid }
    };
    b[off] ^= 0x01;
    let bad = target_dir().join("board-corrupt.elf");
    fs::write(&bad, &b).map_err(|e| format!("writing {}: {e}", bad.display()))?;
    let log = run_board_elf(&bad, "board-corrupt.log")?;
    let expected = read_expected("firmware/qemu/board-selfcheck.txt")?;
    let got: Vec<&str> = log.lines().collect();
    if !trace_matches(&got, &expected) {
        return Err(format!(
            "a board ELF with one flipped flash byte (file offset {off:#x}) did not stop as firmware/qemu/board-selfcheck.txt says:\n--- got (first 60)\n{}\n--- expected\n{}",
            got.iter().take(60).copied().collect::<Vec<_>>().join("\n"),
            expected.join("\n")
        ));
    }
    Ok(format!("one flipped flash byte: stopped after {} accesses, outputs low, SelfCheck latched and logged in the backup SRAM, no tick in {} s", got.len(), BOARD_RUN.as_secs()))
}

/// The board's vector table (`__INTERRUPTS`): both switch channels' EXTI lines (EXTI0 = IRQ 6, PA0;
/// EXTI4 = IRQ 10, PA4) go to the edge handler and the bookkeeping line (UART5 = IRQ 53) to the
/// bookkeeping. QEMU does not model the F405's GPIO, so the edges cannot be driven there; this
/// checks that they are wired.
pub fn check_board_vectors(path: &Path) -> Result<String, String> {
    use object::{Object, ObjectSection, ObjectSymbol};
    let b = fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let elf = object::File::parse(&*b).map_err(|e| format!("{}: not an ELF object: {e}", path.display()))?;
    let sym = |part: &str| elf.symbols().find(|s| s.name().is_ok_and(|n| n.contains(part))).map(|s| s.address());
    let table = sym("__INTERRUPTS").ok_or("no __INTERRUPTS in the board ELF")?;
    let entry = |irq: u64| -> Result<u64, String> {
        let addr = table + 4 * irq;
        let sec = elf
            .sections()
            .find(|s| s.address() <= addr && addr + 4 <= s.address() + s.size())
            .ok_or_else(|| format!("vector {irq} outside every section"))?;
        let data = sec.data().map_err(|e| format!("reading {}: {e}", sec.name().unwrap_or("?")))?;
        let off = (addr - sec.address()) as usize;
        let w = data.get(off..off + 4).ok_or("vector table truncated")?;
        Ok(u64::from(u32::from_le_bytes([w[0], w[1], w[2], w[3]])) & !1)
    };
    for (irq, handler, what) in [(6, "exti0_entry", "EXTI0 (switch channel A)"), (10, "exti4_entry", "EXTI4 (switch channel B)"), (53, "book_entry", "UART5 (the edge's bookkeeping)"), (50, "tim5_entry", "TIM5 (the LSI capture, clock check)"), (37, "usart1_entry", "USART1 (the avoidance's weights in, velocity out)"), (29, "tim3_entry", "TIM3's line (the avoidance step, pended by the tick)")] {
        let want = sym(handler).ok_or_else(|| format!("no {handler} in the board ELF"))? & !1;
        let got = entry(irq)?;
        if got != want {
            return Err(format!("vector {irq}, {what}: {got:#x}, want {handler} at {want:#x}"));
        }
    }
    Ok("vectors: EXTI0 and EXTI4 -> edge, UART5 -> bookkeeping, TIM5 -> LSI capture, USART1 and TIM3 -> avoidance".into())
}

/// Run the `qemu-io` board ELF on netduinoplus2 until its bench exits (semihosting), deterministic
/// time (`-icount shift=3`); returns the bench's output and the `-d unimp` register trace.
pub fn run_board_edge() -> Result<(String, String), String> {
    run_board_bench("edges")
}

/// The `qemu-io` bench in `mode` (its semihosting command line, `board_bench.rs`): "edges", or a
/// fault that ends the run: "panic" (in thread mode), "overflow" (the stack into the MPU guard).
fn run_board_bench(mode: &str) -> Result<(String, String), String> {
    let log = target_dir().join(format!("board-{mode}.log"));
    let _ = fs::remove_file(&log);
    let elf = qemu_io_dir().join(TARGET).join("release").join("board");
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args(["-M", "netduinoplus2", "-nographic", "-monitor", "none"])
        .args(["-semihosting-config", &format!("enable=on,target=native,arg=board,arg={mode}"), "-icount", "shift=3"])
        .args(["-d", "unimp,guest_errors", "-D"])
        .arg(&log);
    // The edge run carries USART1 traffic (weights frames as fast as the model takes them), so that
    // the worst case measured in it includes the USART interrupt and the avoidance step's masked
    // sections; the fault runs need none.
    let traffic = if mode == "edges" { Some(crate::board_serial::Traffic::start("board-edges.sock")?) } else { None };
    match &traffic {
        Some(t) => cmd.args(["-chardev", &format!("socket,id=s0,path={}", t.path().display()), "-serial", "chardev:s0"]),
        None => cmd.args(["-serial", "none"]),
    };
    cmd.arg("-kernel").arg(&elf);
    let run = run_captured(cmd, "qemu-system-arm -M netduinoplus2 (board bench)", QEMU_TIMEOUT);
    let sent = traffic.map(|t| t.stop()).unwrap_or(0);
    let (out, status) = run?;
    if !status.success() {
        return Err(format!("the board bench ({mode}) failed ({status}):\n{out}"));
    }
    if mode == "edges" && sent == 0 {
        return Err("the edge run's USART traffic: no byte was taken by QEMU".into());
    }
    let trace = fs::read_to_string(&log).map_err(|e| format!("reading {}: {e}", log.display()))?;
    Ok((out, trace))
}

/// The bench's markers (GPIOI BSRR writes, `board_bench.rs`).
fn bench_marker(v: u32) -> &'static str {
    match v {
        1 => "reset pressed",
        2 => "reset released",
        3 => "edge on channel A pended (EXTI0)",
        4 => "edge on channel B pended (EXTI4)",
        5 => "obstacle gone",
        6 => "edge on channel B pended (EXTI4)",
        7 => "edge on channel A pended (EXTI0)",
        8 => "end",
        9 => "the LSI stops (the clock check's reference)",
        10 => "a panic in thread mode",
        11 => "a stack overflow in thread mode",
        12 => "the fault handler held 20 ms",
        13 => "a configuration bit flipped",
        14 => "both channels trip, no edge interrupt (the tick polls it)",
        _ => "unknown marker",
    }
}

/// The board edge run's trace reduced to what a person checks: the bench's markers and every change
/// of the four outputs (PD12 stop K1, PE12 stop K2, PB12 escalation, PD14 sensor supply; 1 =
/// energised). Repeated de-energise writes of the stopped ticks change nothing and do not appear.
fn board_edge_timeline(trace: &[&str]) -> Vec<String> {
    let value = |l: &str| l.rsplit("value 0x").next().and_then(|v| u32::from_str_radix(v.trim_end_matches(')'), 16).ok());
    let ports: [(&str, &[(u32, &str)]); 3] = [
        ("GPIOD:", &[(12, "PD12 stop K1"), (14, "PD14 sensor supply")]),
        ("GPIOE:", &[(12, "PE12 stop K2")]),
        ("GPIOB:", &[(12, "PB12 escalation")]),
    ];
    let mut odr = [0u32; 3];
    let mut out = Vec::new();
    for l in trace {
        let Some(v) = value(l) else { continue };
        if !l.contains("offset 0x018") {
            continue;
        }
        if l.starts_with("GPIOI:") {
            out.push(format!("bench {v}: {}", bench_marker(v)));
        }
        for (k, (page, pins)) in ports.iter().enumerate() {
            if l.starts_with(page) {
                let new = (odr[k] & !(v >> 16)) | (v & 0xFFFF);
                for (bit, name) in pins.iter() {
                    if (new ^ odr[k]) & (1 << bit) != 0 {
                        out.push(format!("{name} -> {}", (new >> bit) & 1));
                    }
                }
                odr[k] = new;
            }
        }
    }
    out
}

/// Check the board edge run: the bench passed; the boot is the production board's
/// (`firmware/qemu/board-boot.txt`); the markers and output changes equal
/// `firmware/qemu/board-edge.txt`; and after each edge pended while armed the very next two device
/// accesses are the stop writes (GPIOD BSRR 0x10000000, K1; GPIOE BSRR 0x10000000, K2): nothing,
/// not even a tick, comes between.
pub fn check_board_edge(out: &str, trace: &str) -> Result<String, String> {
    if !out.contains("bench: PASS") {
        return Err(format!("the board edge bench did not pass:\n{out}"));
    }
    let lines: Vec<&str> = trace.lines().collect();
    let mut expected_boot = read_expected("firmware/qemu/board-boot.txt")?;
    // The qemu-io build's one difference in the boot: right after the backup SRAM is switched on
    // (the PWR_CR write) its two "not on silicon" checks: it reads GPIOD's MODER back, writes a test
    // word ("QEMU") to the last backup SRAM word and reads it back, and stops for good if either
    // read is not 0 (real GPIO or real backup SRAM: the bench image is on silicon, not in QEMU).
    let pwr = expected_boot.iter().position(|l| l.starts_with("PWR: unimplemented device write")).ok_or("board-boot.txt has no PWR_CR write")?;
    for (i, l) in [
        "GPIOD: unimplemented device read  (size 4, offset 0x000)",
        "BKPSRAM: unimplemented device write (size 4, offset 0x3fc, value 0x51534d55)",
        "BKPSRAM: unimplemented device read  (size 4, offset 0x3fc)",
    ]
    .into_iter()
    .enumerate()
    {
        expected_boot.insert(pwr + 1 + i, l.into());
    }
    if lines.len() < expected_boot.len() || !trace_matches(&lines[..expected_boot.len()], &expected_boot) {
        return Err(format!(
            "the qemu-io board's boot differs from firmware/qemu/board-boot.txt:\n--- got\n{}",
            lines.iter().take(expected_boot.len()).copied().collect::<Vec<_>>().join("\n")
        ));
    }
    let rest = &lines[expected_boot.len()..];
    let got = board_edge_timeline(rest);
    let want = read_expected("firmware/qemu/board-edge.txt")?;
    if got != want {
        return Err(format!(
            "the board edge run differs from firmware/qemu/board-edge.txt:\n--- got\n{}\n--- expected\n{}",
            got.join("\n"),
            want.join("\n")
        ));
    }
    let stop_writes = [
        "GPIOD: unimplemented device write (size 4, offset 0x018, value 0x10000000)",
        "GPIOE: unimplemented device write (size 4, offset 0x018, value 0x10000000)",
    ];
    let mut direct = 0;
    for marker in ["value 0x00000003)", "value 0x00000006)"] {
        let i = rest
            .iter()
            .position(|l| l.starts_with("GPIOI:") && l.ends_with(marker))
            .ok_or_else(|| format!("no bench marker {marker} in the trace"))?;
        match rest.get(i + 1..i + 3) {
            Some(next) if next == stop_writes => direct += 1,
            next => {
                return Err(format!(
                    "after the edge pend ({}) the next device accesses are {:?}, not the two stop writes (K1, K2)",
                    rest[i],
                    next.unwrap_or(&[])
                ))
            }
        }
    }
    let ticks = rest.iter().filter(|l| l.starts_with("I2S2ext:") && (l.ends_with("value 0xaaaa)") || l.ends_with("value 0x0000aaaa)"))).count();
    let stack = check_board_stack(out)?;
    Ok(format!(
        "board ELF (qemu-io GPIO) on netduinoplus2: boot as board-boot.txt, {} events as board-edge.txt, both stop channels written as the next two accesses after {direct} edges (EXTI0, EXTI4), {ticks} ticks; board stack {stack} B <= {BOARD_STACK_LIMIT} B (painted)",
        got.len()
    ))
}

/// The faults that end a run (`board_bench.rs`, mode "panic" and "overflow") on the `qemu-io` board
/// ELF: armed and fed, then a panic in thread mode, or a stack overflow into the MPU guard. After
/// the bench's marker the trace must show the three outputs written low (K1, K2, escalation), the
/// `FaultHandler` latch (cause 9) stored in the backup SRAM, the fault handler's 20 ms hold (marker
/// 12) and not one IWDG feed from the marker on (on main a panic in thread mode left SysTick feeding
/// the watchdog, and an overflow locked the core up before any handler ran).
pub fn check_board_faults() -> Result<String, String> {
    let mut done = Vec::new();
    for (mode, marker, what) in [("panic", 10, "a panic in thread mode"), ("overflow", 11, "a stack overflow")] {
        let (out, trace) = run_board_bench(mode)?;
        if !out.contains("bench: PASS") {
            return Err(format!("{what}: the bench did not end in the fault handler:\n{out}"));
        }
        let lines: Vec<&str> = trace.lines().collect();
        let value = |l: &str| l.rsplit("value 0x").next().and_then(|v| u32::from_str_radix(v.trim_end_matches(')'), 16).ok());
        let is = |l: &str, page: &str, off: &str, v: u32| l.starts_with(page) && l.contains("write") && l.contains(off) && value(l) == Some(v);
        let at = lines
            .iter()
            .position(|l| is(l, "GPIOI:", "offset 0x018", marker))
            .ok_or_else(|| format!("{what}: no bench marker {marker} in the trace"))?;
        let after = &lines[at..];
        let feed = |l: &&&str| l.starts_with("I2S2ext:") && value(l) == Some(0xAAAA);
        let (before, since) = (lines[..at].iter().filter(feed).count(), after.iter().filter(feed).count());
        let dropped = ["GPIOD:", "GPIOE:", "GPIOB:"].iter().all(|p| after.iter().any(|l| is(l, p, "offset 0x018", 1 << 28)));
        let latched = after.iter().any(|l| is(l, "BKPSRAM:", "offset 0x004", 9));
        let held = after.iter().any(|l| is(l, "GPIOI:", "offset 0x018", 12));
        if before == 0 || since != 0 || !dropped || !latched || !held {
            return Err(format!(
                "{what}: IWDG feeds {before} before (want > 0) and {since} after (want 0), outputs dropped {dropped}, FaultHandler latched {latched}, handler held 20 ms {held}"
            ));
        }
        // The overflow must have hit the MPU guard: MMFSR.DACCVIOL (CFSR bit 1), the handler's report.
        let cfsr = out
            .lines()
            .find_map(|l| l.split("CFSR 0x").nth(1))
            .and_then(|v| u32::from_str_radix(v.trim(), 16).ok())
            .ok_or_else(|| format!("{what}: no CFSR in the bench's report:\n{out}"))?;
        if mode == "overflow" && cfsr & 0x02 == 0 {
            return Err(format!("{what}: CFSR {cfsr:#010x} has no MemManage data access violation: the MPU guard did not catch it"));
        }
        done.push(format!("{what}: outputs low, FaultHandler latched, 0 IWDG feeds after it ({before} before), CFSR {cfsr:#x}"));
    }
    // A configuration bit flipped while armed (EXTI0's NVIC priority): the periodic read-back
    // (`board_diag.rs`, every 16 ticks) latches Diagnostic (cause 15) and every output drops.
    let (out, trace) = run_board_bench("config")?;
    let stopped = out.lines().find(|l| l.starts_with("bench: a flipped configuration bit: stopped after")).ok_or_else(|| format!("a flipped configuration bit: the bench did not stop:\n{out}"))?;
    let lines: Vec<&str> = trace.lines().collect();
    let value = |l: &str| l.rsplit("value 0x").next().and_then(|v| u32::from_str_radix(v.trim_end_matches(')'), 16).ok());
    let at = lines.iter().position(|l| l.starts_with("GPIOI:") && value(l) == Some(13)).ok_or("no marker 13 in the trace")?;
    let latched = lines[at..].iter().any(|l| l.starts_with("BKPSRAM:") && l.contains("write") && l.contains("offset 0x004") && value(l) == Some(15));
    let esc_low = lines[at..].iter().any(|l| l.starts_with("GPIOB:") && l.contains("offset 0x018") && value(l) == Some(1 << 28));
    if !latched || !esc_low {
        return Err(format!("a flipped configuration bit: Diagnostic latched {latched}, escalation dropped {esc_low}"));
    }
    done.push(format!("a flipped configuration bit: Diagnostic latched, every output low ({})", stopped.trim_start_matches("bench: a flipped configuration bit: ")));
    Ok(done.join("; "))
}
