//! # studies — the thesis's experiments, one shape each
//!
//! The algorithm crates (`qsr-core`, `pqrm`, `serge`, `qlink`) are what a robot embeds; this
//! crate is what reproduces the thesis with them: worlds simulated with `sim2d`, the
//! settings the thesis sweeps, the records of every trial, and reports that set our figures
//! beside the thesis's with verdicts computed by tested code. The front ends (the `qrm` CLI,
//! the Python wheel) only parse, show progress, write files and draw.
//!
//! ## Why a crate of its own
//! - **Robots do not compile a simulator.** `qlink` and `serge` know nothing of `sim2d`;
//!   the simulated perception with occlusion ([`world_perception::WorldPerception`]) and the
//!   simulated datasets live here.
//! - **One place for the thesis's numbers and verdicts.** A report's claims are computed
//!   from the records by functions with tests ([`verdict`]), never typed into a format string
//!   of a front end.
//!
//! ## Layout
//! | module | thesis | what |
//! |---|---|---|
//! | [`pqrm::monte_carlo`] | §2.3.1, Figs 2.6–2.11 | PQRM map quality vs noise, six calculi (the run is `pqrm::study`) |
//! | [`pqrm::real_data`] | §2.3.2, Figs 2.14–2.16 | PQRM on a surveyed recording (MRCLAM): baselines, calibration, tempering, sensor models, many robots |
//! | [`pqrm::reasoning`] | new (§3.3.2) | inference of hidden and never-seen triplets by composition, consistency checks, on a recording with surveyed landmarks |
//! | [`recording`] | — | a recording in any form qrm reads (CSV, MRCLAM, g2o, MCAP), its noise given or fitted |
//! | [`calibration`] | — | a recording's noise fitted from the recording itself (`qrm pqrm calibrate`) |
//! | [`mapping`] | — | a user's recording mapped (`qrm map`): read, gated, τ chosen, mapped, scored |
//! | [`simulation`] | — | a simulated recording (`qrm sim`): a scenario, its detector, the files a user maps and scores |
//! | [`config`] | — | a config as a user edits it: TOML, a file's fields over the built-in, `key=value` |
//! | [`qlink::table_4_1`] | §4.4.1, Table 4.1, Figs 4.6–4.7 | navigation failure rate vs sensor range and landmark size |
//! | [`qlink::field`] | §4.4.2, Table 4.2 | the lidar-only field-site experiment in simulation |
//! | [`serge::datasets`] | §3.4 | the well-separated, lab and hallway datasets |
//! | [`serge::cross_validation`] | §3.4.2, Fig 3.7 | SERGE cross-validation over μ and σ, fold by fold |
//! | [`serge::examples`], [`serge::resolution_tree`], [`serge::learned_calculus`] | Figs 3.8–3.10, §3.3.2 | maps on all data, the lab's resolution-tree plan, the hallway's learned calculus and Algorithm 3 checked |
//! | [`serge::region_map`], [`serge::calculus_learning`] | §3.2, §3.3.2 | SERGE on a user's own beliefs; a calculus learned from a user's recording |
//! | [`serge::study`] | §3.4 | all of it as one study (`serge-cv`), a shard per fold and dataset |
//! | [`demo`] | DESIGN §1 | the whole pipeline: lidar mapping, PQRM, a learned calculus, Q-Link across the field site, an MCAP log |
//!
//! ## Naming rule
//! A study's module is named after what the thesis calls it (`table_4_1`, `field`,
//! `cross_validation`); `run*` runs, `summarise`/`table` reduce records, `report` judges.
//!
//! ## Errors
//! [`StudyError`]: `InvalidParameter` (a configuration refused before any work),
//! `Cancelled`, and the wrapped errors of the crates a study drives (`Qlink`, `Serge`,
//! `Pqrm`, `Calculus`, `Sim`, `Log`).

pub mod calibration;
pub mod config;
pub mod demo;
mod error;
pub mod mapping;
pub mod pqrm;
pub mod qlink;
pub mod recording;
pub mod registry;
pub mod report;
pub mod serge;
pub mod shard;
pub mod simulation;
pub mod study;
pub mod verdict;
pub mod world_perception;

pub use error::{Result, StudyError};
pub use registry::{STUDIES, find};
pub use report::{
    Attachment, Cell, Claim, Column, Figure, Line, NavigationPicture, Plot, Products, RegionsPanel,
    Report, SiteRun, Table, Verdict,
};
pub use study::{AnyStudy, Ran, Study};
