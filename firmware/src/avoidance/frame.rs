//! The serial frame that carries one grid of weights from the host (defined once, here; the host
//! encodes with [`encode_frame`]).
//!
//! All integers little-endian; lengths and positions are Q16.16 metres (`raw / 65536`).
//!
//! | offset | size | field |
//! |---|---|---|
//! | 0 | 2 | sync `0xA5 0x5A` |
//! | 2 | 1 | version ([`VERSION`], 3) |
//! | 3 | 1 | `nx`, centres along x, 1..=30 |
//! | 4 | 1 | `ny`, centres along y, 1..=30 |
//! | 5 | 1 | `session`: the host picks a new one each time it starts (ours: Unix seconds mod 256); another session is applied, with any `seq`, only once the weights in use are stale, and never one applied before since boot (see `receiver`) |
//! | 6 | 4 | `seq`, u32, increases by at least one per frame (wrapping) |
//! | 10 | 2 | `age_ms`, u16: age of the depth image when the frame was sent (the receiver counts the weights' age from the first byte's arrival less this) |
//! | 12 | 4 | `x0`, Q16.16 m: position of centre (0, 0) |
//! | 16 | 4 | `y0`, Q16.16 m |
//! | 20 | 4 | `spacing`, Q16.16 m, > 0 |
//! | 24 | 4 | `sigma`, Q16.16 m, > 0: the sigma to evaluate with (eq 70, or widened per Fig. 90) |
//! | 28 | 4 | `echo_ms`, u32: the MCU's clock (`t_ms` of a velocity frame, `link`) read by the host *before* the depth image was captured: the capture is no earlier, so `now - echo_ms` on the MCU is an **upper** bound of the image's age, whatever the host's buffers and the line delayed (version 3) |
//! | 32 | 1 | `echo_boot`: that velocity frame's `boot` byte; a frame echoing another boot's clock is not used by the monitor |
//! | 33 | 3 | reserved, 0 |
//! | 36 | 4 | `tool_x`, Q16.16 m: the tool's position when the image was captured (the sectors are measured from it) |
//! | 40 | 4 | `tool_y`, Q16.16 m |
//! | 44 | 4 | `nearest_x`, Q16.16 m: the nearest sensed point (steering only) |
//! | 48 | 4 | `nearest_y`, Q16.16 m |
//! | 52 | 16 | person separation per sector (`safe::SECTORS` sectors of 45 degrees, `safe::sector_of`), u16 mm from the tool's surface, rounded down; `0xFFFF`: nothing sensed |
//! | 68 | 16 | fixture separation per sector (obstacles the scene declares fixed: clearance without a human approach speed), u16 mm, the same way |
//! | 84 | 4 nx ny | weights, i32 Q16.16 m, row-major (`j * nx + i`, y outer) |
//! | end-4 | 4 | CRC-32/ISO-HDLC (the zlib CRC) of bytes 2..end-4 |
//!
//! A 5 x 5 frame is 188 bytes, a 15 x 15 one 988 bytes, a 30 x 30 one 3,688 bytes.

use super::field::MAX_AXIS;

/// First sync byte.
pub const SYNC0: u8 = 0xA5;
/// Second sync byte.
pub const SYNC1: u8 = 0x5A;
/// Protocol version carried in byte 2 (3: the MCU clock echo and the sensed separation per sector
/// for the monitor; 2: byte 5 is the session; version 1 had it reserved, 0).
pub const VERSION: u8 = 3;
/// Bytes before the weights.
pub const HEADER_LEN: usize = 84;
/// Sectors of the sensed separation (the monitor's, `safe::SECTORS`).
pub const FRAME_SECTORS: usize = 8;
/// A sector's separation when nothing was sensed in it, mm.
pub const NOTHING_MM: u16 = u16::MAX;
/// Bytes of the trailing CRC.
pub const CRC_LEN: usize = 4;
/// Longest frame (30 x 30).
pub const MAX_FRAME: usize = HEADER_LEN + 4 * MAX_AXIS * MAX_AXIS + CRC_LEN;

/// The CRC used by the frame.
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Header fields of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameHeader {
    /// The MCU's clock read by the host before the image was captured (a velocity frame's `t_ms`), ms.
    pub echo_ms: u32,
    /// That velocity frame's boot byte.
    pub echo_boot: u8,
    /// Tool position at capture, Q16.16 m.
    pub tool_q16: [i32; 2],
    /// The nearest sensed point at capture, Q16.16 m.
    pub nearest_q16: [i32; 2],
    /// Person separation per sector from the tool's surface at capture, mm ([`NOTHING_MM`]: none).
    pub person_mm: [u16; FRAME_SECTORS],
    /// Fixture separation per sector, mm ([`NOTHING_MM`]: none).
    pub fixture_mm: [u16; FRAME_SECTORS],
    /// Session of the sending host (byte 5): a restarted host sends a new one.
    pub session: u8,
    /// Centres along x.
    pub nx: u8,
    /// Centres along y.
    pub ny: u8,
    /// Sequence number.
    pub seq: u32,
    /// Age of the image when sent, ms.
    pub age_ms: u16,
    /// Centre (0, 0) x, Q16.16 m.
    pub x0_q16: i32,
    /// Centre (0, 0) y, Q16.16 m.
    pub y0_q16: i32,
    /// Spacing, Q16.16 m.
    pub spacing_q16: i32,
    /// Sigma, Q16.16 m.
    pub sigma_q16: i32,
}

impl Default for FrameHeader {
    /// A 1 x 1 grid at the origin, fail-safe: a person touching the tool in every sector (a host
    /// that forgets to fill in its sensing stops a monitored board instead of clearing it; review
    /// finding), no fixture, the clock echo 0 of boot 0. An encoding and test convenience: the host
    /// sets every field it knows.
    fn default() -> Self {
        FrameHeader {
            echo_ms: 0,
            echo_boot: 0,
            tool_q16: [0; 2],
            nearest_q16: [0; 2],
            person_mm: [0; FRAME_SECTORS],
            fixture_mm: [NOTHING_MM; FRAME_SECTORS],
            session: 0,
            nx: 1,
            ny: 1,
            seq: 0,
            age_ms: 0,
            x0_q16: 0,
            y0_q16: 0,
            spacing_q16: 1 << 16,
            sigma_q16: 1 << 16,
        }
    }
}

/// A separation in metres as the frame's u16 mm: rounded down (never more than measured), at most
/// 65.534 m; [`NOTHING_MM`] for anything not finite or beyond.
pub fn mm_of_m(m: f64) -> u16 {
    if m.is_nan() || m < 0.0 {
        0
    } else if m * 1000.0 >= f64::from(NOTHING_MM) {
        NOTHING_MM
    } else {
        (m * 1000.0) as u16
    }
}

/// Total frame length for an `nx` by `ny` grid, `None` if the grid is out of range.
pub const fn frame_len(nx: usize, ny: usize) -> Option<usize> {
    if nx == 0 || ny == 0 || nx > MAX_AXIS || ny > MAX_AXIS {
        None
    } else {
        // nx, ny <= 30: at most 3,632, no overflow.
        Some(HEADER_LEN.saturating_add(nx.saturating_mul(ny).saturating_mul(4)).saturating_add(CRC_LEN))
    }
}

fn put(out: &mut [u8], at: usize, bytes: &[u8]) -> Option<()> {
    out.get_mut(at..at.checked_add(bytes.len())?)?.copy_from_slice(bytes);
    Some(())
}

/// Encode one frame into `out`; the frame length, or `None` if the grid is out of range, `weights_q16`
/// does not hold `nx * ny` values, or `out` is too short.
pub fn encode_frame(h: &FrameHeader, weights_q16: &[i32], out: &mut [u8]) -> Option<usize> {
    let (nx, ny) = (h.nx as usize, h.ny as usize);
    let len = frame_len(nx, ny)?;
    if weights_q16.len() != nx.saturating_mul(ny) || out.len() < len {
        return None;
    }
    put(out, 0, &[SYNC0, SYNC1, VERSION, h.nx, h.ny, h.session])?;
    put(out, 6, &h.seq.to_le_bytes())?;
    put(out, 10, &h.age_ms.to_le_bytes())?;
    put(out, 12, &h.x0_q16.to_le_bytes())?;
    put(out, 16, &h.y0_q16.to_le_bytes())?;
    put(out, 20, &h.spacing_q16.to_le_bytes())?;
    put(out, 24, &h.sigma_q16.to_le_bytes())?;
    put(out, 28, &h.echo_ms.to_le_bytes())?;
    put(out, 32, &[h.echo_boot, 0, 0, 0])?;
    put(out, 36, &h.tool_q16[0].to_le_bytes())?;
    put(out, 40, &h.tool_q16[1].to_le_bytes())?;
    put(out, 44, &h.nearest_q16[0].to_le_bytes())?;
    put(out, 48, &h.nearest_q16[1].to_le_bytes())?;
    for (k, (p, f)) in h.person_mm.iter().zip(h.fixture_mm.iter()).enumerate() {
        put(out, 52usize.checked_add(k.checked_mul(2)?)?, &p.to_le_bytes())?;
        put(out, 68usize.checked_add(k.checked_mul(2)?)?, &f.to_le_bytes())?;
    }
    for (k, w) in weights_q16.iter().enumerate() {
        put(out, k.checked_mul(4)?.checked_add(HEADER_LEN)?, &w.to_le_bytes())?;
    }
    let body_end = len.checked_sub(CRC_LEN)?;
    let crc = CRC.checksum(out.get(2..body_end)?);
    put(out, body_end, &crc.to_le_bytes())?;
    Some(len)
}

fn le_u32(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at.checked_add(4)?)?;
    let mut a = [0u8; 4];
    a.copy_from_slice(s);
    Some(u32::from_le_bytes(a))
}

/// Read the header of a buffer that starts with the sync bytes; `None` if short or invalid.
pub fn decode_header(b: &[u8]) -> Option<FrameHeader> {
    if b.len() < HEADER_LEN || b.first() != Some(&SYNC0) || b.get(1) != Some(&SYNC1) {
        return None;
    }
    if b.get(2) != Some(&VERSION) {
        return None;
    }
    let nx = *b.get(3)?;
    let ny = *b.get(4)?;
    frame_len(nx as usize, ny as usize)?;
    let age = b.get(10..12)?;
    // Reserved bytes must be zero (a later version's field is not silently ignored).
    if b.get(33..36)? != [0, 0, 0] {
        return None;
    }
    // Two bytes a sector, straight from the header's slices (the receiver decodes a header in one
    // step: no per-value index arithmetic).
    let mut person_mm = [NOTHING_MM; FRAME_SECTORS];
    let mut fixture_mm = [NOTHING_MM; FRAME_SECTORS];
    for (d, c) in person_mm.iter_mut().zip(b.get(52..68)?.chunks_exact(2)) {
        if let [lo, hi] = c {
            *d = u16::from_le_bytes([*lo, *hi]);
        }
    }
    for (d, c) in fixture_mm.iter_mut().zip(b.get(68..84)?.chunks_exact(2)) {
        if let [lo, hi] = c {
            *d = u16::from_le_bytes([*lo, *hi]);
        }
    }
    Some(FrameHeader {
        echo_ms: le_u32(b, 28)?,
        echo_boot: *b.get(32)?,
        tool_q16: [le_u32(b, 36)? as i32, le_u32(b, 40)? as i32],
        nearest_q16: [le_u32(b, 44)? as i32, le_u32(b, 48)? as i32],
        person_mm,
        fixture_mm,
        session: *b.get(5)?,
        nx,
        ny,
        seq: le_u32(b, 6)?,
        age_ms: u16::from_le_bytes([*age.first()?, *age.get(1)?]),
        x0_q16: le_u32(b, 12)? as i32,
        y0_q16: le_u32(b, 16)? as i32,
        spacing_q16: le_u32(b, 20)? as i32,
        sigma_q16: le_u32(b, 24)? as i32,
    })
}

/// Whether the whole frame `b` (exactly one frame long) carries a correct CRC.
pub fn crc_ok(b: &[u8]) -> bool {
    let n = b.len();
    if n < HEADER_LEN + CRC_LEN {
        return false;
    }
    let end = n.saturating_sub(CRC_LEN);
    match (b.get(2..end), le_u32(b, end)) {
        (Some(body), Some(c)) => CRC.checksum(body) == c,
        _ => false,
    }
}

/// Weight `k` of a validated frame, Q16.16.
pub fn weight_q16(b: &[u8], k: usize) -> Option<i32> {
    le_u32(b, k.checked_mul(4)?.checked_add(HEADER_LEN)?).map(|v| v as i32)
}
