//! A CSV table, each field quoted as it needs.

use std::path::Path;

use crate::{FileError, Result, write_atomic};

/// A CSV table written through the `csv` crate, which quotes a field holding a comma, a quote
/// or a line break: a calculus or state label from a spec file may hold any of them, and
/// joined by hand with `,` such a label shifted every column after it (issue 19). Every row
/// must have the header's number of fields.
#[derive(Debug)]
pub struct CsvTable(csv::Writer<Vec<u8>>);

impl CsvTable {
    /// A table with this header.
    ///
    /// # Errors
    /// Never for an in-memory table; kept for the csv crate's signature.
    pub fn new<I, S>(header: I) -> Result<Self>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(header)?;
        Ok(Self(w))
    }

    /// Appends a row.
    ///
    /// # Errors
    /// [`FileError::Csv`] for a row whose length differs from the header's.
    pub fn row<I, S>(&mut self, fields: I) -> Result<()>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        Ok(self.0.write_record(fields)?)
    }

    /// The table's text.
    ///
    /// # Errors
    /// As the csv crate's flush (not for memory).
    pub fn into_bytes(self) -> Result<Vec<u8>> {
        self.0
            .into_inner()
            .map_err(|e| FileError::Csv(csv::Error::from(e.into_error())))
    }

    /// Writes the table to `path` atomically ([`write_atomic`]).
    ///
    /// # Errors
    /// As [`write_atomic`].
    pub fn write(self, path: &Path) -> Result<()> {
        write_atomic(path, &self.into_bytes()?)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    #[test]
    fn a_row_of_the_wrong_length_is_refused() {
        let mut t = CsvTable::new(["a", "b"]).unwrap();
        t.row(["1", "2"]).unwrap();
        assert!(matches!(t.row(["1"]), Err(FileError::Csv(_))));
    }
}
