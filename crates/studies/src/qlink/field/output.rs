//! What the field experiment produced: each world's map and trials, and the pooled counts,
//! rates and bounds — read by the experiment's aggregate and by its report.

use serde::{Deserialize, Serialize};

use super::FieldVariant;
use super::mapping::MappingStats;
use super::summary::{BoundSummary, FieldSummary, MapSize, RestrictedPlans};
use super::trials::{FieldTrial, TaskDraws};

/// One world: how its map came out and every trial run in it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldWorld {
    /// Its index (the shard's).
    pub world: usize,
    /// Its seed: the config's seed + the index.
    pub seed: u64,
    /// The mapping drive's figures.
    pub mapping: MappingStats,
    /// Why start/goal draws were redrawn.
    pub draws: TaskDraws,
    /// Success and failure counts per variant.
    pub variants: Vec<FieldSummary>,
    /// The map's size.
    pub map_size: MapSize,
    /// The thesis variant's tasks planned on the map and on the map restricted to nearby
    /// triplets.
    pub restricted_map_plans: RestrictedPlans,
    /// The simulated site (for pictures: Fig 4.9).
    pub site: sim2d::WorldSpec,
    /// The mapping drive's true positions (m).
    pub drive: Vec<[f64; 2]>,
    /// Every trial, variant by variant.
    pub trials: Vec<FieldTrial>,
}

/// A variant's success rate over the worlds: the mean and sample sd of the worlds' rates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VariantRate {
    /// The variant.
    pub variant: FieldVariant,
    /// Mean of the worlds' success rates.
    pub mean: f64,
    /// Their sample standard deviation (0 for one world).
    pub sd: f64,
    /// Worlds with a rate: those whose map gave the variant a pair to try.
    #[serde(default)]
    pub worlds: usize,
}

/// What a run of the field experiment produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldOutput {
    /// The worlds, in seed order.
    pub worlds: Vec<FieldWorld>,
    /// Counts per variant over all worlds' trials.
    pub variants: Vec<FieldSummary>,
    /// Rates per variant over the worlds.
    pub success_rate_over_worlds: Vec<VariantRate>,
    /// Propositions 2 and 4 per variant, at the lidar's and at the effective range.
    pub bounds: Vec<BoundSummary>,
}

impl FieldOutput {
    /// Every trial with its world, world by world.
    pub fn trials(&self) -> impl Iterator<Item = (&FieldWorld, &FieldTrial)> {
        self.worlds
            .iter()
            .flat_map(|w| w.trials.iter().map(move |t| (w, t)))
    }

    /// The pooled counts of `variant`.
    #[must_use]
    pub fn pooled(&self, variant: FieldVariant) -> Option<&FieldSummary> {
        self.variants.iter().find(|s| s.variant == variant)
    }
}
