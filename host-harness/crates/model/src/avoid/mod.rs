//! What an avoidance scene (`[avoid]`, `flinch avoid`, docs/avoidance.md) holds: the validated
//! values (`scene`), the true geometry of robot, operator and obstacles (`shapes`) and the recorded
//! frames' camera (`depth_camera`). Read and checked by the loader in `crate::scene::avoid`; run by
//! `flinch-avoid`.

pub mod depth_camera;
pub mod link;
pub mod scene;
pub mod shapes;
