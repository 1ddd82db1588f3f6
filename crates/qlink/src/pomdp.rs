//! The QSR level with uncertainty (thesis §4.3.3): a POMDP over (robot state, link state).
//!
//! States `X = Q × Q`: the robot's qualitative state relative to the references (observed:
//! the robot localises in the frame of the references it sees) and the link landmark's
//! (hidden: only the map's distribution is known). Actions: "go to state `a`", allowed
//! when `a` is the current state or a neighbour of it (or any state with direct transitions,
//! §4.4.2). The move succeeds with `p_move`, otherwise the robot stays. Observation after
//! each move: the link is seen with `p_detect` when the robot is in the link's state, with
//! `p_false` otherwise. Reward: `found_reward` (100) when the link is seen in the robot's
//! state, `step_cost` (−1) per step otherwise; the episode ends when the link is seen.
//!
//! Because the robot state is observed and the link state is static, a belief is the robot
//! state plus a distribution over the link's state, and after "not seen" it is updated by
//! Bayes' rule. The finite-horizon problem is then solved **exactly** by expectimax over the
//! reachable beliefs: `(2·|A|)^h` nodes, 4,096 for the quadrant calculus at horizon 4 (tens
//! of microseconds). The same recursion under the optimal policy gives the success
//! probability of eqs. 4.2–4.3, `p_{0:τ} = p_0 + (1 − p_0)·p_{1:τ}`, used as the edge cost
//! `−log p` (eq. 4.4), and the expected number of moves (the "expected transitions" cost).

use serde::{Deserialize, Serialize};

use crate::error::{QlinkError, Result};
use qsr_core::cost::{Budget, Cost};

/// Core-seconds per belief entry updated in a look-ahead, measured: EDC (20 states), direct
/// moves, one thread, horizons 3–5 (1.6 · 10⁵ … 6.4 · 10⁷ entries): 0.8–0.9 ns an entry.
pub const SECONDS_PER_BELIEF_ENTRY: f64 = 9e-10;

/// What one decision's look-ahead may take: a minute of one core (a navigator decides at
/// every step, so a decision of hours is a mistaken horizon, not a long run).
pub const DECISION_BUDGET: Budget = Budget::new(1024.0 * 1024.0 * 1024.0, 60.0);

/// A search POMDP over the states of one calculus.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SearchPomdp {
    /// `allowed[r][a]`: may the robot in `r` head for `a`.
    pub allowed: Vec<Vec<bool>>,
    /// Probability a move reaches its target state.
    pub p_move: f64,
    /// Probability of seeing the link when in its state.
    pub p_detect: f64,
    /// Probability of "seeing" it elsewhere (a false detection; ends the episode unrewarded).
    pub p_false: f64,
    /// Reward for finding the link.
    pub found_reward: f64,
    /// Reward of every other step (negative: a cost).
    pub step_cost: f64,
    /// Planning horizon (decisions).
    pub horizon: usize,
}

/// The optimal first action and what the policy achieves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Decision {
    /// State to head for.
    pub action: usize,
    /// Expected total reward.
    pub value: f64,
    /// Probability of finding the link within the horizon (eq. 4.3).
    pub p_success: f64,
    /// Expected number of moves made.
    pub expected_moves: f64,
}

/// Where the robot may head in one decision.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Moves {
    /// Its current state or a neighbour of it (§4.3.3).
    #[default]
    Neighbours,
    /// Any state (direct transitions, §4.4.2).
    Direct,
}

/// Builds a [`SearchPomdp`] with named settings; the defaults are the thesis's §4.4.1 search
/// (neighbour moves that always succeed, the link seen with probability 0.9 in its state and
/// never elsewhere, rewards 100 / −1, horizon 4).
///
/// ```
/// use qlink::{Moves, SearchPomdp};
/// let quadrant = qsr_core::Calculus::builtin("quadrant")?;
/// let pomdp = SearchPomdp::builder(&quadrant)
///     .moves(Moves::Direct)
///     .p_move(0.9)
///     .horizon(3)
///     .build()?;
/// assert_eq!((pomdp.p_detect, pomdp.horizon), (0.9, 3));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
#[must_use]
pub struct SearchPomdpBuilder<'c> {
    calculus: &'c qsr_core::Calculus,
    moves: Moves,
    p_move: f64,
    p_detect: f64,
    horizon: usize,
}

impl SearchPomdpBuilder<'_> {
    /// Where the robot may head in one decision.
    pub fn moves(mut self, moves: Moves) -> Self {
        self.moves = moves;
        self
    }
    /// Probability a move reaches its target state.
    pub fn p_move(mut self, p: f64) -> Self {
        self.p_move = p;
        self
    }
    /// Probability of seeing the link when in its state.
    pub fn p_detect(mut self, p: f64) -> Self {
        self.p_detect = p;
        self
    }
    /// Planning horizon (decisions).
    pub fn horizon(mut self, h: usize) -> Self {
        self.horizon = h;
        self
    }
    /// The POMDP.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for probabilities outside [0, 1] or horizon 0.
    pub fn build(self) -> Result<SearchPomdp> {
        SearchPomdp::with(
            self.calculus,
            self.moves,
            self.p_move,
            self.p_detect,
            self.horizon,
        )
    }
}

impl SearchPomdp {
    /// A builder on `calculus`'s states, with the thesis's §4.4.1 settings as defaults.
    pub fn builder(calculus: &qsr_core::Calculus) -> SearchPomdpBuilder<'_> {
        SearchPomdpBuilder {
            calculus,
            moves: Moves::Neighbours,
            p_move: 1.0,
            p_detect: 0.9,
            horizon: 4,
        }
    }

    fn with(
        calculus: &qsr_core::Calculus,
        moves: Moves,
        p_move: f64,
        p_detect: f64,
        horizon: usize,
    ) -> Result<Self> {
        let direct = moves == Moves::Direct;
        let n = calculus.n_states();
        let g = calculus.neighbours();
        let allowed = (0..n)
            .map(|r| {
                (0..n)
                    .map(|a| {
                        direct
                            || r == a
                            || g.is_adjacent(
                                qsr_core::StateId(r as u16),
                                qsr_core::StateId(a as u16),
                            )
                    })
                    .collect()
            })
            .collect();
        let p = Self {
            allowed,
            p_move,
            p_detect,
            p_false: 0.0,
            found_reward: 100.0,
            step_cost: -1.0,
            horizon,
        };
        p.validate()?;
        Ok(p)
    }

    /// The same parameters (move and detection probabilities, rewards, horizon; direct
    /// moves if every move is allowed here) on another calculus's states — for hybrid maps,
    /// whose layers have different numbers of states.
    ///
    /// # Errors
    /// As [`SearchPomdpBuilder::build`].
    pub fn for_calculus(&self, calculus: &qsr_core::Calculus) -> Result<Self> {
        let moves = if self.allowed.iter().all(|row| row.iter().all(|&a| a)) {
            Moves::Direct
        } else {
            Moves::Neighbours
        };
        let mut p = Self::with(calculus, moves, self.p_move, self.p_detect, self.horizon)?;
        p.p_false = self.p_false;
        p.found_reward = self.found_reward;
        p.step_cost = self.step_cost;
        Ok(p)
    }

    /// The same POMDP with another probability of detecting the link when the robot is in
    /// its state (e.g. one measured per landmark: visibility-aware edge costs).
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for a probability outside [0, 1].
    pub fn with_p_detect(mut self, p_detect: f64) -> Result<Self> {
        self.p_detect = p_detect;
        self.validate()?;
        Ok(self)
    }

    fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("p_move", self.p_move),
            ("p_detect", self.p_detect),
            ("p_false", self.p_false),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(QlinkError::InvalidParameter(format!(
                    "{name} = {v} is not in [0, 1]"
                )));
            }
        }
        if self.horizon == 0 {
            return Err(QlinkError::InvalidParameter(
                "the horizon must be ≥ 1".into(),
            ));
        }
        self.check_work(self.horizon)
    }

    /// The look-ahead visits about `b^h` beliefs (`b` the most moves allowed from a state) of
    /// `n` entries each: refused beyond [`DECISION_BUDGET`] with the estimate instead of
    /// running without end (issue 17: horizon 1000).
    fn check_work(&self, horizon: usize) -> Result<()> {
        let n = self.n_states().max(1) as f64;
        let b = self
            .allowed
            .iter()
            .map(|row| row.iter().filter(|a| **a).count())
            .max()
            .unwrap_or(1)
            .max(1) as f64;
        Cost::work(n * b.powf(horizon as f64), SECONDS_PER_BELIEF_ENTRY)
            .check(
                &DECISION_BUDGET,
                format!(
                    "a horizon-{horizon} look-ahead over {b} moves per state (n × b^h = {n} × \
                     {b}^{horizon} belief entries)"
                ),
            )
            .map_err(|e| {
                QlinkError::InvalidParameter(e.hint("use a shorter horizon").to_string())
            })?;
        Ok(())
    }

    /// Number of qualitative states.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.allowed.len()
    }

    /// Belief over the link's state after *not* seeing it with the robot in `r`.
    #[must_use]
    pub fn update_not_seen(&self, belief: &[f64], r: usize) -> Vec<f64> {
        let mut b: Vec<f64> = belief
            .iter()
            .enumerate()
            .map(|(q, &p)| {
                p * if q == r {
                    1.0 - self.p_detect
                } else {
                    1.0 - self.p_false
                }
            })
            .collect();
        let s: f64 = b.iter().sum();
        if s > 0.0 {
            b.iter_mut().for_each(|x| *x /= s);
        }
        b
    }

    /// The optimal decision for the robot in `robot` with link belief `belief`.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for a belief of the wrong length, negative or NaN
    /// entries, or a robot state out of range.
    pub fn decide(&self, robot: usize, belief: &[f64]) -> Result<Decision> {
        self.decide_with(robot, belief, self.horizon)
    }

    /// As [`SearchPomdp::decide`] with another horizon.
    ///
    /// # Errors
    /// As [`SearchPomdp::decide`].
    pub fn decide_with(&self, robot: usize, belief: &[f64], horizon: usize) -> Result<Decision> {
        let n = self.n_states();
        if belief.len() != n
            || robot >= n
            || belief.iter().any(|p| p.is_nan() || *p < 0.0)
            || horizon == 0
        {
            return Err(QlinkError::InvalidParameter(format!(
                "belief of {} entries for {n} states, robot state {robot}, horizon {horizon}",
                belief.len()
            )));
        }
        self.check_work(horizon)?;
        let s: f64 = belief.iter().sum();
        let b: Vec<f64> = if s > 0.0 {
            belief.iter().map(|p| p / s).collect()
        } else {
            vec![1.0 / n as f64; n]
        };
        Ok(self.best(robot, &b, horizon))
    }

    /// Expectimax: (value, p_success, expected moves) of each action; the best returned.
    fn best(&self, r: usize, b: &[f64], h: usize) -> Decision {
        let mut best: Option<Decision> = None;
        for a in 0..self.n_states() {
            if !self.allowed[r][a] {
                continue;
            }
            let (v, p, m) = self.q_value(r, a, b, h);
            let d = Decision {
                action: a,
                value: v,
                p_success: p,
                expected_moves: m,
            };
            // ties: the higher success probability, then the lower state id
            if best.is_none_or(|x| {
                v > x.value + 1e-12 || ((v - x.value).abs() <= 1e-12 && p > x.p_success + 1e-12)
            }) {
                best = Some(d);
            }
        }
        best.unwrap_or(Decision {
            action: r,
            value: 0.0,
            p_success: 0.0,
            expected_moves: 0.0,
        })
    }

    fn q_value(&self, r: usize, a: usize, b: &[f64], h: usize) -> (f64, f64, f64) {
        let outcomes: [(usize, f64); 2] = if a == r {
            [(r, 1.0), (r, 0.0)]
        } else {
            [(a, self.p_move), (r, 1.0 - self.p_move)]
        };
        let (mut v, mut p, mut m) = (0.0, 0.0, 0.0);
        for (r2, pr) in outcomes {
            if pr == 0.0 {
                continue;
            }
            let p_true = b[r2] * self.p_detect;
            let p_fa = (1.0 - b[r2]) * self.p_false;
            let p_not = 1.0 - p_true - p_fa;
            let (mut vv, mut pp, mut mm) = (p_true * self.found_reward, p_true, 1.0);
            // a false detection ends the episode with the step cost
            vv += p_fa * self.step_cost;
            if p_not > 0.0 {
                vv += p_not * self.step_cost;
                if h > 1 {
                    let nb = self.update_not_seen(b, r2);
                    let d = self.best(r2, &nb, h - 1);
                    vv += p_not * d.value;
                    pp += p_not * d.p_success;
                    mm += p_not * d.expected_moves;
                }
            }
            v += pr * vv;
            p += pr * pp;
            m += pr * mm;
        }
        (v, p, m)
    }
}
