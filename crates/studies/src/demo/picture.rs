//! The data of the demo's picture: the site with the mapping drive and the run, the plan's
//! map elements as triangles of their landmarks, the links found, and the learned calculus's
//! regions beside it.

use qlink::{Perception, QualitativeMap};
use qsr_core::Calculus;
use serde::{Deserialize, Serialize};

use super::choice::Chosen;
use super::pipeline::Mapping;
use crate::report::RegionsPanel;
use crate::world_perception::WorldPerception;

/// Cells along x of the regions panel.
const REGION_CELLS: usize = 160;

/// Window of a constraint calculus's panel in its normalised frame; a raster calculus shows
/// its own window.
const CONSTRAINT_WINDOW: [f64; 4] = [-2.2, 2.2, -1.6, 2.6];

/// What the picture draws (besides the run's trajectory and searches, in [`Chosen`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Picture {
    /// The site.
    pub world: sim2d::WorldSpec,
    /// The mapping drive (m).
    pub drive: Vec<[f64; 2]>,
    /// The first plan's elements, each as its landmarks' positions.
    pub plan: Vec<[[f64; 2]; 3]>,
    /// Positions of the links found.
    pub links: Vec<[f64; 2]>,
    /// The goal landmark's position (the start's when the world does not have it).
    pub goal: [f64; 2],
    /// The learned calculus's regions.
    pub regions: Option<RegionsPanel>,
}

impl Picture {
    /// The picture of `run` over `mapping`.
    #[must_use]
    pub fn new(
        mapping: &Mapping,
        map: &QualitativeMap,
        perception: &WorldPerception<'_>,
        run: &Chosen,
        learned: Option<&Calculus>,
    ) -> Self {
        let pos_of = |id: u32| perception.position(id);
        let plan = run
            .outcome
            .plan
            .iter()
            .filter_map(|&e| {
                let [x, y, z] = map.elements()[e].landmarks;
                Some([pos_of(x)?, pos_of(y)?, pos_of(z)?])
            })
            .collect();
        let links = run
            .outcome
            .transitions
            .iter()
            .filter(|t| t.success)
            .filter_map(|t| pos_of(t.link))
            .collect();
        Self {
            world: mapping.scenario.world.spec().clone(),
            drive: mapping
                .frames
                .iter()
                .map(|f| [f.pose.x, f.pose.y])
                .collect(),
            plan,
            links,
            goal: pos_of(run.goal).unwrap_or(run.start),
            regions: learned.map(regions_of),
        }
    }
}

/// A calculus's regions on a grid over its normalised frame (A = (0, 0), B = (1, 0)).
#[must_use]
pub fn regions_of(c: &Calculus) -> RegionsPanel {
    let window = match c.partition() {
        qsr_core::Partition::Raster(r) => r.window(),
        qsr_core::Partition::Constraints(_) => CONSTRAINT_WINDOW,
    };
    let [x0, x1, y0, y1] = window;
    let nx = REGION_CELLS;
    let cell = (x1 - x0) / nx as f64;
    let ny = ((y1 - y0) / cell).ceil() as usize;
    let cell_region = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| {
                let p = qsr_core::Point2::new(
                    x0 + (i as f64 + 0.5) * cell,
                    y0 + (j as f64 + 0.5) * cell,
                );
                u32::from(c.classify_normalised(&p).0)
            })
        })
        .collect();
    RegionsPanel {
        title: format!("Learned calculus: {} regions of A→B", c.n_states()),
        window: [x0, x1, y0, y0 + ny as f64 * cell],
        nx,
        ny,
        cell_region,
        marks: vec![([0.0, 0.0], "A".into()), ([1.0, 0.0], "B".into())],
    }
}
