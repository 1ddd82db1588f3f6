//! What the SERGE study produced: per dataset its cross-validation records and summaries and
//! its example maps — read by the study's aggregate and by its report.

use serde::{Deserialize, Serialize};

use super::cross_validation::{CvRecord, CvSummary};
use super::datasets::DatasetName;
use super::examples::DatasetExamples;

/// One dataset's results.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DatasetResult {
    /// The dataset.
    pub dataset: DatasetName,
    /// Its beliefs K.
    pub k: usize,
    /// Every SERGE run, fold by fold.
    pub records: Vec<CvRecord>,
    /// Mean ± sd over folds per setting.
    pub summary: Vec<CvSummary>,
    /// Example maps and the use case.
    pub examples: DatasetExamples,
}

/// What a run of the study produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SergeOutput {
    /// The datasets, in the config's order.
    pub datasets: Vec<DatasetResult>,
}

impl SergeOutput {
    /// The result of `name`.
    #[must_use]
    pub fn dataset(&self, name: DatasetName) -> Option<&DatasetResult> {
        self.datasets.iter().find(|d| d.dataset == name)
    }
}
