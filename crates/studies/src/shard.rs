//! Shards: a study's work split into independent parts that can run on other machines and
//! be merged, in any order, into the result of a local run.

use crate::error::{Result, StudyError};

/// Checks that `indices` are `0..n`, each exactly once.
///
/// # Errors
/// [`StudyError::InvalidParameter`] naming the missing, duplicated and out-of-range shards:
/// a sweep that lost a shard must fail, not average what came back.
pub fn check_indices(n: usize, indices: impl IntoIterator<Item = usize>) -> Result<()> {
    let mut seen = vec![0usize; n];
    let mut foreign = Vec::new();
    for i in indices {
        match seen.get_mut(i) {
            Some(c) => *c += 1,
            None => foreign.push(i),
        }
    }
    let missing: Vec<usize> = (0..n).filter(|&i| seen[i] == 0).collect();
    let twice: Vec<usize> = (0..n).filter(|&i| seen[i] > 1).collect();
    if missing.is_empty() && twice.is_empty() && foreign.is_empty() {
        return Ok(());
    }
    let mut why = Vec::new();
    if !missing.is_empty() {
        why.push(format!("missing {missing:?}"));
    }
    if !twice.is_empty() {
        why.push(format!("more than once {twice:?}"));
    }
    if !foreign.is_empty() {
        why.push(format!("beyond the {n} shards {foreign:?}"));
    }
    Err(StudyError::InvalidParameter(format!(
        "shards of a study of {n}: {}",
        why.join("; ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shard_once_in_any_order() {
        assert!(check_indices(3, [2, 0, 1]).is_ok());
        assert!(check_indices(0, []).is_ok());
        let e = check_indices(4, [3, 0, 0, 7]).err().map(|e| e.to_string());
        let e = e.unwrap_or_default();
        assert!(e.contains("missing [1, 2]"), "{e}");
        assert!(e.contains("more than once [0]"), "{e}");
        assert!(e.contains("beyond the 4 shards [7]"), "{e}");
    }
}
