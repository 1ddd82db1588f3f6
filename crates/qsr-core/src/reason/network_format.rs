//! The text forms a constraint network is read from, and telling them apart.

use crate::reason::Network;
use crate::{Calculus, QsrError, Result};

/// A constraint network's text form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NetworkFormat {
    /// `{"constraints": [["A", "B", "C", ["label", ...]], ...]}` ([`Network::to_json`]).
    Json,
    /// SparQ's `((A B (r1 r2) C) ...)` ([`Network::to_sparq`]).
    Sparq,
    /// GQR's `.csp`: `N #comment`, then `i j ( r1 r2 )` lines, then `.` — binary networks
    /// only ([`crate::binary::from_gqr_csp_str`]).
    Gqr,
}

impl NetworkFormat {
    /// The form of `text` by its first character that is not white space: `{` JSON, `(`
    /// SparQ, a digit or `#` GQR's `.csp`.
    ///
    /// # Errors
    /// [`QsrError::Network`] for an empty text or another first character, saying which.
    pub fn detect(text: &str) -> Result<Self> {
        match text.trim_start().chars().next() {
            Some('{') => Ok(Self::Json),
            Some('(') => Ok(Self::Sparq),
            Some(c) if c.is_ascii_digit() || c == '#' => Ok(Self::Gqr),
            Some(c) => Err(QsrError::Network {
                at: format!("its first character `{c}`"),
                reason: "JSON starts with `{`, SparQ with `(`, GQR's .csp with its node count"
                    .into(),
            }),
            None => Err(QsrError::Network {
                at: "its start".into(),
                reason: "empty input, expected a constraint network".into(),
            }),
        }
    }
}

impl Network {
    /// Reads a network of `calculus` in `format`.
    ///
    /// # Errors
    /// As [`Network::from_json_str`] and [`Network::from_sparq_str`].
    pub fn parse(calculus: &Calculus, text: &str, format: NetworkFormat) -> Result<Self> {
        match format {
            NetworkFormat::Json => Self::from_json_str(calculus, text),
            NetworkFormat::Sparq => Self::from_sparq_str(calculus, text),
            NetworkFormat::Gqr => Err(QsrError::Network {
                at: "the file".into(),
                reason: format!(
                    "GQR's .csp form holds binary networks; `{}` is ternary (use JSON or SparQ)",
                    calculus.name()
                ),
            }),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    #[test]
    fn the_form_is_told_by_the_first_character() {
        assert_eq!(
            NetworkFormat::detect("  \n{\"constraints\": []}").unwrap(),
            NetworkFormat::Json
        );
        assert_eq!(
            NetworkFormat::detect("((a b (l) c))").unwrap(),
            NetworkFormat::Sparq
        );
        assert_eq!(
            NetworkFormat::detect("9 #N10\n0 1 ( DC )\n.").unwrap(),
            NetworkFormat::Gqr
        );
        let e = NetworkFormat::detect("a b c").unwrap_err().to_string();
        assert!(e.contains("`a`") && e.contains("SparQ with `(`"), "{e}");
        let e = NetworkFormat::detect(" \n").unwrap_err().to_string();
        assert!(e.contains("empty input"), "{e}");
    }
}
