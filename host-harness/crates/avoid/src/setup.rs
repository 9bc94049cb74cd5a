//! [`Setup`]: what a run prepares once from its scene (the camera, the RBF fitter, the calibration
//! or the robot model removal, the empty plane's weights).

use crate::calib::{zigzag, Calibration};
use crate::depth::Rng;
use crate::rbf::{Fitter, RbfGrid};
use crate::scene::Avoid;
use crate::link::*;

/// What is computed once per scene: the pseudo-inverses, the calibration (only with
/// `robot.removal = "calibration"`) and the weights of the raised empty plane.
pub struct Setup {
    /// Separable fitter.
    pub fitter: Fitter,
    /// Robot masks (empty with `robot.removal = "model"`).
    pub calibration: Calibration,
    /// Weights of the empty plane raised by `fit.offset_m`, subtracted before eq 71 when
    /// `fit.remove_plane` (the plane's own weights are larger at the borders: phantom walls).
    pub plane_weights: Vec<f64>,
}

impl Setup {
    /// Compute the pseudo-inverse and run the calibration pass (or use a loaded calibration).
    pub fn new(scene: &Avoid, calibration: Option<Calibration>) -> Result<Self, String> {
        let cam = scene.camera();
        let grid = RbfGrid::new(cam.width_px, cam.height_px, scene.fit.grid, cam.m_per_px, scene.fit.sigma_factor)?;
        let fitter = Fitter::new(grid)?;
        let plane = crate::depth::HeightMap { width: cam.width_px, height: cam.height_px, m: vec![scene.fit.offset_m; cam.width_px * cam.height_px] };
        let plane_weights = fitter.weights(&plane);
        let calibration = match calibration {
            _ if scene.robot.removal == "model" => Calibration { width: cam.width_px, height: cam.height_px, threshold_m: 0.0, positions: Vec::new(), masks: Vec::new() },
            Some(c) => {
                if (c.width, c.height) != (cam.width_px, cam.height_px) {
                    return Err(format!(
                        "calibration is for {} x {} px images, the scene's camera is {} x {}",
                        c.width, c.height, cam.width_px, cam.height_px
                    ));
                }
                c
            }
            None => {
                let (w, h) = scene.extent_m();
                let d = scene.robot.calibration_step_m;
                let pos = zigzag([d / 2.0, d / 2.0], [w - d / 2.0, h - d / 2.0], d);
                let mut rng = Rng::new(scene.camera.seed ^ 0xCA11);
                Calibration::run(
                    &cam,
                    &scene.robot_shape(),
                    &fitter,
                    &pos,
                    scene.fit.offset_m,
                    scene.robot.calibration_threshold_m,
                    scene.robot.calibration_dilate_m,
                    &mut rng,
                )
            }
        };
        if let Some(baud) = scene.baud {
            let (bytes, tx) = link_time(fitter.grid.nx, fitter.grid.ny, baud)?;
            if tx > scene.frame_period_s {
                return Err(format!(
                    "avoid.baud = {baud}: a {} x {} frame ({bytes} bytes, 10 bits a byte) takes {:.1} ms, longer than frame_period_s = {} s; the line needs at least {} baud",
                    fitter.grid.nx,
                    fitter.grid.ny,
                    tx * 1e3,
                    scene.frame_period_s,
                    min_baud(bytes, scene.frame_period_s)
                ));
            }
        }
        Ok(Setup { fitter, calibration, plane_weights })
    }
}
