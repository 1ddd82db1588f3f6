//! # qlink — navigation with qualitative relational maps (thesis chapter 4)
//!
//! A robot with a qualitative map knows only how landmarks sit relative to each other. Q-Link
//! gets it from a start to a goal in three levels:
//!
//! 1. **Link Graph** ([`LinkGraph`]): map elements (landmark sets with their qualitative
//!    states, [`QualitativeMap`]) joined when they share ≥ β landmarks; plans are cheapest
//!    paths under unit, expected-transition or −log P(success) costs.
//! 2. **QSR level** ([`SearchPomdp`]): to move from one element to the next, search for the
//!    shared *link* landmark over the qualitative states of the current frame — a POMDP over
//!    (robot state, link state) solved exactly over a short horizon.
//! 3. **Trajectory level** ([`Controller`]): turn "go to state q" into a path — an arc, a
//!    midpoint-and-sweep, the closest point (a QP), or a safe search.
//!
//! [`Navigator`] runs the three with a [`Perception`] (anything that says which landmarks
//! the robot detects: [`RangePerception`] here, a simulator's or a real sensor's elsewhere)
//! and re-plans around failed transitions; [`execution`] holds how it senses and remembers
//! and [`robot`] what its detector and wheels get wrong (the thesis's robot by default, an
//! erring one; idealised options named as such). The thesis's studies
//! (§4.4.1 Table 4.1, the §4.4.2 field experiment) live in the `studies` crate, so a robot
//! that embeds Q-Link does not compile a simulator.
//!
//! ## Why it is built this way
//! - The map is an interface over layers (PQRM or exact), so hybrid maps of several calculi
//!   plug in without the planner knowing.
//! - Edges are directed: a transition's cost depends on which frame the link is searched in.
//! - The robot's qualitative state is observed (it localises in the frame it sees) and the
//!   link's is static, so the POMDP's beliefs are small and it is solved exactly rather than
//!   approximately; the same recursion gives the success probabilities of eqs. 4.2–4.3.
//! - Controllers return waypoints and never see world coordinates they could not measure:
//!   they work from the positions of the references in view.
//!
//! ## Naming rule
//! Nouns are levels and data (`LinkGraph`, `Plan`, `SearchPomdp`, `Decision`, `Controller`);
//! `plan`/`decide`/`path`/`navigate` run them; `*_from`/`from_*` convert.
//!
//! ## Errors
//! [`QlinkError`]: `EmptyMap`, `UnknownLandmark`, `SameStartGoal`, `NoPath`,
//! `InvalidParameter`, `Unsupported`, `Cancelled`, and wrapped calculus and mapper errors.

pub mod bounds;
pub mod controller;
mod error;
pub mod execution;
pub mod graph;
pub mod map;
pub mod navigate;
pub mod perception;
pub mod pomdp;
pub mod robot;

pub use bounds::{Assumptions, BoundCheck, Geometry};
pub use controller::{Controller, ControllerKind, circle, closest_point, robot_state};
pub use error::{QlinkError, Result};
pub use execution::{Arrival, Odometry, References, Sensing};
pub use graph::{CostModel, DistanceField, LinkEdge, LinkGraph, Plan};
pub use map::{Layer, MapElement, QualitativeMap};
pub use navigate::{Failure, NavConfig, NavOutcome, Navigator, Stranded, TransitionRecord};
pub use perception::{Look, Perception, RangePerception};
pub use pomdp::{Decision, Moves, SearchPomdp, SearchPomdpBuilder};
pub use robot::{DetectionNoise, MotionNoise, Robot};
