//! Landmarks of a simulated world as the navigating robot detects them: within range and
//! only when fully visible (sim2d's exact full occlusion, §4.4.1). Lives with the studies, not
//! in `qlink`, so a robot that embeds Q-Link does not compile the simulator.

use std::collections::HashMap;

use qlink::Perception;
use qlink::perception::distance as d;

/// Landmarks of a sim2d world, detected within range only when fully visible (§4.4.1).
#[derive(Debug)]
pub struct WorldPerception<'w> {
    world: &'w sim2d::World,
    index: HashMap<u32, usize>,
    range: f64,
}

impl<'w> WorldPerception<'w> {
    /// Perception in `world` with `range`.
    #[must_use]
    pub fn new(world: &'w sim2d::World, range: f64) -> Self {
        Self {
            index: world
                .spec()
                .landmarks
                .iter()
                .enumerate()
                .map(|(i, l)| (l.id, i))
                .collect(),
            world,
            range,
        }
    }
}

impl Perception for WorldPerception<'_> {
    fn position(&self, id: u32) -> Option<[f64; 2]> {
        self.index
            .get(&id)
            .map(|&i| self.world.spec().landmarks[i].pos)
    }
    fn sees(&self, pos: [f64; 2], id: u32) -> bool {
        self.index.get(&id).is_some_and(|&i| {
            d(pos, self.world.spec().landmarks[i].pos) <= self.range
                && self.world.is_fully_visible(pos, i)
        })
    }
    fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
        let mut out: Vec<u32> = self
            .world
            .spec()
            .landmarks
            .iter()
            .enumerate()
            .filter(|(i, l)| d(pos, l.pos) <= self.range && self.world.is_fully_visible(pos, *i))
            .map(|(_, l)| l.id)
            .collect();
        out.sort_unstable();
        out
    }
    fn ids(&self) -> Vec<u32> {
        let mut ids: Vec<u32> = self.index.keys().copied().collect();
        ids.sort_unstable();
        ids
    }
    fn range(&self) -> f64 {
        self.range
    }
}
