//! The Link Graph level (thesis §4.3.2): map elements are nodes, an edge joins two elements
//! sharing at least β landmarks (the *links*), and the plan `P*` is the cheapest path
//! (eq. 4.1) from any element the robot can localise in to any element holding the goal.
//!
//! Edges are directed because the cost of a transition `M_i → M_j` — searching for the link
//! in `M_i`'s frame — depends on the direction when it comes from the POMDP (eqs. 4.2–4.4).
//! Shortest paths are multi-source Dijkstra over the petgraph graph (the start is a *set* of
//! elements, the goal a set too), with an optional set of excluded edges for contingency
//! re-planning; for many queries to one goal, [`LinkGraph::distance_field`] runs Dijkstra
//! once backwards from the goal's elements and [`DistanceField::path_from`] reads any plan
//! off it.

use std::cmp::Reverse;
use std::collections::{BTreeMap, BTreeSet, BinaryHeap};

use petgraph::Direction;
use petgraph::graph::{DiGraph, EdgeIndex, NodeIndex};
use petgraph::visit::EdgeRef;
use serde::{Deserialize, Serialize};

use crate::error::{QlinkError, Result};
use crate::map::QualitativeMap;

/// How edges are priced (thesis §4.3.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CostModel {
    /// 1 per transition: fewest map elements.
    Unit,
    /// Expected number of qualitative-state traversals to find the link.
    ExpectedTransitions,
    /// −log P(success) of the transition (eqs. 4.2–4.4): most likely to complete.
    NegLogSuccess,
}

impl std::str::FromStr for CostModel {
    type Err = QlinkError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "unit" => Ok(Self::Unit),
            "expected-transitions" => Ok(Self::ExpectedTransitions),
            "neg-log-success" => Ok(Self::NegLogSuccess),
            _ => Err(QlinkError::InvalidParameter(format!(
                "unknown cost model `{s}` (unit, expected-transitions, neg-log-success)"
            ))),
        }
    }
}

/// An edge: the shared landmarks and the cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkEdge {
    links: [u32; 3],
    n_links: u8,
    /// Cost of taking the edge in its direction.
    pub cost: f64,
}

impl LinkEdge {
    /// The link landmarks `L_i ∩ L_j`.
    #[must_use]
    pub fn links(&self) -> &[u32] {
        &self.links[..usize::from(self.n_links)]
    }
}

/// A plan over map elements.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Elements from the start element to a goal element.
    pub elements: Vec<usize>,
    /// Total cost.
    pub cost: f64,
}

impl Plan {
    /// Number of transitions |P|.
    #[must_use]
    pub fn len(&self) -> usize {
        self.elements.len().saturating_sub(1)
    }

    /// True for a plan that starts in a goal element.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The Link Graph.
#[derive(Debug, Clone)]
pub struct LinkGraph {
    graph: DiGraph<usize, LinkEdge>,
    beta: usize,
}

/// What [`LinkGraph::dijkstra`] found: costs, predecessors, the target settled first.
struct Search {
    dist: Vec<f64>,
    prev: Vec<usize>,
    reached: Option<usize>,
}

/// Costs to a goal from every element (`f64::INFINITY`: no path).
#[derive(Debug, Clone)]
pub struct DistanceField {
    goal: u32,
    dist: Vec<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

impl LinkGraph {
    /// Builds the graph: an edge each way between elements sharing ≥ β landmarks, priced by
    /// `cost(from, to, links)`.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for β = 0 or β > 3, or a cost that is negative or NaN.
    pub fn new(
        map: &QualitativeMap,
        beta: usize,
        cost: impl Fn(usize, usize, &[u32]) -> f64,
    ) -> Result<Self> {
        if !(1..=3).contains(&beta) {
            return Err(QlinkError::InvalidParameter(format!(
                "β = {beta}: the number of shared landmarks must be 1, 2 or 3"
            )));
        }
        let n = map.elements().len();
        let mut graph: DiGraph<usize, LinkEdge> = DiGraph::with_capacity(n, 0);
        for i in 0..n {
            graph.add_node(i);
        }
        // shared landmarks of every pair that shares one, found through the landmark index
        let mut shared: BTreeMap<(usize, usize), Vec<u32>> = BTreeMap::new();
        for l in map.landmarks() {
            let list = map.elements_with(l);
            for (a, &i) in list.iter().enumerate() {
                for &j in &list[a + 1..] {
                    shared.entry((i, j)).or_default().push(l);
                }
            }
        }
        for ((i, j), links) in shared {
            if links.len() < beta {
                continue;
            }
            let mut arr = [0u32; 3];
            arr[..links.len()].copy_from_slice(&links);
            for (a, b) in [(i, j), (j, i)] {
                let c = cost(a, b, &links);
                if c.is_nan() || c < 0.0 {
                    return Err(QlinkError::InvalidParameter(format!(
                        "edge {a} → {b}: cost {c} is not a non-negative number"
                    )));
                }
                graph.add_edge(
                    NodeIndex::new(a),
                    NodeIndex::new(b),
                    LinkEdge {
                        links: arr,
                        n_links: links.len() as u8,
                        cost: c,
                    },
                );
            }
        }
        Ok(Self { graph, beta })
    }

    /// β.
    #[must_use]
    pub fn beta(&self) -> usize {
        self.beta
    }

    /// Number of elements (nodes).
    #[must_use]
    pub fn n_elements(&self) -> usize {
        self.graph.node_count()
    }

    /// Number of directed edges.
    #[must_use]
    pub fn n_edges(&self) -> usize {
        self.graph.edge_count()
    }

    /// The petgraph graph (node weight = element index).
    #[must_use]
    pub fn graph(&self) -> &DiGraph<usize, LinkEdge> {
        &self.graph
    }

    /// The edge `from → to`, if any.
    #[must_use]
    pub fn edge(&self, from: usize, to: usize) -> Option<&LinkEdge> {
        self.graph
            .find_edge(NodeIndex::new(from), NodeIndex::new(to))
            .map(|e| &self.graph[e])
    }

    /// The cheapest plan from any of `starts` to any element holding `goal`, avoiding the
    /// directed edges in `excluded` (failed transitions).
    ///
    /// # Errors
    /// [`QlinkError::UnknownLandmark`] when no element holds the goal;
    /// [`QlinkError::InvalidParameter`] for no start; [`QlinkError::NoPath`].
    pub fn plan(
        &self,
        map: &QualitativeMap,
        starts: &[usize],
        goal: u32,
        excluded: &BTreeSet<(usize, usize)>,
    ) -> Result<Plan> {
        let goals = map.elements_with(goal);
        if goals.is_empty() {
            return Err(QlinkError::UnknownLandmark(goal));
        }
        if starts.is_empty() {
            return Err(QlinkError::InvalidParameter(
                "no start element: the robot sees no two landmarks of one map element".into(),
            ));
        }
        let is_goal: BTreeSet<usize> = goals.iter().copied().collect();
        let search = self.dijkstra(starts, Direction::Outgoing, excluded, Some(&is_goal));
        let Some(u) = search.reached else {
            return Err(QlinkError::NoPath { goal });
        };
        let mut elements = vec![u];
        let mut x = u;
        while search.prev[x] != usize::MAX {
            x = search.prev[x];
            elements.push(x);
        }
        elements.reverse();
        Ok(Plan {
            elements,
            cost: search.dist[u],
        })
    }

    /// Costs from every element to the goal's elements (Dijkstra backwards, once per goal).
    ///
    /// # Errors
    /// [`QlinkError::UnknownLandmark`].
    pub fn distance_field(&self, map: &QualitativeMap, goal: u32) -> Result<DistanceField> {
        let goals = map.elements_with(goal);
        if goals.is_empty() {
            return Err(QlinkError::UnknownLandmark(goal));
        }
        let search = self.dijkstra(goals, Direction::Incoming, &BTreeSet::new(), None);
        Ok(DistanceField {
            goal,
            dist: search.dist,
        })
    }

    /// Multi-source Dijkstra, the one shortest-path search of the crate: from every element
    /// of `sources` at cost 0, along edges in `direction` (`Incoming`: backwards, costs *to*
    /// the sources), skipping the directed edges in `excluded`, stopping at the first element
    /// of `targets` settled. Ties go to the lower predecessor id, so plans do not depend on
    /// edge order.
    ///
    /// Why not `petgraph::algo::dijkstra`: it starts from one node, returns no predecessors
    /// (a plan needs them) and breaks ties by heap order; a super-source would mean copying
    /// the graph per query. The test `agrees_with_petgraph_dijkstra_from_one_source` checks
    /// this search against it.
    fn dijkstra(
        &self,
        sources: &[usize],
        direction: Direction,
        excluded: &BTreeSet<(usize, usize)>,
        targets: Option<&BTreeSet<usize>>,
    ) -> Search {
        let n = self.graph.node_count();
        let mut dist = vec![f64::INFINITY; n];
        let mut prev = vec![usize::MAX; n];
        let mut heap = BinaryHeap::new();
        for &s in sources {
            if s < n && dist[s] > 0.0 {
                dist[s] = 0.0;
                heap.push(Reverse((Key(0.0), s)));
            }
        }
        while let Some(Reverse((Key(d), u))) = heap.pop() {
            if d > dist[u] {
                continue;
            }
            if targets.is_some_and(|t| t.contains(&u)) {
                return Search {
                    dist,
                    prev,
                    reached: Some(u),
                };
            }
            for e in self.graph.edges_directed(NodeIndex::new(u), direction) {
                let (from, to) = (e.source().index(), e.target().index());
                let v = if direction == Direction::Outgoing {
                    to
                } else {
                    from
                };
                if excluded.contains(&(from, to)) {
                    continue;
                }
                let nd = d + e.weight().cost;
                if nd < dist[v] || (nd == dist[v] && u < prev[v]) {
                    dist[v] = nd;
                    prev[v] = u;
                    heap.push(Reverse((Key(nd), v)));
                }
            }
        }
        Search {
            dist,
            prev,
            reached: None,
        }
    }

    fn edge_index(&self, from: usize, to: usize) -> Option<EdgeIndex> {
        self.graph
            .find_edge(NodeIndex::new(from), NodeIndex::new(to))
    }
}

impl DistanceField {
    /// The goal landmark.
    #[must_use]
    pub fn goal(&self) -> u32 {
        self.goal
    }

    /// Cost from element `i` (∞: no path).
    #[must_use]
    pub fn cost(&self, i: usize) -> f64 {
        self.dist.get(i).copied().unwrap_or(f64::INFINITY)
    }

    /// The cheapest plan from any of `starts`, read off the field (ties: lowest element id).
    ///
    /// # Errors
    /// [`QlinkError::NoPath`]; [`QlinkError::InvalidParameter`] for no start.
    pub fn path_from(&self, graph: &LinkGraph, starts: &[usize]) -> Result<Plan> {
        let Some(&start) = starts
            .iter()
            .filter(|&&s| self.cost(s).is_finite())
            .min_by(|&&a, &&b| self.cost(a).total_cmp(&self.cost(b)).then(a.cmp(&b)))
        else {
            return if starts.is_empty() {
                Err(QlinkError::InvalidParameter("no start element".into()))
            } else {
                Err(QlinkError::NoPath { goal: self.goal })
            };
        };
        let mut elements = vec![start];
        let mut u = start;
        let mut guard = 0;
        while self.dist[u] > 0.0 {
            let tol = 1e-9 * self.dist[u].max(1.0);
            let next = graph
                .graph
                .edges(NodeIndex::new(u))
                .filter(|e| {
                    (self.dist[e.target().index()] + e.weight().cost - self.dist[u]).abs() <= tol
                })
                .map(|e| e.target().index())
                .min();
            let Some(v) = next else {
                return Err(QlinkError::NoPath { goal: self.goal });
            };
            debug_assert!(graph.edge_index(u, v).is_some());
            elements.push(v);
            u = v;
            guard += 1;
            if guard > self.dist.len() {
                return Err(QlinkError::NoPath { goal: self.goal });
            }
        }
        Ok(Plan {
            cost: self.dist[start],
            elements,
        })
    }
}

/// Edge prices for [`LinkGraph::new`] under `model`, with one search POMDP per map layer:
/// for the transition `M_i → M_j` the link `L` is searched in the frame of `M_i`'s other two
/// landmarks, starting from any robot state with equal probability (where the robot will
/// be is not known when planning), with the map's distribution over `{A, B : L}`.
/// `Unit` is 1; `ExpectedTransitions` is the POMDP's expected number of moves;
/// `NegLogSuccess` is `−ln p_{0:τ}` (eq. 4.4).
pub fn pomdp_cost<'a>(
    map: &'a QualitativeMap,
    pomdps: &'a [crate::pomdp::SearchPomdp],
    model: CostModel,
) -> impl Fn(usize, usize, &[u32]) -> f64 + 'a {
    move |i, _j, links| {
        if model == CostModel::Unit {
            return 1.0;
        }
        let e = &map.elements()[i];
        let Some(pomdp) = pomdps.get(e.layer) else {
            return f64::INFINITY;
        };
        let link = links.first().copied().unwrap_or(e.landmarks[0]);
        let refs: Vec<u32> = e.landmarks.iter().copied().filter(|&l| l != link).collect();
        let n = pomdp.n_states();
        let belief = match refs.as_slice() {
            [a, b] => map.belief(i, [*a, *b, link]),
            _ => None,
        }
        .unwrap_or_else(|| vec![1.0; n]);
        let decisions: Vec<crate::pomdp::Decision> = (0..n)
            .filter_map(|r| pomdp.decide(r, &belief).ok())
            .collect();
        let mean = |f: fn(&crate::pomdp::Decision) -> f64| {
            decisions.iter().map(f).sum::<f64>() / decisions.len().max(1) as f64
        };
        match model {
            CostModel::ExpectedTransitions => mean(|d| d.expected_moves),
            _ => -mean(|d| d.p_success).max(1e-12).ln(),
        }
    }
}
