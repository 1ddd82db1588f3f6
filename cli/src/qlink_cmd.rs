//! `qrm qlink ...`: Q-Link navigation studies (thesis chapter 4).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use qlink::study::{SettingInfo, StudyConfig, TableRow, TrialRecord, run_study, table};

use crate::output::{CsvTable, Staging, write_atomic};
use crate::plot::{Series, histogram, line_chart};

/// `qrm qlink ...`.
#[derive(Debug, clap::Subcommand)]
pub enum QlinkCmd {
    /// The §4.4.1 simulation study: failure rate vs sensor range and landmark size
    /// (Table 4.1), |P| histogram (Fig 4.6), trajectory length vs |P| (Fig 4.7).
    Study(StudyArgs),
    /// The §4.4.2 field-site experiment in simulation: a lidar-only hybrid map (point
    /// triplets + the two walls), random start/goal trials, success rate, causes of failure,
    /// Table 4.2, and the thesis's proposed improvements measured.
    Field(FieldArgs),
}

/// `qrm qlink field`.
#[derive(Debug, clap::Args)]
pub struct FieldArgs {
    /// Trials per variant (default 200; quick: 12).
    #[arg(long)]
    pub trials: Option<usize>,
    /// Worlds (scenario seeds seed, seed + 1, …), each mapped and navigated on its own
    /// (default 5; quick: 1). Rates are reported per world and pooled.
    #[arg(long)]
    pub worlds: Option<usize>,
    /// Fewer trials, fewer samples and coarser checks: for tests.
    #[arg(long)]
    pub quick: bool,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// `qrm qlink study`.
#[derive(Debug, clap::Args)]
pub struct StudyArgs {
    /// sensor-range, occlusion or all.
    #[arg(long, default_value = "all")]
    pub trial: String,
    /// 400 random pairs per setting and a lighter map: under a minute.
    #[arg(long)]
    pub quick: bool,
    /// Ordered start/goal pairs per setting (default: all 39,800; quick: 400).
    #[arg(long)]
    pub pairs: Option<usize>,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs a `qrm qlink` subcommand.
pub fn run(cmd: QlinkCmd) -> Result<()> {
    match cmd {
        QlinkCmd::Study(a) => study(a),
        QlinkCmd::Field(a) => crate::field_cmd::run(a),
    }
}

/// Table 4.1 of the thesis: (trial, value, failure rate).
const THESIS_TABLE: [(&str, f64, f64); 9] = [
    ("sensor-range", 1.0, 0.0),
    ("sensor-range", 0.9, 0.020),
    ("sensor-range", 0.8, 0.319),
    ("sensor-range", 0.7, 0.555),
    ("sensor-range", 0.6, 0.747),
    ("occlusion", 0.1, 0.020),
    ("occlusion", 0.3, 0.028),
    ("occlusion", 0.5, 0.120),
    ("occlusion", 0.7, 0.163),
];

fn study(a: StudyArgs) -> Result<()> {
    let mut config = if a.quick {
        StudyConfig::quick(a.seed)
    } else {
        StudyConfig::full(a.seed)
    };
    config.trial = a.trial.clone();
    if a.pairs.is_some() {
        config.pairs = a.pairs;
    }
    config.settings()?; // rejects an unknown trial before any work
    // Written into a staging directory, moved into place only when all is done: a
    // failure or Ctrl-C leaves nothing a user could take for a result.
    let stage = Staging::new(&a.out)?;
    let out_dir = stage.path().to_path_buf();
    let t0 = Instant::now();
    let pb = crate::progress::bar(0, "Q-Link navigations");
    let (records, infos) = run_study(&config, &|n| pb.inc_length(n as u64), &|| pb.inc(1))?;
    pb.finish_and_clear();
    for i in &infos {
        outln!("map: {}", describe(i))?;
    }
    let secs = t0.elapsed().as_secs_f64();
    let rows = table(&records);
    write_outputs(&out_dir, &records, &rows, &config, &infos, secs)?;
    outln!(
        "{:<13} {:>6} {:>7} {:>8} {:>9} {:>9} {:>8}",
        "trial",
        "value",
        "pairs",
        "no_path",
        "failures",
        "rate",
        "thesis"
    )?;
    for r in &rows {
        let thesis = thesis_rate(r);
        outln!(
            "{:<13} {:>6} {:>7} {:>8} {:>9} {:>8.1}% {:>8}",
            r.trial,
            r.value,
            r.pairs,
            r.no_path,
            r.failures,
            100.0 * r.failure_rate,
            thesis
        )?;
    }
    outln!("study in {secs:.1} s; wrote {}", a.out.display())?;
    stage.commit()?;
    Ok(())
}

fn write_outputs(
    out: &Path,
    records: &[TrialRecord],
    rows: &[TableRow],
    config: &StudyConfig,
    infos: &[SettingInfo],
    secs: f64,
) -> Result<()> {
    let t_map: f64 = infos.iter().map(|i| i.build_seconds).sum();
    let mut csv = CsvTable::new([
        "trial",
        "value",
        "pairs",
        "no_path",
        "failures",
        "failure_rate",
    ])?;
    for r in rows {
        csv.row([
            (r.trial).to_string(),
            (r.value).to_string(),
            (r.pairs).to_string(),
            (r.no_path).to_string(),
            (r.failures).to_string(),
            (r.failure_rate).to_string(),
        ])?;
    }
    csv.write(&out.join("table.csv"))?;
    let mut csv = CsvTable::new([
        "trial",
        "value",
        "start",
        "goal",
        "plan_len",
        "success",
        "failure",
        "length",
        "transit_length",
        "bound",
        "bound_prop4",
    ])?;
    for r in records {
        let failure = r.failure.map_or(String::new(), |f| {
            serde_json::to_value(f)
                .ok()
                .and_then(|v| v.as_str().map(str::to_owned))
                .unwrap_or_default()
        });
        csv.row([
            (r.trial).to_string(),
            (r.value).to_string(),
            (r.start).to_string(),
            (r.goal).to_string(),
            (r.plan_len).to_string(),
            (r.success).to_string(),
            (failure).to_string(),
            format!("{:.3}", r.length),
            format!("{:.3}", r.transit_length),
            format!("{:.3}", r.bound),
            format!("{:.3}", r.bound_direct),
        ])?;
    }
    csv.write(&out.join("records.csv"))?;
    // Fig 4.6: |P| histogram of the baseline (R' = R, no occlusion)
    let base: Vec<f64> = records
        .iter()
        .filter(|r| {
            r.trial == "sensor-range"
                && (r.value - 1.0).abs() < 1e-9
                && r.failure != Some(qlink::Failure::NoPath)
        })
        .map(|r| r.plan_len as f64)
        .collect();
    let base = if base.is_empty() {
        records
            .iter()
            .filter(|r| r.failure != Some(qlink::Failure::NoPath))
            .map(|r| r.plan_len as f64)
            .collect()
    } else {
        base
    };
    let maxp = base.iter().copied().fold(1.0, f64::max);
    let edges: Vec<f64> = (0..=(maxp as usize + 1)).map(|k| k as f64 - 0.5).collect();
    histogram(
        &out.join("fig4_6_plan_length_histogram"),
        "Fig 4.6: Link Graph path length |P| (R' = R, no occlusion)",
        "|P|",
        &edges,
        &[("pairs with a path".to_owned(), base)],
    )?;
    // Fig 4.7: mean trajectory length vs |P| per setting, with Proposition 2's bound
    let mut series = Vec::new();
    let mut settings: Vec<(String, u64)> = Vec::new();
    for r in records {
        let k = (r.trial.clone(), r.value.to_bits());
        if !settings.contains(&k) {
            settings.push(k);
        }
    }
    let mut top = 1usize;
    for (trial, bits) in &settings {
        let v = f64::from_bits(*bits);
        let ok: Vec<&TrialRecord> = records
            .iter()
            .filter(|r| {
                &r.trial == trial && r.value.to_bits() == *bits && r.success && r.plan_len > 0
            })
            .collect();
        let maxp = ok.iter().map(|r| r.plan_len).max().unwrap_or(0);
        top = top.max(maxp);
        let pts: Vec<(f64, f64)> = (1..=maxp)
            .filter_map(|p| {
                let l: Vec<f64> = ok
                    .iter()
                    .filter(|r| r.plan_len == p)
                    .map(|r| r.length)
                    .collect();
                (!l.is_empty()).then(|| (p as f64, l.iter().sum::<f64>() / l.len() as f64))
            })
            .collect();
        let name = if trial == "sensor-range" {
            format!("R' = {v} R")
        } else {
            format!("size {v} m")
        };
        series.push(Series::line(name, pts));
    }
    let bound = (2.0 * std::f64::consts::PI + 1.0) * qlink::study::MAP_RANGE;
    series.push(Series::reference(
        "Prop. 2 bound (2π+1)R|P|",
        (1..=top).map(|p| (p as f64, bound * p as f64)).collect(),
    ));
    line_chart(
        &out.join("fig4_7_length_vs_plan_length"),
        "Fig 4.7: mean trajectory length vs |P|",
        "Link Graph path length |P|",
        "trajectory length (m)",
        &series,
    )?;
    // report
    let mut s = String::new();
    let _ = writeln!(s, "# Q-Link simulation study (thesis §4.4.1)\n");
    let _ = writeln!(
        s,
        "Set-up (DESIGN §7): `qlink-200` world (seed {}), mapped with R = 20 m and N(0, 0.3) noise into a PQRM (`quadrant`, {} samples per landmark per frame, floor 1); β = 1, unit costs; horizon-4 search POMDP (moves to adjacent states, p_detect 0.9); arc controller of radius R'; full-circle fallback; no re-planning (a failed transition fails the pair, as in the thesis). {} ordered pairs per setting. Maps and distance fields built in {t_map:.1} s; total {secs:.1} s.\n",
        config.seed,
        config.samples,
        records
            .iter()
            .filter(|r| r.trial == rows[0].trial && r.value == rows[0].value)
            .count()
    );
    let _ = writeln!(s, "Maps:\n");
    for i in infos {
        let _ = writeln!(s, "- {}", describe(i));
    }
    let _ = writeln!(
        s,
        "\n## Table 4.1\n\n| trial | value | pairs | no path | failures | failure rate | thesis | successes over the Prop. 2 bound | time (s) |\n|---|---|---|---|---|---|---|---|---|"
    );
    for r in rows {
        let thesis = thesis_rate(r);
        let time = infos
            .iter()
            .find(|i| i.trial == r.trial && (i.value - r.value).abs() < 1e-9)
            .map_or(0.0, |i| i.navigate_seconds);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {:.2} % | {thesis} | {} | {time:.2} |",
            r.trial,
            r.value,
            r.pairs,
            r.no_path,
            r.failures,
            100.0 * r.failure_rate,
            r.over_bound
        );
    }
    let baseline = rows
        .iter()
        .find(|r| r.trial == "sensor-range" && (r.value - 1.0).abs() < 1e-9);
    let _ = writeln!(s, "\n## Checks\n");
    if let Some(b) = baseline {
        let _ = writeln!(
            s,
            "- Proposition 1 (R' = R, no occlusion): {} failures of {} pairs with a path — {}.",
            b.failures,
            b.pairs - b.no_path,
            if b.failures == 0 {
                "holds"
            } else {
                "**violated**"
            }
        );
    }
    let over: usize = rows.iter().map(|r| r.over_bound).sum();
    let _ = writeln!(
        s,
        "- Proposition 2 bound (2π+1)R|P| on the transitions of successful runs: exceeded {over} times over all settings (the thesis finds it very conservative; the bound is proved only under Assumptions 1–2, which R' < R and occlusion break)."
    );
    let _ = writeln!(
        s,
        "- Trends the thesis reports: failure rate grows as R' shrinks and as landmarks grow. Ours: sensor range {}; size {}.",
        trend(rows, "sensor-range", true),
        trend(rows, "occlusion", false)
    );
    s.push_str(DIFFERENCES);
    let _ = writeln!(
        s,
        "\nFigures: `fig4_6_plan_length_histogram.svg`, `fig4_7_length_vs_plan_length.svg`; data: `table.csv`, `records.csv`."
    );
    write_atomic(&out.join("report.md"), s.as_bytes())?;
    Ok(())
}

/// The thesis's failure rate for a row, formatted, or "-".
fn thesis_rate(r: &TableRow) -> String {
    THESIS_TABLE
        .iter()
        .find(|t| t.0 == r.trial && (t.1 - r.value).abs() < 1e-9)
        .map_or("-".to_owned(), |t| format!("{:.1} %", 100.0 * t.2))
}

fn describe(i: &SettingInfo) -> String {
    format!(
        "{} {}: {} frames, {} elements, {} directed edges, built in {:.1} s",
        i.trial, i.value, i.frames, i.elements, i.edges, i.build_seconds
    )
}

fn trend(rows: &[TableRow], trial: &str, decreasing_value: bool) -> String {
    let mut sel: Vec<&TableRow> = rows.iter().filter(|r| r.trial == trial).collect();
    if sel.len() < 2 {
        return "not run".into();
    }
    sel.sort_by(|a, b| a.value.total_cmp(&b.value));
    if decreasing_value {
        sel.reverse();
    }
    let rates: Vec<String> = sel
        .iter()
        .map(|r| format!("{:.1} %", 100.0 * r.failure_rate))
        .collect();
    let monotone = sel
        .windows(2)
        .all(|w| w[1].failure_rate >= w[0].failure_rate);
    format!(
        "{} ({})",
        rates.join(" → "),
        if monotone {
            "grows, as in the thesis"
        } else {
            "not monotone"
        }
    )
}

/// Why our Table 4.1 differs from the thesis's (appended to the report).
const DIFFERENCES: &str = "
## Where we differ, and why

- *|P|*: we count transitions; the thesis counts map elements (its |P| = 1 is \"goal visible \
from the start\", our |P| = 0), so its Fig 4.6/4.7 axes are ours + 1. The Prop. 2 bound here \
uses transitions, the tighter reading.
- *Sensor range*: the same trend, somewhat higher rates below R' = 0.9 R. A failure is a \
transition whose link, or a second landmark of the next element, never comes within R' while \
the robot searches at radius R' about the references and the link; how often that happens \
depends on the landmark spacing of the random world and on the mapping path (ours: lawn-mower \
lanes 18 m apart), which the thesis does not give.
- *Occlusion*: we find no failures at any size. Our robot checks what it sees every metre \
along its search arcs and full circles, so one unoccluded sight line anywhere on a circle \
suffices; with 200 discs of at most 0.7 m in 200 m × 200 m some sight line is always clear. \
The thesis's 2–16 % suggest its search looked from far fewer places (its 0.1 m rate equals its \
0.9 R rate, more than 0.1 m discs can occlude); we report what our controller does rather than \
handicap it to match.
";
