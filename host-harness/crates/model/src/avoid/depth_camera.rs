//! `[avoid.depth_camera]`: the pinhole camera of recorded depth frames as a scene gives it
//! (intrinsics, pose over the work plane, depth scale); `flinch-avoid`'s camera.rs uses it.

/// `[avoid.depth_camera]` as written in the scene (ranges: `scene/avoid/`, `DEPTH_CAMERA_KEYS`).
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthCameraCfg {
    /// Focal length along the columns, px.
    pub fx_px: f64,
    /// Focal length along the rows, px.
    pub fy_px: f64,
    /// Principal point, column, px.
    pub cx_px: f64,
    /// Principal point, row, px.
    pub cy_px: f64,
    /// Metres per count (RealSense z16 0.001, TUM 0.0002).
    pub depth_scale_m: f64,
    /// The optical centre over the plane, `[x, y]`, m.
    pub position_m: [f64; 2],
    /// The optical centre above the plane, m.
    pub height_m: f64,
    /// Rotation about the plane's x axis, degrees.
    #[serde(default)]
    pub roll_deg: f64,
    /// Rotation about the plane's y axis, degrees.
    #[serde(default)]
    pub pitch_deg: f64,
    /// Rotation about the vertical, degrees.
    #[serde(default)]
    pub yaw_deg: f64,
}
