//! Raw command-line flags (stage one of argument parsing).

use std::path::PathBuf;

use clap::{Parser, Subcommand};

/// qrm: qualitative relational maps for robots — calculi, probabilistic mapping, learned
/// partitions and qualitative navigation.
#[derive(Debug, Parser)]
#[command(name = "qrm", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// Top-level subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Inspect, use and draw qualitative calculi.
    #[command(subcommand)]
    Calculus(CalculusCmd),
}

/// `qrm calculus ...`. NAME is a built-in calculus (see `list`) or a path to a TOML/JSON spec.
#[derive(Debug, Subcommand)]
pub enum CalculusCmd {
    /// Print the built-in calculus names, one per line.
    List,
    /// Show a calculus: frame, states (ids, labels) and constraints.
    Show {
        /// Built-in name or spec file.
        name: String,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Print the spec of a calculus (a starting point for your own).
    Spec {
        /// Built-in name or spec file.
        name: String,
        /// Print JSON instead of TOML.
        #[arg(long)]
        json: bool,
    },
    /// Classify configurations read from stdin, one per line, printing one label per line.
    ///
    /// Ternary: `ax ay bx by cx cy`; binary oriented: `ox oy yaw cx cy`; extended:
    /// `p1x p1y q1x q1y p2x p2y q2x q2y cx cy`. Blank lines and `#` comments are skipped.
    Classify {
        /// Built-in name or spec file.
        name: String,
    },
    /// The conceptual-neighbour graph and the neighbour distance matrix.
    Neighbours {
        /// Built-in name or spec file.
        name: String,
        /// Print JSON `{"states", "adjacent", "distance"}`.
        #[arg(long)]
        json: bool,
    },
    /// The composition table {AB:C} ∘ {BC:D} → {AB:D}.
    Compose {
        /// Built-in name or spec file.
        name: String,
        /// Print JSON `{"states", "table": {r: {s: [t...]}}}`.
        #[arg(long)]
        json: bool,
    },
    /// A permutation operation table.
    Permute {
        /// Built-in name or spec file.
        name: String,
        /// inverse, shortcut, shortcut-inverse, homing or homing-inverse.
        #[arg(long)]
        op: String,
        /// Print JSON `{"states", "table": {r: [t...]}}`.
        #[arg(long)]
        json: bool,
    },
    /// Draw the partition as SVG.
    Render {
        /// Built-in name or spec file.
        name: String,
        /// Output file (.svg).
        #[arg(long)]
        out: PathBuf,
        /// Picture width in pixels.
        #[arg(long, default_value_t = 640)]
        width: u32,
    },
}
