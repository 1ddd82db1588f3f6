//! What the robot detects: the [`Perception`] trait and the simplest sensor behind it, range
//! only ([`RangePerception`]). A simulator's perception with occlusion (the studies'
//! `WorldPerception`) or a real robot's detector implements the same trait.
//!
//! A perception answers "is landmark `id` detected from here?". It also knows where the
//! landmark is ([`Perception::position`]), because a simulated detection *measures* that
//! position relative to the robot; the navigator reads it only for a landmark it detects at
//! that moment, and otherwise falls back on what it remembers (see [`crate::execution`]).

use std::collections::HashMap;

/// Which way the sensor looks when the robot senses.
///
/// A robot that stands still sweeps its sensor over every direction (thesis §4.4.2: "once the
/// robot reaches this position it performs a sensor sweep"); one that senses on the move sees
/// what its sensor's field of view takes in ahead — a 270° scanner is blind behind it. A
/// sensor that sees all around at every moment (the Table 4.1 robots) ignores the difference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Look {
    /// Every direction: the robot stands and sweeps.
    Sweep,
    /// Driving, facing this world heading (rad).
    Ahead(f64),
}

/// What the robot detects.
pub trait Perception: Sync {
    /// The landmark's position: what a detection measures. The navigator reads it only for a
    /// landmark detected at that moment ([`crate::execution::References`]).
    fn position(&self, id: u32) -> Option<[f64; 2]>;
    /// Whether `id` is detected from `pos`.
    fn sees(&self, pos: [f64; 2], id: u32) -> bool;
    /// Every landmark detected from `pos`, sorted.
    fn visible(&self, pos: [f64; 2]) -> Vec<u32>;
    /// Whether `id` is detected from `pos` looking as `look` says. By default the sensor sees
    /// all around ([`Perception::sees`]); a sensor with a limited field of view overrides it.
    fn sees_looking(&self, pos: [f64; 2], look: Look, id: u32) -> bool {
        let _ = look;
        self.sees(pos, id)
    }
    /// Every landmark detected from `pos` looking as `look` says, sorted (by default
    /// [`Perception::visible`]).
    fn visible_looking(&self, pos: [f64; 2], look: Look) -> Vec<u32> {
        let _ = look;
        self.visible(pos)
    }
    /// Every landmark the sensor could report, sorted: what a false report
    /// ([`crate::DetectionNoise::false_rate`]) takes a feature for.
    fn ids(&self) -> Vec<u32>;
    /// The sensor range.
    fn range(&self) -> f64;
}

/// Point landmarks detected within a range (no occlusion).
#[derive(Debug, Clone)]
pub struct RangePerception {
    ids: Vec<u32>,
    pos: Vec<[f64; 2]>,
    index: HashMap<u32, usize>,
    range: f64,
}

impl RangePerception {
    /// Landmarks `(id, position)` seen within `range`.
    #[must_use]
    pub fn new(landmarks: &[(u32, [f64; 2])], range: f64) -> Self {
        let mut sorted = landmarks.to_vec();
        sorted.sort_by_key(|l| l.0);
        Self {
            index: sorted.iter().enumerate().map(|(i, l)| (l.0, i)).collect(),
            ids: sorted.iter().map(|l| l.0).collect(),
            pos: sorted.iter().map(|l| l.1).collect(),
            range,
        }
    }
}

/// Euclidean distance between two points.
#[must_use]
pub fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

impl Perception for RangePerception {
    fn position(&self, id: u32) -> Option<[f64; 2]> {
        self.index.get(&id).map(|&i| self.pos[i])
    }
    fn sees(&self, pos: [f64; 2], id: u32) -> bool {
        self.index
            .get(&id)
            .is_some_and(|&i| distance(pos, self.pos[i]) <= self.range)
    }
    fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
        self.ids
            .iter()
            .zip(&self.pos)
            .filter(|(_, p)| distance(pos, **p) <= self.range)
            .map(|(id, _)| *id)
            .collect()
    }
    fn ids(&self) -> Vec<u32> {
        self.ids.clone()
    }
    fn range(&self) -> f64 {
        self.range
    }
}
