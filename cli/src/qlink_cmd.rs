//! `qrm qlink ...`: Q-Link navigation studies (thesis chapter 4); `qrm qlink study` is
//! `qrm study run table-4-1` with the study's options as flags.

use crate::flags::StudyFlags;
use anyhow::Result;
use qlink::{Arrival, References};
use studies::qlink::table_4_1::{ArcRadius, Table41, Trials};

/// `qrm qlink ...`.
#[derive(Debug, clap::Subcommand)]
pub enum QlinkCmd {
    /// The §4.4.1 simulation study: failure rate vs sensor range and landmark size
    /// (Table 4.1), |P| histogram (Fig 4.6), trajectory length vs |P| (Fig 4.7) (`--quick`:
    /// 400 random pairs per setting and a lighter map; under a minute).
    Study(StudyArgs),
    /// The §4.4.2 field-site experiment in simulation: a lidar-only hybrid map (point
    /// triplets + the two walls), random start/goal trials, success rate, causes of failure,
    /// Table 4.2, and the thesis's proposed improvements measured (`--quick`: fewer trials,
    /// fewer samples and coarser checks).
    Field(crate::field_cmd::FieldArgs),
}

/// `--trial` of `qrm qlink study` (the study's `Trials`, named for the command line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TrialsArg {
    /// Both, as Table 4.1.
    All,
    /// R' below R, point landmarks.
    SensorRange,
    /// Landmarks as discs that hide each other.
    Occlusion,
}

/// `qrm qlink study`.
#[derive(Debug, clap::Args)]
pub struct StudyArgs {
    /// The trials to run.
    #[arg(long, value_enum, default_value_t = TrialsArg::All)]
    pub trial: TrialsArg,
    /// Ordered start/goal pairs per setting (default: all 39,800; quick: 400); the rows of
    /// further sensing schedules and of the robot's ablations run at most as many.
    #[arg(long)]
    pub pairs: Option<usize>,
    /// Idealised: plan with the true positions of references the robot does not see
    /// (default: where it last saw them, carried forward by its odometry).
    #[arg(long)]
    pub oracle_references: bool,
    /// Idealised: any two landmarks of the next element complete a transition (default:
    /// its reference landmarks, §4.4.1).
    #[arg(long)]
    pub any_two_arrive: bool,
    /// Arcs and search circles of the navigating robot's range R' (default: the mapping
    /// robot's R, as the thesis drives them).
    #[arg(long)]
    pub arcs_at_sensor_range: bool,
    /// Idealised: the navigating robot detects true positions and drives its waypoints
    /// exactly (default: it errs — N(0, 0.3 m) detections, MRCLAM's miss rate, wheel slip;
    /// change them with `qrm study run table-4-1 --set robot.detection.sigma=…`).
    #[arg(long)]
    pub exact_robot: bool,
    /// --quick, --seed, --out.
    #[command(flatten)]
    pub run: StudyFlags,
}

/// Runs a `qrm qlink` subcommand.
pub fn run(cmd: QlinkCmd) -> Result<()> {
    match cmd {
        QlinkCmd::Study(a) => study(a),
        QlinkCmd::Field(a) => crate::field_cmd::run(a),
    }
}

fn study(a: StudyArgs) -> Result<()> {
    // stage two: the flags become the `table-4-1` study's config, run by `qrm study`'s runner
    let mut config = a.run.config::<Table41>();
    config.trial = match a.trial {
        TrialsArg::All => Trials::All,
        TrialsArg::SensorRange => Trials::SensorRange,
        TrialsArg::Occlusion => Trials::Occlusion,
    };
    if a.pairs.is_some() {
        config.pairs = a.pairs;
        config.schedule_pairs = a.pairs.map(|p| p.min(config.schedule_pairs.unwrap_or(p)));
        config.ablation_pairs = a.pairs.map(|p| p.min(config.ablation_pairs.unwrap_or(p)));
    }
    if a.oracle_references {
        config.references = References::Oracle;
    }
    if a.any_two_arrive {
        config.arrival = Arrival::AnyTwo;
    }
    if a.arcs_at_sensor_range {
        config.radius = ArcRadius::SensorRange;
    }
    config.exact_robot |= a.exact_robot;
    crate::study_cmd::run_study::<Table41>(&config, &a.run.out)
}
