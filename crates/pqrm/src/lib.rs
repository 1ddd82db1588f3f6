//! # pqrm — probabilistic qualitative relational mapping
//!
//! A robot observes point landmarks with noise. Instead of estimating where they are, the
//! mapper estimates *how they sit relative to each other*: for every set of three landmarks,
//! a probability distribution over the states of a qualitative calculus (thesis chapter 2).
//!
//! ```text
//! Scan (ids, means, covariances)  ──sample s times per landmark──▶  ScanSamples
//!     ──classify every ordered triplet with qsr-core──▶  counts  ──floor──▶  p(R | Z_t)
//!     ──Bayes filter in log space (eq. 2.10)──▶  Pqrm  ──▶  beliefs, entropy, metrics
//! ```
//!
//! ## Why it is built this way
//! - **Sampling once per landmark per step** ([`sampler`]): the thesis's estimator (eq. 2.9)
//!   integrates the inverse sensor model by sampling; sampling each landmark once and reusing
//!   the samples in every triplet makes a step cost `O(m·s)` draws and keeps the triplet
//!   estimates of one step consistent with each other.
//! - **Log space**: beliefs are log-probabilities renormalised with log-sum-exp, so long runs
//!   never underflow ([`map`]).
//! - **A pseudo-count floor** ([`likelihood`]): one outlier cannot rule a state out forever.
//! - **Finest calculus once, merge the rest**: [`likelihood::merge_counts`] turns EDC counts
//!   into counts of any coarser calculus, so a study samples once for six calculi.
//! - **Tempering chosen from the data** ([`temper`]): eq. 2.10 counts correlated frames as
//!   independent evidence; a tempering exponent τ, chosen by how well the map predicts
//!   held-out blocks of frames, makes the map's confidence honest without ground truth.
//! - **Shared error** ([`evidence`]): frames of one set that share an error prove less than
//!   eq. 2.10 says; the shared-error model reads each set's stored sum with an exponent that
//!   caps its evidence. It cannot know how much a recording's frames share.
//! - **The layout** ([`layout`]): a whole recording can. Every frame aligned into one layout
//!   of the landmarks (generalised Procrustes), the frames' disagreement with it measures the
//!   error they share, and each set's belief is read from the layout give or take that error —
//!   calibrated on every MRCLAM recording tried, the default for recorded data.
//! - **The survey checked against the robots** ([`survey`]): a map scored against surveyed
//!   positions is split into the sets whose landmark pairs every frame sees as surveyed and
//!   those it does not, so a report says which misses the survey itself explains.
//! - **Determinism**: every landmark's samples are seeded by `(seed, step, id)`; results do not
//!   depend on the thread count.
//!
//! ```
//! use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
//! use qsr_core::Calculus;
//!
//! let mut map = Pqrm::new(Calculus::builtin("left-right")?, PqrmConfig { samples: 200, ..PqrmConfig::default() })?;
//! let obs = |id, x, y| Observation::isotropic(LandmarkId(id), [x, y], 0.1);
//! let scan = Scan::new(0.0, 0, vec![obs(1, 0.0, 0.0)?, obs(2, 0.0, 5.0)?, obs(3, -2.0, 2.0)?])?;
//! map.update(&scan)?;
//! let p = map.belief(pqrm::LandmarkSet::new(1, 2, 3)).expect("observed");
//! assert!(p[0] > 0.99); // landmark 3 is left of 1→2
//! # Ok::<(), pqrm::PqrmError>(())
//! ```

pub mod calibrate;
pub mod calibration;
pub mod config;
pub mod error;
pub mod evidence;
pub mod layout;
pub mod likelihood;
pub mod loaders;
pub mod map;
pub mod map_file;
pub mod metrics;
pub mod observation;
pub mod reason;
pub mod reason_study;
pub mod robots;
pub mod sampler;
pub mod sensor;
mod spread;
mod store;
pub mod study;
pub mod survey;
pub mod temper;

pub use error::{PqrmError, Result};
pub use evidence::EvidenceModel;
pub use likelihood::{LandmarkSet, Orderings};
pub use map::{Pqrm, PqrmConfig, TripletBelief, UpdateReport};
pub use metrics::{Baselines, GroundTruth, MapMetrics, evaluate, random_baselines};
pub use observation::{LandmarkId, Observation, Scan};
pub use sampler::ScanSamples;
