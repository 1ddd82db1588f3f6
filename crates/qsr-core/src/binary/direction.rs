//! [`DirectionPartition`]: how a binary calculus cuts the circle of directions about a point.
//!
//! Every binary point calculus here is decided by *angles*: the direction from one point to
//! the other, measured from a heading (OPRA: each point's own; STAR: one shared reference
//! direction). So a calculus is a partition of the circle, and exactness comes from doing the
//! arithmetic on whole *ticks* instead of radians: the circle is `2m` *units` (`π/m` each,
//! so every boundary ray sits on a whole unit) and every unit is split into
//! [`TICKS_PER_UNIT`] ticks. See [`crate::binary`] for why a tick grid decides composition
//! exactly.

use std::f64::consts::PI;

/// Ticks per unit (`π/m`) of the derivation grid.
///
/// Every relation of a configuration of three oriented points is a condition on a
/// *difference of two angles* (edge directions and headings) lying in an interval with whole
///-unit bounds. Such a system over `n` angles (here 6: three edge directions, three headings)
/// that is satisfiable has a solution on the grid `1/n` units (difference constraints: shift
/// each strict bound by `ε = 1/n`; a shortest-path solution is whole units minus at most
/// `(n−1)·ε`). So 6 ticks per unit reach every realisable combination.
pub const TICKS_PER_UNIT: usize = 6;

/// Directions within this many units (`π/m`) of a boundary ray count as on it when a
/// configuration is classified from floating-point coordinates (measured data never lands
/// exactly on a ray; computed data, e.g. a point straight ahead, does up to rounding).
pub const RAY_TOLERANCE: f64 = 1e-9;

/// How the circle of directions is cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DirectionPartition {
    /// OPRA's partition with granularity `m`: `m` lines through the point, one along the
    /// heading, give `2m` rays (even sectors `0, 2, …`, relations of their own) and `2m` open
    /// sectors between them (odd), numbered counter-clockwise from the heading: `4m` sectors.
    Opra {
        /// Granularity (lines through the point), `≥ 1`.
        m: usize,
    },
    /// STAR's partition as SparQ's revised star calculus: `m` half-open sectors of `2π/m`,
    /// sector 0 centred on the reference direction, counter-clockwise, each sector owning its
    /// clockwise boundary ray (`[(2k−1)·π/m, (2k+1)·π/m)`).
    HalfOpen {
        /// Sectors, `≥ 2`.
        m: usize,
    },
}

impl DirectionPartition {
    /// The granularity: the circle is `2·m` units.
    #[must_use]
    pub fn m(self) -> usize {
        match self {
            Self::Opra { m } | Self::HalfOpen { m } => m,
        }
    }

    /// Sectors in the partition.
    #[must_use]
    pub fn n_sectors(self) -> usize {
        match self {
            Self::Opra { m } => 4 * m,
            Self::HalfOpen { m } => m,
        }
    }

    /// Ticks in a full turn.
    #[must_use]
    pub fn ticks_per_turn(self) -> usize {
        2 * self.m() * TICKS_PER_UNIT
    }

    /// The sector of a direction given in ticks (`0..ticks_per_turn`) with `per_unit` ticks
    /// per unit (the derivation uses [`TICKS_PER_UNIT`]; tests use others to check it).
    #[must_use]
    pub(crate) fn sector_of_tick(self, tick: usize, per_unit: usize) -> usize {
        let turn = 2 * self.m() * per_unit;
        let t = tick % turn;
        match self {
            Self::Opra { .. } => {
                let (q, r) = (t / per_unit, t % per_unit);
                if r == 0 { 2 * q } else { 2 * q + 1 }
            }
            Self::HalfOpen { m } => ((t + per_unit) / (2 * per_unit)) % m,
        }
    }

    /// The sector of a direction `theta` (radians, counter-clockwise from the heading; any
    /// finite value). Rays within [`RAY_TOLERANCE`] units are snapped onto.
    #[must_use]
    pub fn sector_of_angle(self, theta: f64) -> usize {
        let m = self.m();
        let units = 2.0 * m as f64;
        let mut u = (theta / (PI / m as f64)).rem_euclid(units);
        let nearest = u.round();
        if (u - nearest).abs() <= RAY_TOLERANCE {
            u = nearest;
        }
        if u >= units {
            u = 0.0;
        }
        // `u` is now in [0, 2m) and exact on a ray: the same rule as the tick version.
        match self {
            Self::Opra { .. } => {
                let q = u.floor();
                // Truncation is exact: q is a whole number below 2m ≤ 2^16.
                let qi = q as usize;
                if u == q { 2 * qi } else { 2 * qi + 1 }
            }
            Self::HalfOpen { m } => (((u + 1.0) / 2.0).floor() as usize) % m,
        }
    }

    /// Whether a sector is a single ray (measure zero on the circle).
    #[must_use]
    pub fn is_ray(self, sector: usize) -> bool {
        matches!(self, Self::Opra { .. }) && sector.is_multiple_of(2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_and_angle_classification_agree_on_every_tick() {
        for p in [
            DirectionPartition::Opra { m: 1 },
            DirectionPartition::Opra { m: 3 },
            DirectionPartition::HalfOpen { m: 8 },
            DirectionPartition::HalfOpen { m: 4 },
        ] {
            let turn = p.ticks_per_turn();
            for t in 0..turn {
                let theta = t as f64 / turn as f64 * std::f64::consts::TAU;
                assert_eq!(
                    p.sector_of_tick(t, TICKS_PER_UNIT),
                    p.sector_of_angle(theta),
                    "{p:?} tick {t}"
                );
            }
        }
    }

    #[test]
    fn opra1_sectors_are_front_left_back_right() {
        let p = DirectionPartition::Opra { m: 1 };
        assert_eq!(p.sector_of_angle(0.0), 0);
        assert_eq!(p.sector_of_angle(1.0), 1);
        assert_eq!(p.sector_of_angle(PI), 2);
        assert_eq!(p.sector_of_angle(-1.0), 3);
        assert_eq!(p.sector_of_angle(-1e-12), 0, "snapped onto the ray");
    }

    #[test]
    fn half_open_sectors_own_their_clockwise_boundary() {
        let p = DirectionPartition::HalfOpen { m: 8 };
        let b = PI / 8.0; // boundary between sector 0 and sector 1
        assert_eq!(p.sector_of_angle(b), 1);
        assert_eq!(p.sector_of_angle(b - 1e-6), 0);
        assert_eq!(p.sector_of_angle(-b), 0);
        assert_eq!(p.sector_of_angle(-b - 1e-6), 7);
    }
}
