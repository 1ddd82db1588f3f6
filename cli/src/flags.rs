//! Flags shared by several commands: a recording's form and its range-bearing noise. Below
//! every command module (they import it; it imports none of them).

/// A recording's format (`--format`, `--from`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum InputFormat {
    /// `t,robot,landmark,x,y,cxx,cxy,cyy` rows.
    Csv,
    /// The UTIAS MRCLAM dataset's folder (range-bearing, surveyed landmarks).
    Mrclam,
    /// g2o landmark edges.
    G2o,
    /// A ROS 2 bag or a Foxglove/qrm MCAP log.
    Mcap,
}

impl InputFormat {
    /// The name on the command line and in summaries.
    pub fn as_str(self) -> &'static str {
        studies::recording::RecordingFormat::from(self).as_str()
    }
}

impl From<InputFormat> for studies::recording::RecordingFormat {
    fn from(f: InputFormat) -> Self {
        match f {
            InputFormat::Csv => Self::Csv,
            InputFormat::Mrclam => Self::Mrclam,
            InputFormat::G2o => Self::G2o,
            InputFormat::Mcap => Self::Mcap,
        }
    }
}

/// Where the range-bearing noise comes from (`--noise`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NoiseMode {
    /// Fitted from the recording (`qrm pqrm calibrate`).
    Auto,
    /// The given sigmas, else MRCLAM's defaults.
    Fixed,
}

/// The range-bearing noise of a recording (MRCLAM), shared by `map`, `pqrm real` and `convert`.
#[derive(Debug, Clone, clap::Args)]
pub struct NoiseArgs {
    /// Range noise (m); given, it wins over the fit (0.15 with `--noise fixed`).
    #[arg(long)]
    pub sigma_range: Option<f64>,
    /// Bearing noise (rad); given, it wins over the fit (0.01 with `--noise fixed`).
    #[arg(long)]
    pub sigma_bearing: Option<f64>,
    /// `auto` fits the noise from the recording itself (as `qrm pqrm calibrate`), `fixed` uses
    /// --sigma-range/--sigma-bearing. Default: auto for mrclam unless a sigma is given.
    #[arg(long = "noise", value_enum)]
    pub mode: Option<NoiseMode>,
}

impl NoiseArgs {
    /// The request `studies::recording::NoiseRequest` resolves.
    pub fn request(&self) -> studies::recording::NoiseRequest {
        studies::recording::NoiseRequest {
            mode: self.mode.map(|m| match m {
                NoiseMode::Auto => studies::recording::NoiseMode::Auto,
                NoiseMode::Fixed => studies::recording::NoiseMode::Fixed,
            }),
            sigma_range: self.sigma_range,
            sigma_bearing: self.sigma_bearing,
        }
    }
}

/// The flags every study alias shares (`qrm pqrm study`, `qrm qlink field`, …): what
/// `qrm study run NAME` takes as `--quick`, `--seed` and `--out`.
#[derive(Debug, Clone, clap::Args)]
pub struct StudyFlags {
    /// The quick config (a minute or less; the command's help says what it shrinks)
    /// instead of the thesis's.
    #[arg(long)]
    pub quick: bool,
    /// Seed (default: the study's, 0 but for `demo`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Output directory.
    #[arg(long)]
    pub out: std::path::PathBuf,
}

impl StudyFlags {
    /// Study `S`'s quick or full config with the seed: what the alias's own flags change.
    pub fn config<S: studies::Study>(&self) -> S::Config {
        let seed = self.seed.unwrap_or(S::DEFAULT_SEED);
        if self.quick {
            S::quick(seed)
        } else {
            S::full(seed)
        }
    }
}
