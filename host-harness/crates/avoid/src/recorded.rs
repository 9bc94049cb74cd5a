//! Recorded depth frames in the loop (`flinch avoid SCENE --depth FILE|DIR [--robot-poses CSV]`).
//!
//! Frames and their times. `--depth` names one 16-bit PNG or PGM (a single frame at t = 0, held) or
//! a directory. In a directory, `index.csv` (header `t_s,file`, one frame a row, file names relative
//! to the directory) gives the frames and their capture times; without it every `*.png` / `*.pgm` is
//! a frame and its name without the extension is its capture time in seconds (TUM RGB-D's
//! convention: `1305031102.175304.png`). Times must increase; the first frame is t = 0 of the run.
//!
//! Robot poses. `--robot-poses` (header `t_s,x_m,y_m`: the tool point on the plane, in the frames'
//! clock) is interpolated linearly at each frame's capture time; a frame outside the poses' span is
//! refused. With poses, points the robot's height model explains at that pose, grown sideways and
//! upwards by `robot.removal_margin_m` (flying pixels at its edges, a pose a little off), are the
//! robot's and are dropped (see `camera::reproject`), and so is the floor the robot hides from the
//! camera. The cost: a hand within that margin of the robot, and no higher than it, is not seen
//! there (20 mm by default; the part of the hand farther out is). Without
//! poses, nothing is removed: the robot is an obstacle like any other (conservative: a recording
//! with the robot in view and no poses stops the tool where the robot is).
//!
//! At each camera period of the scene the loop takes the newest recorded frame captured by then (a
//! frame is used once; its age counts from its own capture time). After the last frame no new
//! weights arrive: the frame ages and the monitor (v_h x age) and the weights watchdog stop the tool.
//!
//! Null pixels. A depth camera returns 0 where it measured nothing: glare, black or shiny surfaces,
//! edges, and the floor hidden behind anything standing on it. Whatever is there is unknown, and a
//! person may be in it, so **an unknown region is an obstacle**: the monitor measures its separation
//! to the nearest unknown cell as to a seen one (ISO/TS 15066 5.5.4 asks for the distance to the
//! person; unseen, the person may be anywhere in it), and the fit raises it to `stop_height_m` (the
//! field stops the tool at its edge and the vortex steers round it). Slowing only was not chosen: a
//! slowed tool still enters the region. Only holes the camera's own sampling leaves are filled: one
//! pass, each unknown cell with a seen 8-neighbour takes the highest of them (the highest: a partly
//! seen hand grows into the hole rather than being painted over as table). A null strip up to 2
//! cells wide with only floor beside it (a black glove's rim) is still painted as floor, so whenever
//! the fill paints floor the separation the monitor gets is shortened by the fill's reach, two cell
//! diagonals ([`FILL_REACH_CELLS`]; test `a_null_strip_over_the_hands_edge_is_not_painted_as_table`).
//! Still open: a black object narrower than that reach with nothing seen around it (a black finger
//! alone) is invisible; ISO 13855's reasoning (the hand it belongs to is seen) covers a person, not an
//! object. One pass is a fixed
//! bound on the time (each cell looks at its 8 neighbours once: 9 reads a cell, whatever the hole),
//! where the thesis's fill repeats until every hole is closed (82 ms for a 300 x 300 px hole, issue
//! 11) and paints what was inside it as the mean of its rim. A point more than the sense height
//! under the plane is a wrong measurement, not floor: dropped like a null pixel (counted), so it
//! never paints a cell as seen table. The floor the robot hides (with poses) is
//! the robot's, as it already is under the wrist in the synthetic camera (docs/avoidance.md, robot
//! removal): no camera sees there.

use std::path::{Path, PathBuf};

use crate::camera::{reproject, Cell, Pinhole, PlaneRaster};
use crate::depth::{DepthImage, HeightMap};
use crate::path::{Frame, FrameSource, Setup};
use crate::rbf::{filter_weights, Field};
use crate::scene::Avoid;

/// Most pixels of one recorded frame: 4096 x 4096 (depth cameras give up to 1280 x 1024).
pub const MAX_FRAME_PIXELS: usize = 4096 * 4096;

/// The recorded frames and robot poses.
#[derive(Clone, Debug)]
pub struct Recording {
    /// Capture time (s, the first is 0) and file of every frame, in time order.
    pub frames: Vec<(f64, PathBuf)>,
    /// Robot poses: time (s, on the frames' clock, shifted with them) and the tool point, m.
    pub poses: Option<Vec<(f64, [f64; 2])>>,
    /// The time subtracted from the files' times, s.
    pub t0_s: f64,
}

fn parse_csv(path: &Path, header: &str) -> Result<Vec<Vec<String>>, String> {
    // Through the one reader: regular files only, at most 64 MiB.
    let kind = if header.contains("file") { flinch_output::input::Kind::FrameIndex } else { flinch_output::input::Kind::Poses };
    let text = flinch_output::input::read_text(path, kind).map_err(|e| e.to_string())?;
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    match lines.next() {
        Some((_, h)) if h.trim() == header => {}
        Some((n, h)) => return Err(format!("{}:{}: header must be `{header}`, got `{}`", path.display(), n + 1, h.trim())),
        None => return Err(format!("{}: empty, expected the header `{header}` and one row or more", path.display())),
    }
    let cols = header.split(',').count();
    let mut rows = Vec::new();
    for (n, l) in lines {
        let f: Vec<String> = l.split(',').map(|s| s.trim().to_string()).collect();
        if f.len() != cols {
            return Err(format!("{}:{}: {} fields, expected {cols} ({header})", path.display(), n + 1, f.len()));
        }
        rows.push(f.into_iter().chain(std::iter::once((n + 1).to_string())).collect());
    }
    if rows.is_empty() {
        return Err(format!("{}: no rows after the header `{header}`", path.display()));
    }
    Ok(rows)
}

fn number(path: &Path, line: &str, key: &str, v: &str) -> Result<f64, String> {
    match v.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("{}:{line}: {key}: must be a finite number, got `{v}`", path.display())),
    }
}

impl Recording {
    /// Read the frame list (`depth`: a file or a directory) and the robot poses.
    pub fn open(depth: &Path, poses: Option<&Path>) -> Result<Self, String> {
        let mut frames: Vec<(f64, PathBuf)> = Vec::new();
        if depth.is_dir() {
            let index = depth.join("index.csv");
            // Present but not a regular file (a FIFO, a directory) is refused by the reader, not ignored.
            if std::fs::symlink_metadata(&index).is_ok() {
                for r in parse_csv(&index, "t_s,file")? {
                    frames.push((number(&index, &r[2], "t_s", &r[0])?, depth.join(&r[1])));
                }
            } else {
                let entries = std::fs::read_dir(depth).map_err(|e| format!("{}: cannot list: {e}", depth.display()))?;
                for e in entries {
                    let p = e.map_err(|e| format!("{}: {e}", depth.display()))?.path();
                    let ext = p.extension().and_then(|x| x.to_str()).map(str::to_ascii_lowercase);
                    if !matches!(ext.as_deref(), Some("png") | Some("pgm")) {
                        continue;
                    }
                    let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("");
                    match stem.parse::<f64>() {
                        Ok(t) if t.is_finite() => frames.push((t, p)),
                        _ => {
                            return Err(format!(
                                "{}: the name is not a capture time in seconds (as TUM's 1305031102.175304.png) and {} has no index.csv (`t_s,file`)",
                                p.display(),
                                depth.display()
                            ))
                        }
                    }
                }
                if frames.is_empty() {
                    return Err(format!("{}: no .png or .pgm depth frames and no index.csv", depth.display()));
                }
            }
        } else {
            frames.push((0.0, depth.to_path_buf()));
        }
        frames.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(w) = frames.windows(2).find(|w| w[1].0 <= w[0].0) {
            return Err(format!("{} and {}: two frames at t = {} s; capture times must differ", w[0].1.display(), w[1].1.display(), w[1].0));
        }
        let t0 = frames[0].0;
        for f in &mut frames {
            f.0 -= t0;
        }
        let poses = match poses {
            None => None,
            Some(p) => {
                let mut out = Vec::new();
                for r in parse_csv(p, "t_s,x_m,y_m")? {
                    let t = number(p, &r[3], "t_s", &r[0])? - t0;
                    out.push((t, [number(p, &r[3], "x_m", &r[1])?, number(p, &r[3], "y_m", &r[2])?]));
                }
                if out.windows(2).any(|w| w[1].0 <= w[0].0) {
                    return Err(format!("{}: t_s must increase", p.display()));
                }
                Some(out)
            }
        };
        Ok(Recording { frames, poses, t0_s: t0 })
    }

    /// The robot's tool point at time `t` (interpolated), if poses were given.
    pub fn pose_at(&self, t: f64, frame: &Path) -> Result<Option<[f64; 2]>, String> {
        let Some(p) = &self.poses else { return Ok(None) };
        let (first, last) = (p[0].0, p[p.len() - 1].0);
        if t < first - 1e-9 || t > last + 1e-9 {
            return Err(format!(
                "{}: captured at t = {:.6} s (+ {} s), outside the robot poses' span {:.6}..{:.6} s: no pose to remove the robot with",
                frame.display(),
                t,
                self.t0_s,
                first,
                last
            ));
        }
        let k = p.partition_point(|q| q.0 <= t).clamp(1, p.len().max(2) - 1).min(p.len() - 1);
        if p.len() == 1 {
            return Ok(Some(p[0].1));
        }
        let (a, b) = (p[k - 1], p[k]);
        let s = ((t - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
        Ok(Some([a.1[0] + s * (b.1[0] - a.1[0]), a.1[1] + s * (b.1[1] - a.1[1])]))
    }
}

/// What the recorded frames looked like, for the report.
#[derive(Clone, Debug, Default)]
pub struct RecordedStats {
    /// Frames used.
    pub frames_used: usize,
    /// Largest share of the plane raster unknown after the fill (obstacle), in one frame.
    pub max_unknown_fraction: f64,
    /// Cells filled from a neighbour, largest in one frame.
    pub max_filled_cells: usize,
    /// Points dropped as lower than the sense height under the plane, over all frames.
    pub below_plane_points: usize,
    /// Valid points on the plane raster, over all frames.
    pub valid_points: usize,
}

/// A recording whose median frame interval is longer than this is mis-timed (capture times in
/// milliseconds read as seconds, or frames of another session), s.
pub const MAX_MEDIAN_INTERVAL_S: f64 = 1.0;

/// The warnings a recording earns (issue 29 item 7): its frames mis-timed (the median interval
/// between capture times over [`MAX_MEDIAN_INTERVAL_S`]) or mis-scaled (most valid points under
/// the work plane: a wrong `depth_scale_m` or camera height), each naming why. Neither is refused:
/// the run goes on, and says it.
pub fn recording_warnings(rec: &Recording, stats: &RecordedStats) -> Vec<String> {
    let mut w = Vec::new();
    let mut gaps: Vec<f64> = rec.frames.windows(2).map(|f| f[1].0 - f[0].0).collect();
    gaps.sort_by(f64::total_cmp);
    if let Some(&median) = gaps.get(gaps.len() / 2) {
        if median > MAX_MEDIAN_INTERVAL_S {
            w.push(format!(
                "recording mis-timed: the median interval between frames is {median:.3} s (over {MAX_MEDIAN_INTERVAL_S} s; a depth camera gives 15-90 frames a second): capture times in another unit, or frames of more than one session? Each frame is used at its capture time"
            ));
        }
    }
    if stats.valid_points > 0 && 2 * stats.below_plane_points > stats.valid_points {
        w.push(format!(
            "recording mis-scaled: {} of {} valid points ({:.0} %) lie under the work plane (more than the sense height below it): depth_scale_m or the camera's height_m/position_m in [avoid.depth_camera] is wrong? Those points were dropped as unknown (obstacle)",
            stats.below_plane_points,
            stats.valid_points,
            100.0 * stats.below_plane_points as f64 / stats.valid_points as f64
        ));
    }
    w
}

/// The recording as the loop's camera.
pub struct RecordedSource {
    rec: Recording,
    cam: Pinhole,
    next: usize,
    /// What was seen.
    pub stats: RecordedStats,
}

impl RecordedSource {
    /// For a scene with `[avoid.depth_camera]`.
    pub fn new(scene: &Avoid, rec: Recording) -> Result<Self, String> {
        let cfg = scene.depth_camera.as_ref().ok_or("--depth needs [avoid.depth_camera] in the scene: the pinhole camera (fx_px, fy_px, cx_px, cy_px, position_m, height_m) and depth_scale_m")?;
        Ok(RecordedSource { rec, cam: Pinhole::new(cfg), next: 0, stats: RecordedStats::default() })
    }
}

/// One recorded frame through the pipeline: reprojection (robot removed at its pose), the bounded
/// fill, unknown cells as obstacles; the field and the separation from the tool's surface.
pub fn process_frame(scene: &Avoid, setup: &Setup, cam: &Pinhole, img: &DepthImage, pose: Option<[f64; 2]>, tool: [f64; 2]) -> (Field, f64, [f64; 2], FrameInfo) {
    let c = &scene.camera;
    let plane = PlaneRaster { width: c.width_px, height: c.height_px, m_per_px: c.m_per_px };
    let robot = scene.robot_shape();
    let sense = scene.safety.sense_height_m;
    // Points lower than the sense height under the plane are measurement errors, not floor.
    let rep = reproject(cam, img, &plane, pose.map(|p| (&robot, p, scene.robot.removal_margin_m)), sense);
    let (w, h) = (plane.width, plane.height);
    // One pass of fill, from the cells seen in the frame only.
    let mut cells = rep.cells.clone();
    let mut filled = 0;
    let mut filled_floor = 0;
    for r in 0..h {
        for col in 0..w {
            if rep.cells[r * w + col] != Cell::Unknown {
                continue;
            }
            let mut best: Option<f64> = None;
            for (dr, dc) in [(-1i64, -1i64), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)] {
                let (rr, cc) = (r as i64 + dr, col as i64 + dc);
                if rr >= 0 && cc >= 0 && (rr as usize) < h && (cc as usize) < w {
                    if let Cell::Seen(v) = rep.cells[rr as usize * w + cc as usize] {
                        best = Some(best.map_or(v, |b: f64| b.max(v)));
                    }
                }
            }
            if let Some(v) = best {
                cells[r * w + col] = Cell::Seen(v);
                filled += 1;
                if v <= sense {
                    filled_floor += 1;
                }
            }
        }
    }
    // The floor the robot hides from the camera is the robot's (with a pose).
    if let Some(p) = pose {
        let top = robot.wrist_height_m.max(robot.link_height_m);
        for (k, cell) in cells.iter_mut().enumerate() {
            if *cell == Cell::Unknown && hidden_by_robot(cam, &robot, p, plane.centre(k), top) {
                *cell = Cell::Seen(0.0);
            }
        }
    }
    let mut acc = crate::sensing::Nearest::new(tool, plane.m_per_px);
    let mut unknown = 0;
    let mut m = Vec::with_capacity(w * h);
    for (k, cell) in cells.iter().enumerate() {
        let (height, obstacle) = match *cell {
            Cell::Seen(v) => (v, v > sense),
            Cell::Unknown => {
                unknown += 1;
                (scene.stop_height_m, true)
            }
        };
        if obstacle {
            acc.add(plane.centre(k));
        }
        m.push(height);
    }
    let (from_centre, nearest) = acc.nearest();
    // A cell filled with floor may hide an obstacle's edge: a null strip up to two cells wide is
    // filled from both sides, so a black rim or finger there reads as floor and the nearest seen
    // obstacle can be up to two cell diagonals farther than the true one. The separation the monitor
    // gets is shortened by that reach whenever the fill painted floor (review finding 6a).
    let fill_reach = if filled_floor > 0 { FILL_REACH_CELLS * plane.m_per_px } else { 0.0 };
    let sep = (from_centre - robot.wrist_radius_m - fill_reach).max(0.0);
    // Per direction; where the fill painted floor the hidden edge may lie in any direction: the
    // shortest separation in every sector.
    let sectors = if filled_floor > 0 { [sep; crate::sensing::SECTORS] } else { acc.sectors().map(|d| (d - robot.wrist_radius_m).max(0.0)) };
    let mut map = HeightMap { width: w, height: h, m };
    crate::depth::raise(&mut map, scene.fit.offset_m);
    let mut wts = setup.fitter.weights(&map);
    if scene.fit.remove_plane {
        for (v, p) in wts.iter_mut().zip(&setup.plane_weights) {
            *v -= p;
        }
    }
    filter_weights(&mut wts);
    let info = FrameInfo { unknown_cells: unknown, filled_cells: filled, robot_points: rep.robot_points, below_plane_points: rep.below_plane_points, valid_points: rep.valid_points, sectors_m: sectors };
    (Field::new(&setup.fitter.grid, wts, scene.fit.eval_sigma_factor), sep, nearest, info)
}

/// How far (in cells) the one-pass fill can paint floor over an obstacle's edge: a strip two
/// cells wide, measured along a diagonal.
pub const FILL_REACH_CELLS: f64 = 2.0 * std::f64::consts::SQRT_2;

/// Counts of one processed frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameInfo {
    /// Cells unknown after the fill (obstacles).
    pub unknown_cells: usize,
    /// Cells filled from a neighbour.
    pub filled_cells: usize,
    /// Points dropped as the robot's.
    pub robot_points: usize,
    /// Points dropped as lower than the sense height under the plane (measurement errors).
    pub below_plane_points: usize,
    /// Valid points on the plane raster.
    pub valid_points: usize,
    /// The separation per direction from the tool's surface (the monitor's sectors), m: the
    /// shortest one in every sector when the fill painted floor.
    pub sectors_m: [f64; crate::sensing::SECTORS],
}

/// Whether the line of sight from the floor at `q` to the camera passes through the robot (with the
/// tool at `pose`): checked every 2 mm of height up to the robot's top.
fn hidden_by_robot(cam: &Pinhole, robot: &crate::depth::RobotShape, pose: [f64; 2], q: [f64; 2], top: f64) -> bool {
    let o = cam.origin;
    let n = (top / 2e-3).ceil() as usize;
    (1..=n).any(|i| {
        let z = i as f64 * 2e-3;
        let s = z / o[2];
        let p = [q[0] + s * (o[0] - q[0]), q[1] + s * (o[1] - q[1])];
        robot.height_at(pose, p) >= z
    })
}

impl FrameSource for RecordedSource {
    fn frame(&mut self, scene: &Avoid, setup: &Setup, t_s: f64, tool: [f64; 2]) -> Result<Option<Frame>, String> {
        // The newest frame captured by now.
        let k = self.rec.frames.partition_point(|f| f.0 <= t_s + 1e-9);
        if k == 0 || k <= self.next {
            return Ok(None);
        }
        self.next = k;
        let (tc, path) = self.rec.frames[k - 1].clone();
        let img = DepthImage::load(&path)?;
        if img.width < 2 || img.height < 2 || img.width * img.height > MAX_FRAME_PIXELS {
            return Err(format!(
                "{}: {} x {} px; a depth frame must be at least 2 x 2 and at most {MAX_FRAME_PIXELS} pixels (depth cameras give up to 1280 x 1024; the work per frame is bounded by it)",
                path.display(),
                img.width,
                img.height
            ));
        }
        let pose = self.rec.pose_at(tc, &path)?;
        let (field, separation_m, nearest_m, info) = process_frame(scene, setup, &self.cam, &img, pose, tool);
        let cells = (scene.camera.width_px * scene.camera.height_px) as f64;
        let s = &mut self.stats;
        s.frames_used += 1;
        s.max_unknown_fraction = s.max_unknown_fraction.max(info.unknown_cells as f64 / cells);
        s.max_filled_cells = s.max_filled_cells.max(info.filled_cells);
        s.below_plane_points += info.below_plane_points;
        s.valid_points += info.valid_points;
        // A recording carries no fixture classes yet: every sensed pixel is a person's.
        Ok(Some(Frame { field, separation_m, nearest_m, capture_s: tc, goal_separation_m: None, sectors_m: info.sectors_m, fixture_sectors_m: [crate::sensing::NOTHING_SENSED_M; crate::sensing::SECTORS] }))
    }
}

/// Render the scene's own recording through its pinhole camera: one frame per entry of `track`
/// (capture time s, tool point m), the hand where the scene's key frames put it, the scene camera's
/// depth noise (mm) and null pixels, `width x height` pixels. Each frame is written as a 16-bit PNG
/// into every `(dir, metres per count)` of `outs`, with `index.csv`, and `poses.csv` (the track).
/// Depths are whole millimetres before scaling, so the conventions (0.001 and 0.0002 m per count)
/// carry the same depths.
pub fn render_recording(scene: &Avoid, outs: &[(&Path, f64)], width: usize, height: usize, track: &[(f64, [f64; 2])]) -> Result<(), String> {
    let cfg = scene.depth_camera.as_ref().ok_or("render_recording needs [avoid.depth_camera]")?;
    let cam = Pinhole::new(cfg);
    for (dir, _) in outs {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let robot = scene.robot_shape();
    let mut rng = crate::depth::Rng::new(scene.camera.seed ^ 0x5EC0);
    let mut index = String::from("t_s,file\n");
    let mut poses = String::from("t_s,x_m,y_m\n");
    for (k, &(t, tool)) in track.iter().enumerate() {
        let z = crate::camera::render_depth(&cam, width, height, Some((&robot, tool)), Some((&scene.operator_shape_at(t), scene.hand_at(t))));
        let noisy: Vec<Option<f64>> = z
            .iter()
            .map(|d| {
                let n = scene.camera.noise_mm * rng.normal();
                let null = rng.uniform() < scene.camera.null_fraction;
                d.filter(|_| !null).map(|z| ((z * 1e3 + n).round() * 1e-3).max(1e-3))
            })
            .collect();
        let name = format!("{k:05}.png");
        for (dir, scale) in outs {
            crate::camera::to_counts(&noisy, width, height, *scale).save(&dir.join(&name))?;
        }
        index.push_str(&format!("{t},{name}\n"));
        poses.push_str(&format!("{t},{},{}\n", tool[0], tool[1]));
    }
    for (dir, _) in outs {
        std::fs::write(dir.join("index.csv"), &index).map_err(|e| format!("{}: {e}", dir.display()))?;
        std::fs::write(dir.join("poses.csv"), &poses).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    Ok(())
}

/// `flinch avoid --depth`: the scene's loop on the recorded frames, with the reference or the
/// on-target engine.
pub fn simulate(scene: &Avoid, setup: &Setup, engine: crate::path::Engine, depth: &Path, poses: Option<&Path>) -> Result<(crate::path::PathResult, RecordedStats), String> {
    use crate::path::{mcu_engine, simulate_from, Engine, RefEngine};
    let rec = Recording::open(depth, poses)?;
    let mut src = RecordedSource::new(scene, rec)?;
    let mut res = match engine {
        Engine::Reference => simulate_from(scene, setup, &mut RefEngine::new(scene)?, &mut src)?,
        Engine::Mcu => simulate_from(scene, setup, &mut mcu_engine(scene)?, &mut src)?,
    };
    // The verdict was judged against the scene file's model operator, not the recording's people:
    // never a verified `reached` or `stopped`.
    res.verdict_basis = crate::path::VerdictBasis::SceneModelNotRecording;
    res.status = res.status.unverified();
    res.warnings.extend(recording_warnings(&src.rec, &src.stats));
    Ok((res, src.stats))
}
