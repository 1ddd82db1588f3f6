//! The field experiment as a [`Study`]: one shard per world, merged into the pooled rates,
//! the rates over worlds and the distance bounds.

use qsr_core::progress::Progress;
use qsr_core::stats::MeanSd;

use super::summary::{BoundRange, bound_summary, map_size, restricted_plans, summarise};
use super::trials::{FieldTask, FieldTrial, field_units, run_field};
use super::{FieldParams, FieldVariant};
use crate::error::{Result, StudyError};
use crate::report::Report;
use crate::shard::check_indices;
use crate::study::Study;

pub use super::output::{FieldOutput, FieldWorld, VariantRate};

/// The field-site experiment of thesis §4.4.2 (see the module): every variant's trials in
/// each of [`FieldParams::worlds`] simulated worlds.
#[derive(Debug, Clone, Copy, Default)]
pub struct FieldExperiment;

/// Runs world `index` of `config`: maps it, runs every variant's trials, sizes the map.
///
/// # Errors
/// [`StudyError::InvalidParameter`] for an index beyond the worlds; as [`run_field`].
pub fn run_world(
    config: &FieldParams,
    index: usize,
    progress: &dyn Progress,
) -> Result<FieldWorld> {
    check_world(config, index)?;
    let params = FieldParams {
        seed: config.seed + index as u64,
        ..config.clone()
    };
    let variants = FieldVariant::ALL;
    let (field, draws, trials) = run_field(&params, &variants, progress)?;
    let tasks: Vec<FieldTask> = trials
        .iter()
        .filter(|t| t.variant == FieldVariant::Thesis)
        .map(|t| t.task)
        .collect();
    Ok(FieldWorld {
        world: index,
        seed: params.seed,
        mapping: field.stats.clone(),
        draws,
        variants: summarise(&trials, &variants),
        map_size: map_size(&field, &params)?,
        restricted_map_plans: restricted_plans(&field, &params, &tasks)?,
        site: field.scenario.world.spec().clone(),
        drive: field.drive.clone(),
        trials,
    })
}

fn check_world(config: &FieldParams, index: usize) -> Result<()> {
    config.validate()?;
    if index >= config.worlds {
        return Err(StudyError::InvalidParameter(format!(
            "world {index} of a field experiment of {} worlds",
            config.worlds
        )));
    }
    Ok(())
}

/// Merges worlds given in any order (each exactly once) into the experiment's output.
///
/// # Errors
/// [`StudyError::InvalidParameter`] for a missing, duplicated or foreign world.
pub fn aggregate(config: &FieldParams, shards: Vec<(usize, FieldWorld)>) -> Result<FieldOutput> {
    check_indices(config.worlds, shards.iter().map(|(i, _)| *i))?;
    let mut worlds: Vec<(usize, FieldWorld)> = shards;
    worlds.sort_by_key(|(i, _)| *i);
    for (i, w) in &worlds {
        if w.world != *i || w.seed != config.seed + *i as u64 {
            return Err(StudyError::InvalidParameter(format!(
                "shard {i} holds world {} of seed {}: not this config's world {i}",
                w.world, w.seed
            )));
        }
    }
    let worlds: Vec<FieldWorld> = worlds.into_iter().map(|(_, w)| w).collect();
    let flat: Vec<FieldTrial> = worlds.iter().flat_map(|w| w.trials.clone()).collect();
    let variants = FieldVariant::ALL;
    let success_rate_over_worlds = variants
        .iter()
        .map(|&v| {
            // a world whose map gave no pair to try has no rate (not a rate of 0)
            let rates: Vec<f64> = worlds
                .iter()
                .filter_map(|w| w.variants.iter().find(|s| s.variant == v))
                .filter(|s| s.judged() > 0)
                .map(|s| s.success_rate)
                .collect();
            let s = MeanSd::of(&rates);
            VariantRate {
                variant: v,
                mean: s.mean,
                sd: s.sd,
                worlds: s.n,
            }
        })
        .collect();
    Ok(FieldOutput {
        variants: summarise(&flat, &variants),
        bounds: variants
            .iter()
            .flat_map(|&v| BoundRange::ALL.map(|r| bound_summary(&flat, v, r)))
            .collect(),
        success_rate_over_worlds,
        worlds,
    })
}

impl Study for FieldExperiment {
    const NAME: &'static str = "field";
    const ABOUT: &'static str = "§4.4.2: the lidar-only field-site experiment in simulation (success rate, Table 4.2, bounds)";
    type Config = FieldParams;
    type Output = FieldOutput;
    type Shard = FieldWorld;

    fn quick(seed: u64) -> FieldParams {
        FieldParams::quick(seed)
    }
    fn full(seed: u64) -> FieldParams {
        FieldParams::full(seed)
    }
    fn check(config: &FieldParams) -> Result<()> {
        config.validate()
    }
    /// One shard per world.
    fn shards(config: &FieldParams) -> Result<usize> {
        config.validate()?;
        Ok(config.worlds)
    }
    /// [`field_units`] of every variant.
    fn shard_units(config: &FieldParams, index: usize) -> Result<usize> {
        check_world(config, index)?;
        Ok(field_units(config, &FieldVariant::ALL))
    }
    fn run_shard(
        config: &FieldParams,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<FieldWorld> {
        run_world(config, index, progress)
    }
    fn aggregate(config: &FieldParams, shards: Vec<(usize, FieldWorld)>) -> Result<FieldOutput> {
        aggregate(config, shards)
    }
    fn report(config: &FieldParams, output: &FieldOutput) -> Report {
        super::report::report(config, output)
    }
}
