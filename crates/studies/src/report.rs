//! What a study says: claims set beside the thesis's with computed verdicts, tables defined
//! once and rendered for the terminal, markdown and CSV, and the data of its figures.
//!
//! A front end never formats a study's numbers itself: it asks a [`Table`] for its CSV, its
//! markdown or its terminal text, draws each [`Figure`] with whatever plotting it has, and
//! writes [`Report::to_markdown`]. So the CLI, Python and a Ray driver show the same table.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

/// How a claim of ours compares with the thesis's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Ours says what the thesis says.
    Agree,
    /// Ours says otherwise.
    Disagree,
    /// A property holds in our runs: one the thesis proves, or a claim of ours where the
    /// thesis measures nothing (the reasoning study's).
    Holds,
    /// Such a property fails in our runs (a proof's assumptions do not hold, a claim of ours
    /// is not borne out, or a bug).
    Violated,
    /// Nothing to judge by: the claim is over cases this run has none of (no trial ran, no
    /// success to measure, no run whose assumptions hold). A claim over nothing is neither
    /// borne out nor refuted — "0 of 0 exceed the bound" is not an agreement.
    NotJudged,
}

impl Verdict {
    /// `Agree` when `same`, else `Disagree`.
    #[must_use]
    pub fn agree_if(same: bool) -> Self {
        if same { Self::Agree } else { Self::Disagree }
    }

    /// `Holds` when `holds`, else `Violated`.
    #[must_use]
    pub fn holds_if(holds: bool) -> Self {
        if holds { Self::Holds } else { Self::Violated }
    }

    /// This verdict, judged over `cases` cases: [`Verdict::NotJudged`] when there are none.
    /// Every claim over a pool that a run can leave empty states its verdict through this,
    /// so that an empty pool is never a vacuous agreement (nor a disagreement).
    ///
    /// ```
    /// use studies::Verdict;
    /// assert_eq!(Verdict::agree_if(true).over(0), Verdict::NotJudged);
    /// assert_eq!(Verdict::agree_if(true).over(3), Verdict::Agree);
    /// ```
    #[must_use]
    pub fn over(self, cases: usize) -> Self {
        if cases == 0 { Self::NotJudged } else { self }
    }

    /// "agree", "disagree", "holds", "violated", "not-judged" (as in the JSON).
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Agree => "agree",
            Self::Disagree => "disagree",
            Self::Holds => "holds",
            Self::Violated => "violated",
            Self::NotJudged => "not-judged",
        }
    }
}

/// One thing the thesis says, what we measured, and whether they agree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Claim {
    /// What is claimed ("failure rate as R' shrinks").
    pub what: String,
    /// The thesis's statement or numbers.
    pub thesis: String,
    /// Ours, from the records.
    pub ours: String,
    /// Computed from the two.
    pub verdict: Verdict,
    /// Why, where a verdict needs a reason (markdown; empty for none).
    #[serde(default)]
    pub why: String,
}

/// One cell: what a CSV holds (full precision, empty for missing) and what a person reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// The CSV field.
    pub csv: String,
    /// The text in markdown and on the terminal.
    pub text: String,
}

impl Cell {
    /// Text, the same everywhere.
    #[must_use]
    pub fn text(s: impl Into<String>) -> Self {
        let s = s.into();
        Self {
            csv: s.clone(),
            text: s,
        }
    }

    /// An integer.
    #[must_use]
    pub fn int(n: impl Into<i128>) -> Self {
        Self::text(n.into().to_string())
    }

    /// A number written in full in CSV (Rust's shortest round-trip form) and with `decimals`
    /// for a person.
    #[must_use]
    pub fn number(v: f64, decimals: usize) -> Self {
        Self {
            csv: v.to_string(),
            text: format!("{v:.decimals$}"),
        }
    }

    /// A number with `decimals` everywhere (a measured length, where more digits are noise).
    #[must_use]
    pub fn fixed(v: f64, decimals: usize) -> Self {
        Self::text(format!("{v:.decimals$}"))
    }

    /// A fraction: in full in CSV, as a percentage with `decimals` for a person.
    #[must_use]
    pub fn percent(fraction: f64, decimals: usize) -> Self {
        Self {
            csv: fraction.to_string(),
            text: format!("{:.decimals$} %", 100.0 * fraction),
        }
    }

    /// No value: an empty CSV field, "-" for a person.
    #[must_use]
    pub fn missing() -> Self {
        Self {
            csv: String::new(),
            text: "-".to_owned(),
        }
    }

    /// `f` of the value, or [`Cell::missing`].
    #[must_use]
    pub fn maybe<T>(v: Option<T>, f: impl FnOnce(T) -> Self) -> Self {
        v.map_or_else(Self::missing, f)
    }
}

/// Where a column is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shown {
    /// In the CSV, the markdown and on the terminal.
    Everywhere,
    /// Only in the CSV (data a person rarely reads: bounds, ids).
    CsvOnly,
    /// Only for a person (timings, which would make the CSV differ run to run).
    HumanOnly,
}

/// A column: its CSV key and the heading a person reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Column {
    /// CSV header.
    pub key: String,
    /// Markdown and terminal heading.
    pub heading: String,
    /// Where it is shown.
    pub shown: Shown,
}

impl Column {
    /// A column shown everywhere.
    #[must_use]
    pub fn new(key: &str, heading: &str) -> Self {
        Self {
            key: key.to_owned(),
            heading: heading.to_owned(),
            shown: Shown::Everywhere,
        }
    }

    /// Shown only in the CSV.
    #[must_use]
    pub fn csv_only(mut self) -> Self {
        self.shown = Shown::CsvOnly;
        self
    }

    /// Shown only to a person.
    #[must_use]
    pub fn human_only(mut self) -> Self {
        self.shown = Shown::HumanOnly;
        self
    }
}

/// A table defined once: its columns and rows of cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Table {
    /// File stem of its CSV (`table` → `table.csv`).
    pub name: String,
    /// Heading in the report ("Table 4.1").
    pub title: String,
    /// A paragraph above it in the report (markdown; may be empty).
    pub caption: String,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows, each as long as `columns`.
    pub rows: Vec<Vec<Cell>>,
    /// Shown in the report and on the terminal (false: data written as CSV only).
    pub in_report: bool,
}

impl Table {
    /// An empty table shown in the report.
    #[must_use]
    pub fn new(name: &str, title: &str, columns: Vec<Column>) -> Self {
        Self {
            name: name.to_owned(),
            title: title.to_owned(),
            caption: String::new(),
            columns,
            rows: Vec::new(),
            in_report: true,
        }
    }

    /// With a caption.
    #[must_use]
    pub fn caption(mut self, caption: impl Into<String>) -> Self {
        self.caption = caption.into();
        self
    }

    /// Data only: written as CSV, not shown in the report.
    #[must_use]
    pub fn data_only(mut self) -> Self {
        self.in_report = false;
        self
    }

    /// Appends a row.
    ///
    /// # Panics
    /// When the row's length is not the number of columns: a bug in the study, which its
    /// tests meet.
    pub fn push(&mut self, row: Vec<Cell>) {
        assert_eq!(
            row.len(),
            self.columns.len(),
            "table `{}`: a row of {} cells for {} columns",
            self.name,
            row.len(),
            self.columns.len()
        );
        self.rows.push(row);
    }

    fn indices(&self, human: bool) -> Vec<usize> {
        self.columns
            .iter()
            .enumerate()
            .filter(|(_, c)| match c.shown {
                Shown::Everywhere => true,
                Shown::CsvOnly => !human,
                Shown::HumanOnly => human,
            })
            .map(|(i, _)| i)
            .collect()
    }

    /// The CSV columns: headers then rows, each a list of fields (quoting is the writer's).
    #[must_use]
    pub fn csv_records(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let idx = self.indices(false);
        let header = idx.iter().map(|&i| self.columns[i].key.clone()).collect();
        let rows = self
            .rows
            .iter()
            .map(|r| idx.iter().map(|&i| r[i].csv.clone()).collect())
            .collect();
        (header, rows)
    }

    /// The table in markdown (pipes in cells escaped).
    #[must_use]
    pub fn to_markdown(&self) -> String {
        let idx = self.indices(true);
        let esc = |s: &str| s.replace('|', "\\|");
        let mut s = String::new();
        let heads: Vec<String> = idx.iter().map(|&i| esc(&self.columns[i].heading)).collect();
        let _ = writeln!(s, "| {} |", heads.join(" | "));
        let _ = writeln!(s, "|{}", "---|".repeat(idx.len()));
        for r in &self.rows {
            let cells: Vec<String> = idx.iter().map(|&i| esc(&r[i].text)).collect();
            let _ = writeln!(s, "| {} |", cells.join(" | "));
        }
        s
    }

    /// The table as aligned text for a terminal: text columns left, numbers right.
    #[must_use]
    pub fn to_terminal(&self) -> String {
        let idx = self.indices(true);
        let width: Vec<usize> = idx
            .iter()
            .map(|&i| {
                self.rows
                    .iter()
                    .map(|r| r[i].text.chars().count())
                    .chain([self.columns[i].heading.chars().count()])
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let numeric: Vec<bool> = idx
            .iter()
            .map(|&i| {
                self.rows.iter().all(|r| {
                    let t = r[i].text.trim_end_matches(" %").trim_end_matches('%');
                    t == "-" || t.parse::<f64>().is_ok()
                })
            })
            .collect();
        let line = |cells: Vec<&str>| {
            let parts: Vec<String> = cells
                .iter()
                .zip(&width)
                .zip(&numeric)
                .map(|((c, &w), &num)| {
                    if num {
                        format!("{c:>w$}")
                    } else {
                        format!("{c:<w$}")
                    }
                })
                .collect();
            parts.join("  ").trim_end().to_owned()
        };
        let mut s = line(
            idx.iter()
                .map(|&i| self.columns[i].heading.as_str())
                .collect(),
        );
        s.push('\n');
        for r in &self.rows {
            s.push_str(&line(idx.iter().map(|&i| r[i].text.as_str()).collect()));
            s.push('\n');
        }
        s
    }
}

/// A series of a line chart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Line {
    /// Legend entry.
    pub name: String,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
    /// ± error bar per point.
    #[serde(default)]
    pub err: Option<Vec<f64>>,
    /// A reference (a bound, a baseline): drawn dashed.
    pub reference: bool,
}

/// A run drawn on a site: its path, and whether it reached its goal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SiteRun {
    /// Positions along the run (m).
    pub points: Vec<(f64, f64)>,
    /// Reached its goal (drawn solid; dashed when not).
    pub reached: bool,
}

/// What a figure shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Plot {
    /// Histograms of groups of values over shared bin edges.
    Histogram {
        /// Bin edges, ascending.
        edges: Vec<f64>,
        /// `(legend, values)` per group.
        groups: Vec<(String, Vec<f64>)>,
    },
    /// Lines.
    Lines {
        /// The series.
        series: Vec<Line>,
    },
    /// Points `(x, y, colour value)` in the normalised frame of a ternary calculus, over the
    /// EDC's curves (thesis Fig 2.8).
    EdcScatter {
        /// `(x, y, value)`.
        points: Vec<(f64, f64, f64)>,
        /// What the colour shows.
        colour_label: String,
    },
    /// A matrix of counts with labelled rows and columns (a confusion matrix).
    Heatmap {
        /// Row and column labels.
        labels: Vec<String>,
        /// `matrix[row][column]`.
        matrix: Vec<Vec<u64>>,
    },
    /// A partition of a window into regions, cell by cell (a salient region map, a raster
    /// calculus; thesis Figs 3.8–3.10), with data points and marks over it.
    Regions {
        /// `[x0, x1, y0, y1]`.
        window: [f64; 4],
        /// Cells along x.
        nx: usize,
        /// Cells along y.
        ny: usize,
        /// Region of every cell, row by row (`u32::MAX`: not drawn).
        cell_region: Vec<u32>,
        /// Data points (black).
        points: Vec<[f64; 2]>,
        /// Cells shaded dark (a plan's path, where a composed point can be).
        shade: Option<Vec<bool>>,
        /// Labelled marks (red).
        marks: Vec<([f64; 2], String)>,
        /// Each region's number written at its centroid.
        numbers: bool,
    },
    /// A simulated site from above: its objects, the mapping drive and runs over them
    /// (thesis Fig 4.9).
    Site {
        /// The site.
        world: sim2d::WorldSpec,
        /// The mapping drive (m).
        drive: Vec<(f64, f64)>,
        /// The runs.
        runs: Vec<SiteRun>,
    },
    /// Every landmark in the normalised frame of one reference pair, coloured by a
    /// probability: those whose set with the pair was observed (circles) and those inferred
    /// (triangles), `(x, y, p)` each (the reasoning study).
    ReferencePair {
        /// Observed sets.
        observed: Vec<(f64, f64, f64)>,
        /// Inferred sets.
        inferred: Vec<(f64, f64, f64)>,
    },
    /// A simulated run from above: the world, the robot's path and rays to what it detected
    /// (`qrm sim`'s picture).
    Scenario {
        /// The world.
        world: sim2d::WorldSpec,
        /// The path (m).
        trajectory: Vec<(f64, f64)>,
        /// Rays from the robot to its detections, `(from, to)` (m).
        rays: Vec<((f64, f64), (f64, f64))>,
    },
    /// One navigation over a simulated site and, beside it, a calculus's regions (the demo's
    /// picture); boxed, being far larger than the other kinds.
    Navigation(Box<NavigationPicture>),
}

/// One navigation over a simulated site — the mapping drive, the plan's map elements as
/// triangles of their landmarks, the links found, where the robot searched, start and goal —
/// and beside it, optionally, a calculus's regions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NavigationPicture {
    /// The site.
    pub world: sim2d::WorldSpec,
    /// The mapping drive (m).
    pub drive: Vec<[f64; 2]>,
    /// The navigation's positions (m).
    pub trajectory: Vec<[f64; 2]>,
    /// Index ranges `[from, to]` of `trajectory` spent searching (inclusive).
    pub searches: Vec<[usize; 2]>,
    /// The first plan's elements, each as its three landmarks' positions.
    pub plan: Vec<[[f64; 2]; 3]>,
    /// Positions of the links found.
    pub links: Vec<[f64; 2]>,
    /// Start position.
    pub start: [f64; 2],
    /// The goal landmark's position.
    pub goal: [f64; 2],
    /// A calculus's regions, drawn in a panel beside the site.
    pub regions: Option<RegionsPanel>,
}

/// A calculus's regions on a grid over its normalised frame (A = (0, 0), B = (1, 0)), for a
/// panel beside another picture.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionsPanel {
    /// The panel's title.
    pub title: String,
    /// `[x0, x1, y0, y1]`.
    pub window: [f64; 4],
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
    /// Region of every cell, row by row.
    pub cell_region: Vec<u32>,
    /// Labelled marks (the reference landmarks).
    pub marks: Vec<([f64; 2], String)>,
}

/// A figure's data: a front end draws it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    /// File stem (`fig4_6_plan_length_histogram`).
    pub name: String,
    /// Title.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label (histograms: the count's).
    pub y_label: String,
    /// The data.
    pub plot: Plot,
}

/// A file a study produces beside its tables and figures (a learned calculus, a map, a log),
/// written as it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attachment {
    /// Path under the output directory (`hallway/calculus.json`).
    pub name: String,
    /// Its text (empty for a binary file).
    pub text: String,
    /// A binary file's bytes (`None` for a text file): base64 text in JSON, so a report stays
    /// one JSON document for Python and for shards sent across a cluster.
    #[serde(default, with = "base64_bytes")]
    pub data: Option<Vec<u8>>,
}

impl Attachment {
    /// A text file.
    #[must_use]
    pub fn text(name: impl Into<String>, text: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            text: text.into(),
            data: None,
        }
    }

    /// A binary file.
    #[must_use]
    pub fn binary(name: impl Into<String>, data: Vec<u8>) -> Self {
        Self {
            name: name.into(),
            text: String::new(),
            data: Some(data),
        }
    }

    /// What the file holds.
    #[must_use]
    pub fn bytes(&self) -> &[u8] {
        self.data.as_deref().unwrap_or(self.text.as_bytes())
    }
}

/// Files a job makes for a front end to write as they are — tables (as CSV), figures (drawn by
/// `qrm-plot`), attachments — when the job is not a study with a report (`qrm sim`, a noise
/// calibration, a salient region map): one definition of its files for the CLI and Python.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Products {
    /// Tables, each written as `name.csv`.
    pub tables: Vec<Table>,
    /// Figures, each written as `name.svg` and `name.png`.
    pub figures: Vec<Figure>,
    /// Files written as they are.
    pub attachments: Vec<Attachment>,
}

/// `Option<Vec<u8>>` as base64 text (standard alphabet, padded) or null.
pub mod base64_bytes {
    use base64::Engine as _;
    use base64::engine::general_purpose::STANDARD;
    use serde::{Deserialize, Deserializer, Serializer};

    /// Serialises bytes as base64 text, `None` as null.
    ///
    /// # Errors
    /// The serializer's.
    #[allow(clippy::ref_option)] // the signature serde's `with` calls
    pub fn serialize<S: Serializer>(v: &Option<Vec<u8>>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(b) => s.serialize_str(&STANDARD.encode(b)),
            None => s.serialize_none(),
        }
    }

    /// Reads base64 text or null.
    ///
    /// # Errors
    /// Text that is not base64 (the decoder's reason).
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<u8>>, D::Error> {
        Option::<String>::deserialize(d)?
            .map(|t| {
                STANDARD
                    .decode(t.as_bytes())
                    .map_err(|e| serde::de::Error::custom(format!("not base64: {e}")))
            })
            .transpose()
    }
}

/// Everything a study says about one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Report {
    /// Heading.
    pub title: String,
    /// The set-up, as markdown paragraphs (what ran, with what, how long).
    pub setup: String,
    /// Tables, in report order.
    pub tables: Vec<Table>,
    /// Claims beside the thesis's.
    pub claims: Vec<Claim>,
    /// Figures.
    pub figures: Vec<Figure>,
    /// Closing markdown: where we differ from the thesis and why (mechanisms only — every
    /// number and verdict is in the tables and claims).
    pub notes: String,
    /// Files beside the tables and figures.
    #[serde(default)]
    pub attachments: Vec<Attachment>,
}

impl Report {
    /// The report on a terminal: each table in the report (`title:` then its columns
    /// aligned), then each claim as `[verdict] what: thesis …; ours …`.
    #[must_use]
    pub fn to_terminal(&self) -> String {
        let mut s = String::new();
        for t in self.tables.iter().filter(|t| t.in_report) {
            let _ = writeln!(s, "{}:\n{}", t.title, t.to_terminal());
        }
        for c in &self.claims {
            let _ = writeln!(
                s,
                "[{}] {}: thesis {}; ours {}",
                c.verdict.as_str(),
                c.what,
                c.thesis,
                c.ours
            );
        }
        s
    }

    /// The report as markdown: title, set-up, tables, claims, notes, the files' names.
    #[must_use]
    pub fn to_markdown(&self) -> String {
        let mut s = format!("# {}\n\n", self.title);
        if !self.setup.is_empty() {
            s.push_str(self.setup.trim_end());
            s.push_str("\n\n");
        }
        for t in self.tables.iter().filter(|t| t.in_report) {
            let _ = writeln!(s, "## {}\n", t.title);
            if !t.caption.is_empty() {
                let _ = writeln!(s, "{}\n", t.caption.trim_end());
            }
            s.push_str(&t.to_markdown());
            s.push('\n');
        }
        if !self.claims.is_empty() {
            s.push_str("## Claims\n\n| claim | thesis | ours | verdict |\n|---|---|---|---|\n");
            for c in &self.claims {
                let verdict = if c.why.is_empty() {
                    format!("**{}**", c.verdict.as_str())
                } else {
                    format!("**{}** — {}", c.verdict.as_str(), c.why)
                };
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} |",
                    c.what.replace('|', "\\|"),
                    c.thesis.replace('|', "\\|"),
                    c.ours.replace('|', "\\|"),
                    verdict.replace('|', "\\|")
                );
            }
            s.push('\n');
        }
        if !self.notes.is_empty() {
            s.push_str(self.notes.trim_end());
            s.push_str("\n\n");
        }
        let figures: Vec<String> = self
            .figures
            .iter()
            .map(|f| format!("`{}.svg`", f.name))
            .collect();
        let data: Vec<String> = self
            .tables
            .iter()
            .map(|t| format!("`{}.csv`", t.name))
            .collect();
        if !figures.is_empty() || !data.is_empty() {
            let _ = writeln!(
                s,
                "Figures: {}; data: {}.",
                if figures.is_empty() {
                    "none".to_owned()
                } else {
                    figures.join(", ")
                },
                data.join(", ")
            );
        }
        s
    }

    /// The table named `name`.
    #[must_use]
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }

    /// The claim whose `what` starts with `prefix`.
    #[must_use]
    pub fn claim(&self, prefix: &str) -> Option<&Claim> {
        self.claims.iter().find(|c| c.what.starts_with(prefix))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Table {
        let mut t = Table::new(
            "t",
            "T",
            vec![
                Column::new("name", "name"),
                Column::new("rate", "rate"),
                Column::new("bound", "bound").csv_only(),
                Column::new("secs", "time (s)").human_only(),
            ],
        );
        t.push(vec![
            Cell::text("a|b"),
            Cell::percent(0.125, 1),
            Cell::fixed(1.23456, 3),
            Cell::number(2.0, 2),
        ]);
        t.push(vec![
            Cell::text("c"),
            Cell::missing(),
            Cell::int(7u32),
            Cell::number(0.5, 2),
        ]);
        t
    }

    #[test]
    fn one_table_three_renderings() {
        let t = sample();
        let (h, rows) = t.csv_records();
        assert_eq!(h, ["name", "rate", "bound"]);
        assert_eq!(rows[0], ["a|b", "0.125", "1.235"]);
        assert_eq!(rows[1], ["c", "", "7"]);
        let md = t.to_markdown();
        assert!(
            md.starts_with("| name | rate | time (s) |\n|---|---|---|\n"),
            "{md}"
        );
        assert!(md.contains("| a\\|b | 12.5 % | 2.00 |"), "{md}");
        assert!(md.contains("| c | - | 0.50 |"), "{md}");
        let term = t.to_terminal();
        let lines: Vec<&str> = term.lines().collect();
        assert_eq!(lines[0], "name    rate  time (s)");
        assert_eq!(lines[1], "a|b   12.5 %      2.00");
        assert_eq!(lines[2], "c          -      0.50");
    }

    #[test]
    #[should_panic(expected = "a row of 1 cells for 4 columns")]
    fn a_short_row_is_a_bug_not_a_ragged_csv() {
        sample().push(vec![Cell::text("x")]);
    }

    #[test]
    fn the_report_lists_claims_with_their_verdicts() {
        let r = Report {
            title: "X".into(),
            tables: vec![sample()],
            claims: vec![Claim {
                what: "rate rises".into(),
                thesis: "rises".into(),
                ours: "is flat".into(),
                verdict: Verdict::agree_if(false),
                why: String::new(),
            }],
            ..Report::default()
        };
        let md = r.to_markdown();
        assert!(
            md.contains("| rate rises | rises | is flat | **disagree** |"),
            "{md}"
        );
        assert!(md.contains("data: `t.csv`"));
        assert_eq!(r.claim("rate").map(|c| c.verdict), Some(Verdict::Disagree));
    }
}
