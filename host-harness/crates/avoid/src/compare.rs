//! Speed against accuracy: every number type and Gaussian of the firmware step against the `f64`
//! reference (full-sum field, `f64` controller), on the same scene. `flinch avoid SCENE --compare`.
//!
//! * Command error: the field of the frame at minimum clearance is sent through the serial frame
//!   (Q16.16 on the wire) to a receiver in the variant's number type; the command is evaluated at
//!   every point of a 60 x 60 raster of the workspace and at every point of the reference path, each
//!   with a fresh controller, and compared with the reference command (m/s).
//! * Path error: the whole closed loop is run with the variant; largest distance between the two
//!   paths at the same time step (m), plus its own minimum clearance and time to goal.

use flinch_firmware::avoidance::{self as fw, num::{I16F16, I20F12, I8F24}, Controller, Gauss, Real, Receiver};

use crate::path::{gains, simulate_with, FwEngine, PathResult, RefEngine, Setup};
use crate::rbf::Field;
use crate::scene::Avoid;

/// One row of the comparison.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Variant name.
    pub variant: String,
    /// Largest command error, m/s.
    pub cmd_max_err_mps: f64,
    /// RMS command error, m/s.
    pub cmd_rms_err_mps: f64,
    /// Largest distance to the reference path at the same step, m.
    pub path_max_dev_m: f64,
    /// The variant's minimum clearance, m.
    pub min_clearance_m: f64,
    /// The variant's time to goal, s.
    pub time_to_goal_s: Option<f64>,
}

fn deviation(a: &PathResult, b: &PathResult) -> f64 {
    let n = a.points.len().max(b.points.len());
    (0..n)
        .map(|k| {
            let p = a.points[k.min(a.points.len() - 1)];
            let q = b.points[k.min(b.points.len() - 1)];
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

fn command_error<R: Real, G: Gauss<R>>(scene: &Avoid, field: &Field, pts: &[[f64; 2]], gauss: &G) -> Result<(f64, f64), String> {
    let mut rx = Box::new(Receiver::<R>::new(u16::MAX, 1000));
    rx.feed(&field.to_frame(1, 0)?, 0);
    if rx.stats.good != 1 {
        return Err("comparison frame refused".into());
    }
    let g64 = gains::<f64>(scene)?;
    let gr = gains::<R>(scene)?;
    let goal = scene.goal_m;
    let (mut max, mut sq) = (0.0f64, 0.0f64);
    for p in pts {
        let (h, fx, fy) = field.sample(p[0], p[1]);
        let r = Controller::new(g64).command(p[0], p[1], goal[0], goal[1], &fw::FieldSample { height: h, grad_x: fx, grad_y: fy }, 1.0);
        let q = R::from_f64;
        let s = fw::sample(rx.grid(), gauss, q(p[0]), q(p[1]));
        let c = Controller::new(gr).command(q(p[0]), q(p[1]), q(goal[0]), q(goal[1]), &s, R::ONE);
        let e = ((c.vx.to_f64() - r.vx).powi(2) + (c.vy.to_f64() - r.vy).powi(2)).sqrt();
        max = max.max(e);
        sq += e * e;
    }
    Ok((max, (sq / pts.len().max(1) as f64).sqrt()))
}

fn row<R: Real, G: Gauss<R> + Clone>(
    name: &str,
    scene: &Avoid,
    setup: &Setup,
    reference: &PathResult,
    pts: &[[f64; 2]],
    gauss: G,
) -> Result<Row, String> {
    let (cmd_max, cmd_rms) = command_error::<R, G>(scene, &reference.snapshot.field, pts, &gauss)?;
    let res = simulate_with(scene, setup, &mut FwEngine::<R, G>::new(scene, gauss)?)?;
    Ok(Row {
        variant: name.into(),
        cmd_max_err_mps: cmd_max,
        cmd_rms_err_mps: cmd_rms,
        path_max_dev_m: deviation(reference, &res),
        min_clearance_m: res.min_signed_distance_m,
        time_to_goal_s: res.time_to_goal_s,
    })
}

/// Reference path plus one row per variant.
pub fn compare(scene: &Avoid, setup: &Setup) -> Result<(PathResult, Vec<Row>), String> {
    let reference = simulate_with(scene, setup, &mut RefEngine::new(scene)?)?;
    let (w, h) = scene.extent_m();
    let mut pts: Vec<[f64; 2]> = (0..3600).map(|k| [((k % 60) as f64 + 0.5) * w / 60.0, ((k / 60) as f64 + 0.5) * h / 60.0]).collect();
    pts.extend(reference.points.iter().copied());
    let rows = vec![
        row::<f64, _>("f64 libm, truncated 4 sigma", scene, setup, &reference, &pts, fw::GaussLibm)?,
        row::<f64, _>("f64 lookup table", scene, setup, &reference, &pts, fw::GaussLut::<f64>::new())?,
        row::<f32, _>("f32 libm", scene, setup, &reference, &pts, fw::GaussLibm)?,
        row::<f32, _>("f32 micromath", scene, setup, &reference, &pts, fw::GaussMicromath)?,
        row::<f32, _>("f32 lookup table", scene, setup, &reference, &pts, fw::GaussLut::<f32>::new())?,
        row::<I16F16, _>("I16F16 lookup table", scene, setup, &reference, &pts, fw::GaussLut::<I16F16>::new())?,
        row::<I20F12, _>("I20F12 lookup table", scene, setup, &reference, &pts, fw::GaussLut::<I20F12>::new())?,
        row::<I8F24, _>("I8F24 lookup table", scene, setup, &reference, &pts, fw::GaussLut::<I8F24>::new())?,
    ];
    Ok((reference, rows))
}

/// The path difference between two grid sizes' reference runs, m.
pub fn path_deviation(a: &PathResult, b: &PathResult) -> f64 {
    deviation(a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The firmware step on the host against the f64 reference, command by command: I16F16 with the
    /// table within 20 mm/s everywhere and 2 mm/s rms (of a 250 mm/s command); f32 (libm, and the
    /// table the board runs) within 5 mm/s.
    #[test]
    fn firmware_step_matches_the_f64_reference() {
        let mut scene = Avoid::parse(include_str!("../../../../scenes/avoid_thesis_reach.toml")).unwrap();
        scene.camera.width_px = 105;
        scene.camera.height_px = 105;
        scene.camera.m_per_px = 0.01;
        scene.robot.calibration_step_m = 0.06;
        scene.robot.calibration_dilate_m = 0.045;
        // The field law's numbers, on the thesis's loop (as the thesis wrote it, no latency).
        scene.thesis_mode();
        scene.latency_s = 0.0;
        let setup = Setup::new(&scene, None).unwrap();
        let reference = simulate_with(&scene, &setup, &mut RefEngine::new(&scene).unwrap()).unwrap();
        let pts: Vec<[f64; 2]> = (0..900).map(|k| [((k % 30) as f64 + 0.5) * 0.035, ((k / 30) as f64 + 0.5) * 0.035]).collect();
        let f = &reference.snapshot.field;
        let (max, rms) = command_error::<I16F16, _>(&scene, f, &pts, &fw::GaussLut::<I16F16>::new()).unwrap();
        assert!(max < 0.020 && rms < 0.002, "I16F16: max {max} rms {rms} m/s");
        let (max, _) = command_error::<f32, _>(&scene, f, &pts, &fw::GaussLibm).unwrap();
        assert!(max < 0.005, "f32: max {max} m/s");
        // The board's default (`BoardReal` = f32, the table), side by side with I16F16: within the
        // same 5 mm/s, and no worse than I16F16 at the rms.
        let (max32, rms32) = command_error::<f32, _>(&scene, f, &pts, &fw::GaussLut::<f32>::new()).unwrap();
        assert!(max32 < 0.005, "f32 table: max {max32} m/s");
        assert!(rms32 <= rms, "f32 table rms {rms32} vs I16F16 {rms}");
        // The type the `--mcu` engine runs is one of the two checked here.
        assert!(["f32", "I16F16"].contains(&crate::path::board_real_name()));
        // I20F12 is visibly worse than I16F16 (the comparison can tell formats apart).
        let (_, rms12) = command_error::<I20F12, _>(&scene, f, &pts, &fw::GaussLut::<I20F12>::new()).unwrap();
        assert!(rms12 > rms, "I20F12 rms {rms12} vs I16F16 {rms}");
    }
}
