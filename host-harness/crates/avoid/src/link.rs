//! The serial line from the host to the board: how long one frame of weights takes at a baud rate,
//! the slowest rate that carries a frame per period, and the capture-to-command delay it adds.

use flinch_firmware::avoidance::{self as fw};
use crate::rbf::RbfGrid;
use crate::scene::Avoid;

/// Capture to command for a scene: the latency plus, when the baud rate is modelled, one frame's
/// time on the line, s.
pub fn frame_delay_s(scene: &Avoid) -> Result<f64, String> {
    Ok(scene.latency_s
        + match scene.baud {
            Some(b) => {
                let cam = scene.camera();
                let grid = RbfGrid::new(cam.width_px, cam.height_px, scene.fit.grid, cam.m_per_px, scene.fit.sigma_factor)?;
                link_time(grid.nx, grid.ny, b)?.1
            }
            None => 0.0,
        })
}

/// A frame's size in bytes and its time on a serial line at `baud` (8N1: 10 bits a byte), s.
pub fn link_time(nx: usize, ny: usize, baud: u32) -> Result<(usize, f64), String> {
    let bytes = fw::frame_len(nx, ny).ok_or_else(|| format!("grid {nx} x {ny}: no frame for it (1..=30 a side)"))?;
    Ok((bytes, bytes as f64 * 10.0 / baud.max(1) as f64))
}

/// The lowest baud rate that carries one frame of `bytes` per `period_s` (8N1), rounded up.
pub fn min_baud(bytes: usize, period_s: f64) -> u64 {
    (bytes as f64 * 10.0 / period_s).ceil() as u64
}
