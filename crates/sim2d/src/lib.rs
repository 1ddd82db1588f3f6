//! # sim2d — a 2-D world for qualitative mapping and navigation experiments
//!
//! Static rapier2d colliders (point landmarks as discs, walls as segments, clutter), a
//! unicycle robot, a raycast lidar and an ideal landmark detector with full occlusion, the
//! ground under a line scanner ([`Terrain`]: where pitched ground rises into the scan plane),
//! and seeded scenarios from the thesis (DESIGN §5). The only crate that depends on rapier2d.
//!
//! ## Why rapier
//! Every geometric question — what does this ray hit, what lies between the sensor and
//! that landmark — is answered by rapier's query pipeline over its BVH, so a 1081-ray scan of
//! a 200-landmark world costs a few hundred microseconds instead of 200 ray–disc tests per
//! ray.
//!
//! ## Determinism
//! Worlds are generated from a seed; sensor noise comes from a generator seeded by the run's
//! seed; nothing depends on threads.
//!
//! ```
//! use sim2d::{scenario, Pose};
//! let sc = scenario("hallway", 1, None)?;
//! let frames = sc.run(1, false)?;
//! assert!(frames.iter().any(|f| f.detections.len() >= 3));
//! # Ok::<(), sim2d::SimError>(())
//! ```

mod error;
mod extractor;
mod scenario;
mod sensors;
mod terrain;
mod world;

pub use error::{Result, SimError};
pub use extractor::{
    Candidate, CandidateKind, ExtractorConfig, LidarDetector, MAPPING_MIN_CANDIDATES,
    MIN_POINTS_FLOOR, TriangleRecognizer, angular_resolution, extract, points_of,
};
pub use scenario::{Frame, SCENARIOS, Scenario, scenario, write_observations_csv};
pub use sensors::{
    Detection, DetectorConfig, DetectorNoise, LaserScan, LidarConfig, Pose, Unicycle,
};
pub use terrain::{Bump, Terrain};
pub use world::{Clutter, Hit, PointLandmark, Wall, World, WorldSpec};
