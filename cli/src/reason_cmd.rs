//! `qrm reason ...`: thin front end over `qsr_core::reason` (closure, scenarios).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use pqrm::LandmarkSet;
use pqrm::reason::{Fusion, InferOptions, InferenceReport, Inferrer};
use qsr_core::Calculus;
use qsr_core::binary::{
    BinaryAlgebra, BinaryNetwork, SolveOptions, SolveOutcome, SplitSet, close_binary,
    from_gqr_csp_str, solve_binary,
};
use qsr_core::reason::{
    Algebra, Network, ScenarioOptions, ScenarioOutcome, TableScope, close, find_scenario,
};
use serde_json::json;

use crate::flags::StudyFlags;
use crate::output::write_atomic;

/// `qrm reason ...` (raw flags).
#[derive(Debug, clap::Subcommand)]
pub enum ReasonCmd {
    /// Algebraic closure of a constraint network read from stdin (or --input): prints
    /// `{"consistent": bool, "constraints": [["A","B","C",["label",...]], ...]}` over every
    /// ordered triplet of distinct points — the closed network, or the network when a
    /// constraint became empty (the explanation goes to stderr).
    Close(NetworkArgs),
    /// One algebraically closed scenario refining the network (SparQ's
    /// `scenario-consistency first`, GQR's `consistency`): `{"consistent": bool | null,
    /// "status": "consistent" | "inconsistent" | "unknown", "constraints": [...] | null}`.
    Scenario(ScenarioArgs),
    /// Which laws of a relation algebra a binary calculus's tables obey (converse an
    /// involution, identity neutral, converse of a composition, associativity).
    Laws(LawsArgs),
    /// A saved PQRM map as a constraint network (for `close`, `scenario` or SparQ): each
    /// observed ordering constrained to its most likely state, or to every state whose
    /// probability reaches --threshold; sets never observed are universal.
    Export(ExportArgs),
    /// Consistency check of a saved PQRM map: the most likely entries closure contradicts,
    /// and an irreducible set of them whose relaxation restores consistency (greedy by
    /// belief), with their probabilities.
    Check(CheckArgs),
    /// Distributions for landmark sets never observed together, from the map's other
    /// beliefs through the compose table (see `docs/reasoning.md` for the assumptions).
    Infer(InferArgs),
    /// The reasoning study: inference of hidden sets on a recording with surveyed truth,
    /// inference of never-seen triplets in simulation, and the check's precision; report,
    /// figures, JSON (`--quick`: two calculi, two hidings, two worlds).
    Study(ReasonStudyArgs),
}

/// `qrm reason check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// A saved map (`qrm map ... --out DIR` writes DIR/map.json).
    pub map: PathBuf,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `qrm reason laws`.
#[derive(Debug, clap::Args)]
pub struct LawsArgs {
    /// A binary calculus: opra-M, star-m, a GQR .spec, a SparQ .lisp, or a name in
    /// $GQR_DATA_DIR.
    #[arg(long)]
    pub calculus: String,
}

/// `qrm reason export`.
#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// A saved map.
    pub map: PathBuf,
    /// Keep every state with at least this probability (default: the most likely only).
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Output form.
    #[arg(long, value_enum, default_value_t = NetworkFormat::Json)]
    pub format: NetworkFormat,
}

/// `qrm reason infer`.
#[derive(Debug, clap::Args)]
pub struct InferArgs {
    /// A saved map.
    pub map: PathBuf,
    /// Where to write the inferences (JSON).
    #[arg(long)]
    pub out: PathBuf,
    /// Ordered sets to infer, `A,B,D` (repeatable; default: every unordered set of the map's
    /// landmarks never observed, in increasing-id order).
    #[arg(long = "set")]
    pub sets: Vec<LandmarkSet>,
    /// How path predictions are combined.
    #[arg(long, value_enum, default_value_t = FusionArg::Fitted)]
    pub fusion: FusionArg,
    /// Weight of uniform mixed into each path (0 ≤ ε < 1).
    #[arg(long, default_value_t = pqrm::reason::InferOptions::default().epsilon)]
    pub epsilon: f64,
    /// How a composition entry shares a path's probability among its states: `learned` (as
    /// often as the map's own observed quadruples show each) or `uniform`.
    #[arg(long, default_value = "learned")]
    pub composition: pqrm::reason::Composition,
    /// Rounds of chained inference (round r composes what rounds before it inferred).
    #[arg(long, default_value_t = pqrm::reason::InferOptions::default().rounds)]
    pub rounds: usize,
}

/// `qrm reason study`.
#[derive(Debug, clap::Args)]
pub struct ReasonStudyArgs {
    /// Recording format: mrclam brings its surveyed truth, the others need --truth.
    #[arg(long, value_enum, default_value_t = crate::flags::InputFormat::Mrclam)]
    pub format: crate::flags::InputFormat,
    /// The recording (default: ../shared/data/mrclam-dataset7).
    #[arg(long)]
    pub input: Option<PathBuf>,
    /// Surveyed truth for a recording without it (CSV `landmark,x,y`, as `qrm sim` writes truth.csv).
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Calculi (default: edc, double-cross, quadrant, left-right; quick: edc, double-cross).
    #[arg(long, value_delimiter = ',')]
    pub calculi: Option<Vec<String>>,
    /// Use only the first N frames with three or more landmarks.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// --quick, --seed, --out.
    #[command(flatten)]
    pub run: StudyFlags,
}

/// Fusion rules (see `pqrm::reason::Fusion`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FusionArg {
    /// Mean of the path predictions.
    Mixture,
    /// Geometric mean (log-linear pool, weights 1/k).
    Tempered,
    /// Product (independent evidence).
    Product,
    /// Log-linear pool with weights k^(−α), α fitted on the map itself.
    Fitted,
}

impl From<FusionArg> for Fusion {
    fn from(f: FusionArg) -> Self {
        match f {
            FusionArg::Mixture => Fusion::Mixture,
            FusionArg::Tempered => Fusion::Tempered,
            FusionArg::Product => Fusion::Product,
            FusionArg::Fitted => Fusion::Fitted,
        }
    }
}

/// Where a network comes from and how it is read.
#[derive(Debug, clap::Args)]
pub struct NetworkArgs {
    /// Calculus name or spec file (ternary point calculi), or a binary calculus: opra-M,
    /// star-m, a GQR .spec file, a SparQ .lisp file, or a name in $GQR_DATA_DIR (or ./data).
    #[arg(long)]
    pub calculus: String,
    /// The network file (default: stdin).
    #[arg(long)]
    pub input: Option<PathBuf>,
    /// Input form (default: by its first character, `{` JSON, `(` SparQ, a digit GQR's .csp).
    #[arg(long, value_enum)]
    pub format: Option<NetworkFormat>,
    /// Output form of a binary result: JSON (one line per network), or GQR's .csp.
    #[arg(long, value_enum, default_value_t = NetworkFormat::Json)]
    pub output: NetworkFormat,
    /// Use tables of configurations in general position (SparQ's planar relations) instead of
    /// the sound ones that include points on boundaries.
    #[arg(long)]
    pub general_position: bool,
}

/// `qrm reason scenario`.
#[derive(Debug, clap::Args)]
pub struct ScenarioArgs {
    #[command(flatten)]
    pub network: NetworkArgs,
    /// The most search nodes before giving up (ternary: an error; binary: status "unknown").
    #[arg(long, default_value_t = ScenarioOptions::default().max_nodes)]
    pub max_nodes: usize,
    /// Binary calculi: split constraints into the relations of this set rather than into
    /// base relations — a file, or a name GQR's `-c NAME` finds (`horn`:
    /// DATA/CALCULUS/calculus/hornalg beside the .spec, in $GQR_DATA_DIR or ./data). For a
    /// tractable subclass (RCC-8's or Allen's Horn relations) the answer is consistency; a
    /// solution then holds subclass relations, not base ones.
    #[arg(long, visible_alias = "cover", value_name = "NAME|FILE")]
    pub split: Option<String>,
    /// Binary calculi: one depth-first search, without GQR's geometric restarts (GQR's --2w).
    #[arg(long)]
    pub no_restarts: bool,
}

/// Network file forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NetworkFormat {
    /// `{"constraints": [["A", "B", "C", ["label", ...]], ...]}`.
    Json,
    /// SparQ's `((A B (r1 r2) C) ...)`.
    Sparq,
    /// GQR's .csp (binary networks): `N #name`, `i j ( r1 r2 )` lines, `.`.
    Gqr,
}

impl From<NetworkFormat> for qsr_core::reason::NetworkFormat {
    fn from(f: NetworkFormat) -> Self {
        match f {
            NetworkFormat::Json => Self::Json,
            NetworkFormat::Sparq => Self::Sparq,
            NetworkFormat::Gqr => Self::Gqr,
        }
    }
}

/// The network's text, where it came from, and its form (`--format`, else told by its first
/// character).
fn read_network(args: &NetworkArgs) -> Result<(String, String, qsr_core::reason::NetworkFormat)> {
    let max = qsr_core::text_file::MAX_INPUT_BYTES;
    let (origin, text) = match &args.input {
        Some(path) => (
            path.display().to_string(),
            qsr_core::text_file::read_text(path, max)
                .with_context(|| format!("reading {}", path.display()))?,
        ),
        None => (
            "stdin".to_owned(),
            qsr_core::text_file::read_stream(std::io::stdin(), max)
                .context("reading the network from stdin")?,
        ),
    };
    let format = match args.format {
        Some(f) => f.into(),
        None => qsr_core::reason::NetworkFormat::detect(&text).map_err(|e| {
            let hint = if text.trim().is_empty() {
                ""
            } else {
                "; say --format"
            };
            anyhow::anyhow!("{origin}: {e}{hint}")
        })?,
    };
    Ok((origin, text, format))
}

/// The binary calculus `--calculus` names, if it names one (a ternary built-in wins).
fn binary_algebra(name: &str) -> Result<Option<BinaryAlgebra>> {
    if qsr_core::binary::is_binary_name(name)
        && let Ok(c) = qsr_core::binary::BinaryCalculus::builtin(name)
    {
        crate::binary_cmd::announce_derivation(&c);
    }
    BinaryAlgebra::resolve(name).with_context(|| format!("loading calculus `{name}`"))
}

/// The binary networks of `--input` with their names (a .csp file may hold many).
fn binary_networks(
    args: &NetworkArgs,
    algebra: &BinaryAlgebra,
) -> Result<Vec<(String, BinaryNetwork)>> {
    if args.general_position {
        bail!(
            "--general-position is for ternary calculi; `{}` is binary",
            args.calculus
        );
    }
    let (origin, text, format) = read_network(args)?;
    let context = || format!("reading the network from {origin}");
    Ok(match format {
        qsr_core::reason::NetworkFormat::Gqr => from_gqr_csp_str(algebra, &text)
            .with_context(context)?
            .into_iter()
            .map(|g| (g.name, g.network))
            .collect(),
        f => vec![(
            String::new(),
            BinaryNetwork::parse(algebra, &text, f).with_context(context)?,
        )],
    })
}

/// One binary result in the `--output` form: a JSON line, or a .csp entry.
fn print_binary(
    args: &NetworkArgs,
    name: &str,
    status: &str,
    network: Option<&BinaryNetwork>,
) -> Result<()> {
    match args.output {
        NetworkFormat::Gqr => match network {
            Some(net) => outln!(
                "{}",
                net.to_gqr_csp(format!("{name} {status}").trim_start())
                    .trim_end()
            )?,
            None => outln!("# {name} {status}\n.")?,
        },
        NetworkFormat::Json | NetworkFormat::Sparq => {
            let consistent = match status {
                "consistent" => json!(true),
                "inconsistent" => json!(false),
                _ => serde_json::Value::Null,
            };
            let mut out = json!({
                "consistent": consistent,
                "status": status,
                "constraints": network.map(BinaryNetwork::constraints_json),
            });
            if !name.is_empty() {
                out["name"] = json!(name);
            }
            outln!("{out}")?;
        }
    }
    Ok(())
}

/// `qrm reason close` over a binary calculus: path consistency.
fn close_binary_networks(args: &NetworkArgs, algebra: &BinaryAlgebra) -> Result<()> {
    for (name, network) in binary_networks(args, algebra)? {
        let closed = close_binary(network)?;
        if let Some(why) = closed.describe() {
            eprintln!(
                "inconsistent{}: {why}",
                if name.is_empty() {
                    String::new()
                } else {
                    format!(" ({name})")
                }
            );
        }
        let status = if closed.is_consistent() {
            "consistent"
        } else {
            "inconsistent"
        };
        print_binary(args, &name, status, Some(&closed.network))?;
    }
    Ok(())
}

/// `qrm reason scenario` over a binary calculus: consistency by search.
fn solve_binary_networks(args: &ScenarioArgs, algebra: &BinaryAlgebra) -> Result<()> {
    let split = match &args.split {
        Some(name) => {
            let spec_dir = Path::new(&args.network.calculus)
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("spec"))
                .then(|| Path::new(&args.network.calculus).parent())
                .flatten();
            Some(
                SplitSet::resolve(algebra, name, spec_dir)
                    .with_context(|| format!("loading the split set `{name}`"))?,
            )
        }
        None => None,
    };
    let options = SolveOptions {
        max_nodes: args.max_nodes as u64,
        split,
        restarts: !args.no_restarts,
    };
    for (name, network) in binary_networks(&args.network, algebra)? {
        let solved = solve_binary(network, &options)?;
        let (status, scenario) = match &solved.outcome {
            SolveOutcome::Consistent(s) => ("consistent", Some(s)),
            SolveOutcome::Inconsistent => ("inconsistent", None),
            SolveOutcome::Unknown => {
                eprintln!(
                    "unknown{}: no answer within {} search nodes (raise --max-nodes to search longer)",
                    if name.is_empty() {
                        String::new()
                    } else {
                        format!(" ({name})")
                    },
                    args.max_nodes
                );
                ("unknown", None)
            }
        };
        print_binary(&args.network, &name, status, scenario)?;
    }
    Ok(())
}

/// `{"consistent": bool, "constraints": [...]}` on stdout (`null` without a network), written
/// one triplet at a time: the whole value of a 100-point network took 1.3 GB (issue 39).
fn print_network(consistent: bool, network: Option<&Network>) -> Result<()> {
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let written = (|| -> std::io::Result<()> {
        write!(out, "{{\"consistent\":{consistent},\"constraints\":")?;
        match network {
            Some(n) => n.write_constraints_json(&mut out)?,
            None => out.write_all(b"null")?,
        }
        out.write_all(b"}\n")?;
        out.flush()
    })();
    match written {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => Ok(other?),
    }
}

/// A ternary network and the algebra it is reasoned with (stage two of argument parsing).
fn load(args: &NetworkArgs) -> Result<(Network, Algebra)> {
    let calculus = Calculus::resolve(&args.calculus)
        .with_context(|| format!("loading calculus `{}`", args.calculus))?;
    let (origin, text, format) = read_network(args)?;
    let network = Network::parse(&calculus, &text, format)
        .with_context(|| format!("reading the network from {origin}"))?;
    let scope = if args.general_position {
        TableScope::GeneralPosition
    } else {
        // The sound tables from the disk cache (derived and written on the first run).
        calculus.load_or_derive_cached()?;
        TableScope::Sound
    };
    let algebra = Algebra::of(&calculus, scope)
        .with_context(|| format!("deriving the tables of `{}`", calculus.name()))?;
    Ok((network, algebra))
}

pub fn run(cmd: ReasonCmd) -> Result<()> {
    match cmd {
        ReasonCmd::Close(args) if let Some(alg) = binary_algebra(&args.calculus)? => {
            close_binary_networks(&args, &alg)
        }
        ReasonCmd::Scenario(args) if let Some(alg) = binary_algebra(&args.network.calculus)? => {
            solve_binary_networks(&args, &alg)
        }
        ReasonCmd::Laws(args) => {
            let Some(alg) = binary_algebra(&args.calculus)? else {
                bail!(
                    "`{}` is not a binary calculus (opra-M, star-m, a .spec or .lisp file)",
                    args.calculus
                );
            };
            let laws = alg.check()?;
            outln!(
                "{} ({} relations)\n{}",
                alg.name(),
                alg.n_states(),
                laws.to_text()
            )?;
            Ok(())
        }
        ReasonCmd::Close(args) => {
            let (network, algebra) = load(&args)?;
            crate::progress::announce_cost(
                &format!("closing {} points", network.n_points()),
                qsr_core::reason::closure_cost(network.n_points(), algebra.n_states()),
                &qsr_core::cost::Budget::RUN,
                "an upper bound: a network of singletons closes several times faster",
            );
            let closed = close(network, &algebra)?;
            if let Some(c) = &closed.contradiction {
                eprintln!("inconsistent: {}", c.describe(&closed.network));
            }
            print_network(closed.is_consistent(), Some(&closed.network))
        }
        ReasonCmd::Scenario(args) => {
            if args.split.is_some() || args.no_restarts {
                bail!(
                    "--split and --no-restarts are for binary calculi; `{}` is ternary",
                    args.network.calculus
                );
            }
            let (network, algebra) = load(&args.network)?;
            let options = ScenarioOptions {
                max_nodes: args.max_nodes,
            };
            match find_scenario(network, &algebra, &options)? {
                ScenarioOutcome::Found(s) => print_network(true, Some(&s)),
                ScenarioOutcome::None => print_network(false, None),
                ScenarioOutcome::GaveUp { nodes } => bail!(
                    "no answer within {nodes} search nodes (raise --max-nodes to search longer)"
                ),
            }
        }
        ReasonCmd::Export(args) => export(&args),
        ReasonCmd::Check(args) => check(&args),
        ReasonCmd::Infer(args) => infer(&args),
        ReasonCmd::Study(args) => study(&args),
    }
}

fn load_map(path: &std::path::Path) -> Result<pqrm::Pqrm> {
    // The loader's errors name the file.
    pqrm::Pqrm::load(path).context("loading the map")
}

fn export(args: &ExportArgs) -> Result<()> {
    let map = load_map(&args.map)?;
    let selection = match args.threshold {
        None => pqrm::reason::Selection::MostLikely,
        Some(t) if (0.0..=1.0).contains(&t) => pqrm::reason::Selection::AboveProbability(t),
        Some(t) => bail!("--threshold must be a probability in [0, 1], got {t}"),
    };
    let net = pqrm::reason::to_network(&map, selection)?;
    match args.format {
        NetworkFormat::Json => {
            let mut out = std::io::BufWriter::new(std::io::stdout().lock());
            let written = net
                .write_json(&mut out)
                .and_then(|()| out.write_all(b"\n"))
                .and_then(|()| out.flush());
            match written {
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
                other => other?,
            }
        }
        NetworkFormat::Sparq => outln!("{}", net.to_sparq())?,
        NetworkFormat::Gqr => bail!("a map's network is ternary: GQR's .csp holds binary ones"),
    }
    Ok(())
}

fn check(args: &CheckArgs) -> Result<()> {
    let map = load_map(&args.map)?;
    let result = pqrm::reason::check(&map)?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&result)?)?;
    } else {
        let text = result.to_text(map.calculus().name());
        outln!("{}", text.trim_end())?;
    }
    Ok(())
}

fn infer(args: &InferArgs) -> Result<()> {
    let map = load_map(&args.map)?;
    if let Some(note) = pqrm::reason::calibration_note(map.evidence()) {
        eprintln!("note: {note}");
    }
    let options = InferOptions {
        fusion: args.fusion.into(),
        epsilon: args.epsilon,
        rounds: args.rounds,
        composition: args.composition,
    };
    let mut inferrer = Inferrer::new(&map, options)?;
    let inferences = if args.sets.is_empty() {
        inferrer.infer_unseen()
    } else {
        inferrer.infer_sets(&args.sets)?
    };
    let report = InferenceReport::new(map.calculus(), &inferrer, &inferences);
    write_atomic(&args.out, serde_json::to_string_pretty(&report)?.as_bytes())?;
    outln!(
        "inferred {} sets of `{}` ({} more informative than uniform); wrote {}",
        report.inferences.len(),
        report.calculus,
        report.informative(),
        args.out.display()
    )?;
    if let Some(note) = report.uninformative_note() {
        eprintln!("{note}");
    } else if report.inferences.is_empty() && args.sets.is_empty() {
        eprintln!(
            "every set of the map's landmarks was observed: there is nothing unseen to infer"
        );
    }
    Ok(())
}

/// `qrm reason study`: an alias of `qrm study run reason` (the study's config from the flags).
fn study(a: &ReasonStudyArgs) -> Result<()> {
    use studies::pqrm::reasoning::ReasonStudy;
    let mut config = a.run.config::<ReasonStudy>();
    if let Some(input) = &a.input {
        config.input.clone_from(input);
    }
    config.format = a.format.into();
    config.truth.clone_from(&a.truth);
    config.max_frames = a.max_frames;
    if let Some(c) = &a.calculi {
        config.study.calculi.clone_from(c);
    }
    crate::study_cmd::run_study::<ReasonStudy>(&config, &a.run.out)
}
