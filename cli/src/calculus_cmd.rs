//! `qrm calculus ...`: thin formatting over `qsr_core`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use qsr_core::binary::{BINARY_NAMES, BinaryCalculus, is_binary_name};
use qsr_core::{BUILTIN_NAMES, Calculus, Permutation, RenderOptions};

use crate::args::{CalculusCmd, ComposeMethod};
use crate::binary_cmd::{BinaryJob, TableFormat};
use crate::calculus_text::classify_stdin;
use crate::output::write_atomic;

/// Validated form of a `calculus` subcommand (stage two of argument parsing).
enum Job {
    List,
    Binary {
        calculus: BinaryCalculus,
        job: BinaryJob,
    },
    Show {
        calculus: Calculus,
        json: bool,
    },
    Spec {
        calculus: Calculus,
        json: bool,
    },
    Classify {
        calculus: Calculus,
    },
    Neighbours {
        calculus: Calculus,
        json: bool,
    },
    Compose {
        calculus: Calculus,
        json: bool,
        cells: bool,
    },
    Permute {
        calculus: Calculus,
        op: Permutation,
        json: bool,
    },
    Render {
        calculus: Calculus,
        out: PathBuf,
        width: u32,
    },
}

fn load(name: &str) -> Result<Calculus> {
    Calculus::resolve(name).with_context(|| format!("loading calculus `{name}`"))
}

fn load_binary(name: &str) -> Result<BinaryCalculus> {
    BinaryCalculus::builtin(name).with_context(|| format!("loading calculus `{name}`"))
}

/// Binary calculi: everything of `opra-M`; composition, converse and neighbours of `star-m`
/// (its classification, spec and picture are those of the oriented spec calculus).
fn validate_binary(cmd: &CalculusCmd) -> Result<Option<Job>> {
    let name = match cmd {
        CalculusCmd::List => None,
        CalculusCmd::Show { name, .. }
        | CalculusCmd::Spec { name, .. }
        | CalculusCmd::Classify { name }
        | CalculusCmd::Neighbours { name, .. }
        | CalculusCmd::Compose { name, .. }
        | CalculusCmd::Permute { name, .. }
        | CalculusCmd::Render { name, .. } => Some(name),
    };
    if let Some(e) = name.and_then(|n| qsr_core::binary::name_out_of_range(n)) {
        return Err(e).context("loading the calculus");
    }
    let opra = |n: &str| n.starts_with("opra-");
    let job = match cmd {
        CalculusCmd::Show { name, json } if opra(name) => (name, BinaryJob::Show { json: *json }),
        CalculusCmd::Classify { name } if opra(name) => (name, BinaryJob::Classify),
        CalculusCmd::Spec { name, .. } if opra(name) => bail!(
            "`{name}` is a binary calculus derived by angle arithmetic, not a spec file; \
             `qrm calculus show {name}` lists its relations"
        ),
        CalculusCmd::Render { name, out, width } if opra(name) => (
            name,
            BinaryJob::Render {
                out: out.clone(),
                width: *width,
            },
        ),
        CalculusCmd::Neighbours { name, json } if is_binary_name(name) => {
            (name, BinaryJob::Neighbours { json: *json })
        }
        CalculusCmd::Compose {
            name,
            json,
            gqr,
            method,
        } if is_binary_name(name) => {
            if *method == ComposeMethod::Cells {
                bail!(
                    "--method cells is for learned ternary calculi; `{name}`'s composition is \
                     derived exactly"
                );
            }
            (
                name,
                BinaryJob::Compose {
                    format: TableFormat::of(*json, *gqr),
                },
            )
        }
        CalculusCmd::Permute {
            name,
            op,
            json,
            gqr,
        } if is_binary_name(name) => {
            if let Some(p) = op.permutation() {
                bail!("`{name}` is binary: its one permutation is `--op converse`, not `{p}`");
            }
            (
                name,
                BinaryJob::Converse {
                    format: TableFormat::of(*json, *gqr),
                },
            )
        }
        CalculusCmd::Permute { name, op, .. } if op.permutation().is_none() => bail!(
            "`converse` is the permutation of binary calculi (opra-M, star-m); `{name}` is \
             ternary: inverse, shortcut, shortcut-inverse, homing or homing-inverse"
        ),
        CalculusCmd::Compose {
            gqr: true, name, ..
        }
        | CalculusCmd::Permute {
            gqr: true, name, ..
        } => {
            bail!("--gqr prints binary calculi in GQR's format; `{name}` is ternary")
        }
        _ => return Ok(None),
    };
    Ok(Some(Job::Binary {
        calculus: load_binary(job.0)?,
        job: job.1,
    }))
}

fn validate(cmd: CalculusCmd) -> Result<Job> {
    if let Some(job) = validate_binary(&cmd)? {
        return Ok(job);
    }
    Ok(match cmd {
        CalculusCmd::List => Job::List,
        CalculusCmd::Show { name, json } => Job::Show {
            calculus: load(&name)?,
            json,
        },
        CalculusCmd::Spec { name, json } => Job::Spec {
            calculus: load(&name)?,
            json,
        },
        CalculusCmd::Classify { name } => Job::Classify {
            calculus: load(&name)?,
        },
        CalculusCmd::Neighbours { name, json } => Job::Neighbours {
            calculus: load(&name)?,
            json,
        },
        CalculusCmd::Compose {
            name, json, method, ..
        } => Job::Compose {
            calculus: load(&name)?,
            json,
            cells: method == ComposeMethod::Cells,
        },
        CalculusCmd::Permute { name, op, json, .. } => Job::Permute {
            calculus: load(&name)?,
            // the converse was refused above for a ternary calculus
            op: op
                .permutation()
                .context("the converse of a ternary calculus")?,
            json,
        },
        CalculusCmd::Render { name, out, width } => {
            if out
                .extension()
                .is_none_or(|e| !e.eq_ignore_ascii_case("svg"))
            {
                bail!("--out must name an .svg file, got {}", out.display());
            }
            if !(64..=8192).contains(&width) {
                bail!("--width must be between 64 and 8192 pixels, got {width}");
            }
            Job::Render {
                calculus: load(&name)?,
                out,
                width,
            }
        }
    })
}

/// Runs one `calculus` subcommand.
pub fn run(cmd: CalculusCmd) -> Result<()> {
    let job = validate(cmd)?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    match job {
        Job::List => {
            for n in BUILTIN_NAMES.iter().chain(&BINARY_NAMES) {
                writeln!(out, "{n}")?;
            }
        }
        Job::Binary { calculus, job } => crate::binary_cmd::run(&mut out, &calculus, job)?,
        Job::Show { calculus, json } => show(&mut out, &calculus, json)?,
        Job::Spec { calculus, json } => {
            let text = if json {
                calculus.spec().to_json_string()?
            } else {
                calculus.spec().to_toml_string()?
            };
            writeln!(out, "{}", text.trim_end())?;
        }
        Job::Classify { calculus } => classify(&mut out, &calculus)?,
        Job::Neighbours { calculus, json } => neighbours(&mut out, &calculus, json)?,
        Job::Compose {
            calculus,
            json,
            cells,
        } => compose(&mut out, &calculus, json, cells)?,
        Job::Permute { calculus, op, json } => permute(&mut out, &calculus, op, json)?,
        Job::Render {
            calculus,
            out: path,
            width,
        } => {
            let svg = qsr_core::render_svg(
                &calculus,
                &RenderOptions {
                    width,
                    ..RenderOptions::default()
                },
            )?;
            write_atomic(&path, svg.as_bytes())?;
            writeln!(out, "wrote {}", path.display())?;
        }
    }
    Ok(())
}

fn show(out: &mut impl Write, c: &Calculus, json: bool) -> Result<()> {
    if json {
        writeln!(out, "{}", serde_json::to_string_pretty(&c.describe_json())?)?;
    } else {
        write!(out, "{}", c.describe())?;
    }
    Ok(())
}

fn classify(out: &mut impl Write, c: &Calculus) -> Result<()> {
    classify_stdin(out, |row| Ok(c.label(c.classify_row(row)?).to_owned()))
}

fn neighbours(out: &mut impl Write, c: &Calculus, json: bool) -> Result<()> {
    let g = c.neighbours();
    if json {
        writeln!(out, "{}", serde_json::to_string(&g.to_json(c.labels()))?)?;
    } else {
        write!(out, "{}", g.to_text(c.name(), c.labels()))?;
    }
    Ok(())
}

fn compose(out: &mut impl Write, c: &Calculus, json: bool, cells: bool) -> Result<()> {
    // `cells`: Algorithm 3 over the raster of a learned calculus (sound by construction)
    let owned;
    let t = if cells {
        owned = serge::learn::compose_table(c, &|| {})?;
        &owned
    } else {
        c.compose_table()?
    };
    if json {
        writeln!(out, "{}", serde_json::to_string(&t.to_json(c.labels()))?)?;
    } else {
        let notation = "{AB:C} ∘ {BC:D} → {AB:D}";
        write!(out, "{}", t.to_text(c.name(), c.labels(), notation))?;
    }
    Ok(())
}

fn permute(out: &mut impl Write, c: &Calculus, op: Permutation, json: bool) -> Result<()> {
    let t = c.permutation(op)?;
    if json {
        writeln!(out, "{}", serde_json::to_string(&t.to_json(c.labels()))?)?;
    } else {
        write!(out, "{}", t.to_text(c.name(), c.labels()))?;
    }
    Ok(())
}
