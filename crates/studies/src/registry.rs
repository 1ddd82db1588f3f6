//! The registry: every study by name, for the front ends (`qrm study`, `qrm.studies`,
//! `qrm.distributed`). It names the studies; the studies know only [`crate::study`].

use crate::error::{Result, StudyError};
use crate::study::{AnyStudy, Registered};

/// Every study, in the thesis's order.
pub static STUDIES: &[&dyn AnyStudy] = &[
    &Registered::<crate::pqrm::monte_carlo::MonteCarlo>::new(),
    &Registered::<crate::pqrm::real_data::RealData>::new(),
    &Registered::<crate::pqrm::reasoning::ReasonStudy>::new(),
    &Registered::<crate::serge::SergeStudy>::new(),
    &Registered::<crate::qlink::table_4_1::Table41>::new(),
    &Registered::<crate::qlink::field::FieldExperiment>::new(),
    &Registered::<crate::demo::Demo>::new(),
];

/// The study named `name`.
///
/// # Errors
/// [`StudyError::InvalidParameter`] listing the names there are.
pub fn find(name: &str) -> Result<&'static dyn AnyStudy> {
    STUDIES
        .iter()
        .copied()
        .find(|s| s.name() == name)
        .ok_or_else(|| {
            let names: Vec<&str> = STUDIES.iter().map(|s| s.name()).collect();
            StudyError::InvalidParameter(format!(
                "unknown study `{name}` (studies: {})",
                names.join(", ")
            ))
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_study_is_found_by_name_and_its_configs_are_valid() {
        assert!(!STUDIES.is_empty());
        for s in STUDIES {
            let found = find(s.name()).map(|f| f.name());
            assert_eq!(found.ok(), Some(s.name()));
            for full in [false, true] {
                let c = s.config(full, 3);
                assert!(c.is_object(), "{}: {c}", s.name());
                s.check(&c).unwrap_or_else(|e| panic!("{}: {e}", s.name()));
            }
        }
        let e = find("table-9-9")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("unknown study `table-9-9`") && e.contains("table-4-1"),
            "{e}"
        );
    }

    #[test]
    fn a_misspelt_field_is_refused_with_its_name() {
        let s = find("table-4-1").ok().map(|s| s.config(false, 0));
        let mut c = s.unwrap_or_default();
        if let Some(o) = c.as_object_mut() {
            o.insert("pairs".into(), serde_json::json!("many"));
        }
        let e = find("table-4-1")
            .and_then(|s| s.check(&c))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("config of `table-4-1`") && e.contains("many"),
            "{e}"
        );
    }
}
