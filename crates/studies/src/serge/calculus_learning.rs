//! A calculus learned from a user's recording (`qrm serge learn`, thesis §3.3.2): the
//! [`CalculusLearner`] over the recording's frames, the map turned into a raster calculus,
//! Algorithm 3's compose table, and the files that let a user load, check and draw it.

use std::path::Path;
use std::time::Instant;

use qsr_core::{Calculus, ComposeTable};
use serde_json::json;
use serge::SalientRegionMap;
use serge::learn::TripletObservation;
use serge::learner::CalculusLearner;

use super::learned_calculus::compose_table_json;
use super::region_map::map_figure;
use crate::error::{Result, StudyError};
use crate::report::{Attachment, Products};

/// A calculus learned from a recording.
#[derive(Debug, Clone)]
pub struct LearnedFromRecording {
    /// The calculus (a raster of the map's regions).
    pub calculus: Calculus,
    /// Its compose table by Algorithm 3 (sound by construction).
    pub table: ComposeTable,
    /// The salient region map it was made from.
    pub map: SalientRegionMap,
    /// The ordered triplets learned from.
    pub triplets: Vec<[u32; 3]>,
    /// Their observations, frame by frame.
    pub observations: Vec<TripletObservation>,
    /// Time it took (s).
    pub seconds: f64,
}

impl LearnedFromRecording {
    /// Learns calculus `name` from the observation CSV `input` (`t,robot,landmark,x,y,…`).
    ///
    /// # Errors
    /// The reader's errors naming the file, line and field; [`StudyError::InvalidParameter`]
    /// naming the file when too few landmark sets were seen together or SERGE refuses.
    pub fn learn(learner: &CalculusLearner, input: &Path, name: &str) -> Result<Self> {
        // The sizes first: a bad flag is blamed, not the file.
        learner
            .validate()
            .map_err(|e| StudyError::InvalidParameter(e.to_string()))?;
        let scans = pqrm::loaders::read_csv(input)?.scans;
        let start = Instant::now();
        let (selected, map) = learner
            .learn(&crate::recording::sightings(&scans))
            .map_err(|e| {
                StudyError::InvalidParameter(format!("learning from {}: {e}", input.display()))
            })?;
        let description = format!(
            "learned by SERGE from {} triplets of {} (μ = {}, σ = {})",
            selected.triplets.len(),
            input.display(),
            learner.mu,
            learner.sigma
        );
        let calculus = map.to_calculus(name, &description)?;
        let table = serge::learn::compose_table(&calculus, &|| {})?;
        Ok(Self {
            calculus,
            table,
            map,
            triplets: selected.triplets,
            observations: selected.observations,
            seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// One line: triplets, observations, states, compose entries and time.
    #[must_use]
    pub fn describe(&self) -> String {
        format!(
            "{} triplets, {} observations → `{}` with {} states, compose {} entries, in {:.1} s",
            self.triplets.len(),
            self.observations.len(),
            self.calculus.name(),
            self.calculus.n_states(),
            self.table.n_entries(),
            self.seconds
        )
    }

    /// `calculus.json` (its spec, for `--calculus FILE`), `compose.json` (Algorithm 3's
    /// table), `map.json` (the SR map with its triplets) and the picture `calculus` of the
    /// map over the data in the normalised frame.
    ///
    /// # Errors
    /// [`StudyError::Calculus`] if the spec cannot be written.
    pub fn products(&self) -> Result<Products> {
        let c = &self.calculus;
        let compose = json!({
            "states": c.labels(),
            "table": compose_table_json(c, &self.table),
            "method": "algorithm-3-intervals",
        });
        let mut map = self.map.to_json();
        map["triplets"] = json!(self.triplets);
        let points = self
            .observations
            .iter()
            .filter_map(|o| serge::learn::normalise(o.points[0], o.points[1], o.points[2]))
            .collect();
        let title = format!("learned calculus `{}`: {} states", c.name(), c.n_states());
        Ok(Products {
            tables: Vec::new(),
            figures: vec![map_figure("calculus", title, &self.map, points)],
            attachments: vec![
                Attachment::text("calculus.json", c.spec().to_json_string()?),
                Attachment::text("compose.json", compose.to_string()),
                Attachment::text("map.json", map.to_string()),
            ],
        })
    }
}
