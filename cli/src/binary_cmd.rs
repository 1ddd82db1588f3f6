//! `qrm calculus ...` for binary calculi (OPRA-m, STAR-m): thin formatting over
//! `qsr_core::binary`.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use qsr_core::binary::{BinaryCalculus, CacheOutcome, render_binary_svg};

use crate::output::write_atomic;

/// What to do with a binary calculus (stage two of argument parsing).
pub enum BinaryJob {
    Show { json: bool },
    Classify,
    Neighbours { json: bool },
    Compose { format: TableFormat },
    Converse { format: TableFormat },
    Render { out: PathBuf, width: u32 },
}

/// How a table is printed.
#[derive(Clone, Copy)]
pub enum TableFormat {
    Text,
    Json,
    Gqr,
}

impl TableFormat {
    pub fn of(json: bool, gqr: bool) -> Self {
        match (json, gqr) {
            (true, _) => Self::Json,
            (false, true) => Self::Gqr,
            (false, false) => Self::Text,
        }
    }
}

/// Says on stderr, before a derivation of more than a few seconds starts, how long it is
/// expected to take (issue 39: `calculus compose opra-8` ran for 40 s without a word).
pub fn announce_derivation(c: &BinaryCalculus) {
    let cached = qsr_core::binary::default_cache_dir()
        .is_some_and(|d| qsr_core::binary::cache_path(c, &d).exists());
    if !cached {
        crate::progress::announce_cost(
            &format!("{}: deriving its composition table", c.name()),
            c.compose_cost(),
            &qsr_core::binary::DERIVATION_BUDGET,
            "cached afterwards",
        );
    }
}

/// Loads or derives the tables, saying on stderr where they came from and how long it took.
fn tables(c: &BinaryCalculus) -> Result<()> {
    announce_derivation(c);
    let start = Instant::now();
    let outcome = c.load_or_derive_cached()?;
    let secs = start.elapsed().as_secs_f64();
    match outcome {
        CacheOutcome::InMemory => {}
        CacheOutcome::Loaded(p) => eprintln!(
            "{}: tables read from {} in {secs:.2} s",
            c.name(),
            p.display()
        ),
        CacheOutcome::Written(p) => eprintln!(
            "{}: tables derived in {secs:.2} s, cached in {}",
            c.name(),
            p.display()
        ),
        CacheOutcome::Derived(why) => {
            eprintln!("{}: tables derived in {secs:.2} s ({why})", c.name())
        }
    }
    Ok(())
}

pub fn run(out: &mut impl Write, c: &BinaryCalculus, job: BinaryJob) -> Result<()> {
    match job {
        BinaryJob::Show { json } => show(out, c, json),
        BinaryJob::Classify => classify(out, c),
        BinaryJob::Neighbours { json } => neighbours(out, c, json),
        BinaryJob::Compose { format } => compose(out, c, format),
        BinaryJob::Converse { format } => converse(out, c, format),
        BinaryJob::Render { out: path, width } => {
            write_atomic(&path, render_binary_svg(c, width).as_bytes())?;
            writeln!(out, "wrote {}", path.display())?;
            Ok(())
        }
    }
}

fn show(out: &mut impl Write, c: &BinaryCalculus, json: bool) -> Result<()> {
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&c.describe_json())?)?;
    } else {
        write!(out, "{}", c.describe())?;
    }
    Ok(())
}

fn classify(out: &mut impl Write, c: &BinaryCalculus) -> Result<()> {
    crate::calculus_text::classify_stdin(out, |row| Ok(c.label(c.classify_row(row)?).to_owned()))
}

fn neighbours(out: &mut impl Write, c: &BinaryCalculus, json: bool) -> Result<()> {
    let g = c.neighbours()?;
    if json {
        writeln!(out, "{}", serde_json::to_string(&g.to_json(c.labels()))?)?;
    } else {
        write!(out, "{}", g.to_text(c.name(), c.labels()))?;
    }
    Ok(())
}

fn compose(out: &mut impl Write, c: &BinaryCalculus, format: TableFormat) -> Result<()> {
    tables(c)?;
    let t = c.compose_table()?;
    let text = match format {
        TableFormat::Json => format!("{}\n", serde_json::to_string(&t.to_json(c.labels()))?),
        TableFormat::Gqr => t.to_gqr(c.labels()),
        TableFormat::Text => t.to_text(c.name(), c.labels(), "{A:B} ∘ {B:C} → {A:C}"),
    };
    out.write_all(text.as_bytes())?;
    Ok(())
}

fn converse(out: &mut impl Write, c: &BinaryCalculus, format: TableFormat) -> Result<()> {
    let t = c.converse();
    let text = match format {
        TableFormat::Json => format!("{}\n", serde_json::to_string(&t.to_json(c.labels()))?),
        TableFormat::Gqr => t.to_gqr(c.labels()),
        TableFormat::Text => t.to_text(c.name(), c.labels()),
    };
    out.write_all(text.as_bytes())?;
    Ok(())
}
