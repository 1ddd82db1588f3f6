//! GQR's network files (`.csp`), in and out.
//!
//! A file holds one or more networks. Each starts with a line `N #comment` — `N` the largest
//! node index (nodes are `0..=N`), the comment usually the generator's parameters — followed by
//! constraints `i j ( r1 r2 ... )` and ends at a line starting with `.` (or at the end of the
//! file). Lines starting with `#` and blank lines are skipped; a pair given twice gets the
//! intersection, as GQR does. A pair `i i` is read as GQR reads it: a set holding the
//! identity says nothing, one without it leaves `i` no relation to any other node.

use std::fmt::Write as _;

use super::algebra::AsBinaryAlgebra;
use super::network::{BinaryNetwork, MAX_BINARY_POINTS};
use crate::error::{QsrError, Result};
use crate::reason::StateSet;
use crate::text_file::shorten;

/// One network of a `.csp` file with its header's comment.
#[derive(Debug, Clone)]
pub struct GqrNetwork {
    /// The header's text after `#` (GQR prints it before its verdict), trimmed.
    pub name: String,
    /// The network; its points are named `0`, `1`, ….
    pub network: BinaryNetwork,
}

fn error(line: usize, reason: impl Into<String>) -> QsrError {
    QsrError::Network {
        at: format!("line {line}"),
        reason: reason.into(),
    }
}

/// Reads every network of a `.csp` text.
///
/// ```
/// use qsr_core::binary::{BinaryCalculus, close_binary, from_gqr_csp_str};
/// let opra = BinaryCalculus::builtin("opra-1")?;
/// let nets = from_gqr_csp_str(&opra, "2 #convoy\n0 1 ( 0_0 )\n1 2 ( 0_0 )\n.\n")?;
/// assert_eq!(nets[0].name, "convoy");
/// let closed = close_binary(nets[0].network.clone())?;
/// assert_eq!(closed.network.labels_of(0, 2), ["0_2", "2_0", "s_0"]);
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
///
/// # Errors
/// [`QsrError::Network`] naming the line: a header that is not a node count, more than
/// [`MAX_BINARY_POINTS`] nodes, a constraint that is not `i j ( r ... )`, a node past the
/// header's, a relation the calculus does not have, no network at all.
pub fn from_gqr_csp_str(algebra: &impl AsBinaryAlgebra, text: &str) -> Result<Vec<GqrNetwork>> {
    let algebra = algebra.binary_algebra();
    let mut out = Vec::new();
    let mut current: Option<GqrNetwork> = None;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let Some(net) = current.as_mut() else {
            // A `.` with no network open ends nothing (qrm writes `# name status` and `.`
            // where a search found no network to print).
            if !line.starts_with('.') {
                current = Some(header(&algebra, line, line_no)?);
            }
            continue;
        };
        if line.starts_with('.') {
            out.extend(current.take());
            continue;
        }
        let (a, b, labels) = constraint(line, line_no, net.network.n_points())?;
        let self_relation = a == b;
        let mut set = StateSet::empty(algebra.n_states());
        for l in labels.split_whitespace() {
            let s = algebra.state(l).map_err(|_| {
                error(
                    line_no,
                    format!(
                        "calculus `{}` has no relation `{}`",
                        algebra.name(),
                        shorten(l)
                    ),
                )
            })?;
            set.insert(s);
        }
        if self_relation {
            // GQR intersects the diagonal with the identity: a set without it leaves the
            // point no relation to anything.
            if algebra.identity().is_none_or(|id| !set.contains(id)) {
                let empty = StateSet::empty(algebra.n_states());
                for k in (0..net.network.n_points()).filter(|&k| k != a) {
                    net.network.set(a, k, &empty);
                }
            }
            continue;
        }
        net.network.constrain(a, b, &set);
    }
    out.extend(current);
    if out.is_empty() {
        return Err(error(
            1,
            "no network: a .csp file starts with `N #comment` (N the largest node index)",
        ));
    }
    Ok(out)
}

fn header(algebra: &super::BinaryAlgebra, line: &str, line_no: usize) -> Result<GqrNetwork> {
    let (count, comment) = match line.split_once('#') {
        Some((c, rest)) => (c.trim(), rest.trim()),
        None => (line, ""),
    };
    let largest: usize = count.parse().map_err(|_| {
        error(
            line_no,
            format!(
                "expected a network's header `N #comment` (N the largest node index), got `{}`",
                shorten(line)
            ),
        )
    })?;
    if largest >= MAX_BINARY_POINTS {
        return Err(error(
            line_no,
            format!("{largest} is the largest node index; at most {MAX_BINARY_POINTS} nodes"),
        ));
    }
    let network = BinaryNetwork::universal(algebra, (0..=largest).map(|i| i.to_string()))?;
    Ok(GqrNetwork {
        name: comment.to_owned(),
        network,
    })
}

/// `i j ( labels )`.
fn constraint(line: &str, line_no: usize, n: usize) -> Result<(usize, usize, &str)> {
    let shape = || {
        error(
            line_no,
            format!(
                "expected a constraint `i j ( r1 r2 ... )`, got `{}`",
                shorten(line)
            ),
        )
    };
    let open = line.find('(').ok_or_else(shape)?;
    let close = line[open..].find(')').map(|c| open + c).ok_or_else(shape)?;
    if !line[close + 1..].trim().is_empty() {
        return Err(shape());
    }
    let mut nodes = line[..open].split_whitespace();
    let (Some(a), Some(b), None) = (nodes.next(), nodes.next(), nodes.next()) else {
        return Err(shape());
    };
    let node = |t: &str| -> Result<usize> {
        let v: usize = t.parse().map_err(|_| shape())?;
        if v >= n {
            return Err(error(
                line_no,
                format!("node {v} is past the header's largest index {}", n - 1),
            ));
        }
        Ok(v)
    };
    let (a, b) = (node(a)?, node(b)?);
    Ok((a, b, &line[open + 1..close]))
}

impl BinaryNetwork {
    /// The network as one `.csp` entry: `N #comment`, then `i j ( labels )` for every pair
    /// `i < j` that is not universal, then `.`. Points are written by index; when their names
    /// are not `0`, `1`, … a comment line gives each index's name.
    #[must_use]
    pub fn to_gqr_csp(&self, comment: &str) -> String {
        let n = self.n_points();
        let n_states = self.algebra().n_states();
        let mut out = format!("{} #{}\n", n.saturating_sub(1), comment.replace('\n', " "));
        let numbered = self
            .names()
            .iter()
            .enumerate()
            .all(|(i, name)| *name == i.to_string());
        if !numbered {
            let names: Vec<String> = self
                .names()
                .iter()
                .enumerate()
                .map(|(i, name)| format!("{i}={name}"))
                .collect();
            out.push_str(&format!("# points: {}\n", names.join(" ")));
        }
        let universal = StateSet::universal(n_states);
        for i in 0..n {
            for j in i + 1..n {
                let words = self.words_of(i, j);
                if words == universal.words() {
                    continue;
                }
                let _ = write!(out, "{i} {j} (");
                for r in crate::reason::iter_bits(words) {
                    out.push(' ');
                    out.push_str(self.algebra().label(r));
                }
                out.push_str(" )\n");
            }
        }
        out.push_str(".\n");
        out
    }
}
