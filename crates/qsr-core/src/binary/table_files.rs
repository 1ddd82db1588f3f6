//! Binary calculi read from the reasoners' own files: GQR's `.spec` (with its composition,
//! converse and weights files) and SparQ's `def-calculus` Lisp forms.
//!
//! Relations keep the order in which the converse table (GQR) or `:base-relations` (SparQ)
//! first names them. Every structural fault is a [`QsrError::Spec`] naming the file and line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::algebra::BinaryAlgebra;
use crate::calculus::StateId;
use crate::compose::ComposeTable;
use crate::error::{QsrError, Result};
use crate::reason::network::sexpr;
use crate::text_file::{MAX_INPUT_BYTES, read_bytes, shorten};

/// A calculus file's text. GQR's own files are older than UTF-8 (its `occ.spec` has an
/// ISO-8859-1 comment), so bytes that are not UTF-8 become U+FFFD rather than an error:
/// relation names are ASCII in every published table, and one that is not still fails to
/// match, naming its line.
fn read_calculus_file(path: &Path) -> Result<String> {
    read_bytes(path, MAX_INPUT_BYTES)
        .map(|bytes| String::from_utf8_lossy(&bytes).into_owned())
        .map_err(|source| QsrError::Io {
            path: path.to_owned(),
            source,
        })
}

fn spec_error(file: &str, reason: impl Into<String>) -> QsrError {
    QsrError::Spec {
        calculus: file.to_owned(),
        reason: reason.into(),
    }
}

fn id(i: usize) -> StateId {
    StateId(u16::try_from(i).unwrap_or(u16::MAX))
}

/// Relation names in order of first appearance, and a lookup.
#[derive(Default)]
struct Names {
    labels: Vec<String>,
    index: HashMap<String, usize>,
}

impl Names {
    fn add(&mut self, label: &str) -> usize {
        if let Some(&i) = self.index.get(label) {
            return i;
        }
        self.labels.push(label.to_owned());
        self.index.insert(label.to_owned(), self.labels.len() - 1);
        self.labels.len() - 1
    }

    fn get(&self, label: &str, file: &str, line: usize) -> Result<usize> {
        self.index.get(label).copied().ok_or_else(|| {
            spec_error(
                file,
                format!(
                    "line {line}: `{}` is not a base relation (the converse table names {})",
                    shorten(label),
                    self.labels.len()
                ),
            )
        })
    }
}

impl BinaryAlgebra {
    /// A calculus as GQR defines it: a `.spec` file whose lines `comp_table_file PATH`,
    /// `converse_file PATH`, `weights PATH` (optional), `identity R` and `calculus_size N`
    /// name its tables, paths relative to the spec's directory (GQR's data directory). The
    /// name is the file's stem (`rcc8`).
    ///
    /// # Errors
    /// [`QsrError::Io`] for a file that cannot be read; [`QsrError::Spec`] naming the file and
    /// line for a malformed one, a size that disagrees with the tables, a missing entry.
    pub fn from_gqr_spec(path: &Path) -> Result<Self> {
        let read = read_calculus_file;
        let text = read(path)?;
        let shown = path.display().to_string();
        let mut keys: HashMap<&str, (usize, &str)> = HashMap::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let (key, value) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
            keys.insert(key, (i + 1, value.trim()));
        }
        let need = |key: &str| {
            keys.get(key).copied().ok_or_else(|| {
                spec_error(&shown, format!("no `{key}` line (GQR's .spec names it)"))
            })
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        let file = |key: &str| -> Result<(PathBuf, String)> {
            let (_, rel) = need(key)?;
            let p = dir.join(rel);
            Ok((p.clone(), read(&p)?))
        };
        let (conv_path, conv) = file("converse_file")?;
        let (comp_path, comp) = file("comp_table_file")?;
        let weights = match keys.get("weights") {
            Some(_) => Some(file("weights")?),
            None => None,
        };
        let (size_line, size) = need("calculus_size")?;
        let size: usize = size.parse().map_err(|_| {
            spec_error(
                &shown,
                format!(
                    "line {size_line}: calculus_size `{}` is not a number",
                    shorten(size)
                ),
            )
        })?;
        let (_, identity) = need("identity")?;
        let name = path.file_stem().map_or_else(
            || "calculus".to_owned(),
            |s| s.to_string_lossy().into_owned(),
        );
        let algebra = gqr_tables(
            &name,
            (&conv_path.display().to_string(), &conv),
            (&comp_path.display().to_string(), &comp),
            identity,
            weights
                .as_ref()
                .map(|(p, t)| (p.display().to_string(), t.as_str())),
        )?;
        if algebra.n_states() != size {
            return Err(spec_error(
                &shown,
                format!(
                    "line {size_line}: calculus_size is {size}, the converse table names {} relations",
                    algebra.n_states()
                ),
            ));
        }
        Ok(algebra)
    }

    /// A calculus from the texts of GQR's tables: converse lines `r :: t`, composition lines
    /// `r : s :: ( t1 t2 ... )`, the identity's name, and optional weights lines `r w`.
    ///
    /// # Errors
    /// As [`BinaryAlgebra::from_gqr_spec`], naming the table instead of a file.
    pub fn from_gqr_tables(
        name: &str,
        converse: &str,
        composition: &str,
        identity: &str,
        weights: Option<&str>,
    ) -> Result<Self> {
        gqr_tables(
            name,
            ("converse table", converse),
            ("composition table", composition),
            identity,
            weights.map(|w| ("weights".to_owned(), w)),
        )
    }

    /// A binary calculus from a SparQ definition file (`(def-calculus "name" :arity :binary
    /// :base-relations (...) :identity-relation r :converse-operation ((r t) ...)
    /// :composition-operation ((r s (t ...)) ...))`), relations matched ignoring case.
    ///
    /// # Errors
    /// [`QsrError::Io`], and [`QsrError::Spec`] naming the file for a form that is missing,
    /// not binary, or whose tables name relations it does not have.
    pub fn from_sparq_file(path: &Path) -> Result<Self> {
        let text = read_calculus_file(path)?;
        Self::from_sparq_str(&text).map_err(|e| match e {
            QsrError::Spec { reason, .. } => spec_error(&path.display().to_string(), reason),
            other => other,
        })
    }

    /// As [`BinaryAlgebra::from_sparq_file`], from the file's text.
    ///
    /// # Errors
    /// As [`BinaryAlgebra::from_sparq_file`].
    pub fn from_sparq_str(text: &str) -> Result<Self> {
        sparq_algebra(text)
    }
}

fn gqr_tables(
    name: &str,
    (conv_file, conv): (&str, &str),
    (comp_file, comp): (&str, &str),
    identity: &str,
    weights: Option<(String, &str)>,
) -> Result<BinaryAlgebra> {
    let mut names = Names::default();
    let mut pairs = Vec::new();
    for (i, line) in conv.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (r, t) = line.split_once("::").ok_or_else(|| {
            spec_error(
                conv_file,
                format!(
                    "line {}: expected `r :: converse`, got `{}`",
                    i + 1,
                    shorten(line)
                ),
            )
        })?;
        let (r, t) = (r.trim(), t.trim());
        if r.is_empty() || t.is_empty() || t.contains(char::is_whitespace) {
            return Err(spec_error(
                conv_file,
                format!(
                    "line {}: expected `r :: converse`, got `{}`",
                    i + 1,
                    shorten(line)
                ),
            ));
        }
        pairs.push((i + 1, names.add(r), t.to_owned()));
    }
    let n = names.labels.len();
    if n == 0 {
        return Err(spec_error(
            conv_file,
            "0 base relations: the converse table names every relation (`r :: converse`)",
        ));
    }
    let mut converse = vec![Vec::new(); n];
    for (line, r, t) in &pairs {
        if !converse[*r].is_empty() {
            return Err(spec_error(
                conv_file,
                format!(
                    "line {line}: `{}` is given a converse twice",
                    names.labels[*r]
                ),
            ));
        }
        converse[*r].push(id(names.get(t, conv_file, *line)?));
    }
    let mut rows = vec![vec![None::<Vec<StateId>>; n]; n];
    for (i, line) in comp.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let shape = || {
            spec_error(
                comp_file,
                format!(
                    "line {}: expected `r : s :: ( t1 t2 ... )`, got `{}`",
                    i + 1,
                    shorten(line)
                ),
            )
        };
        let (lhs, rhs) = line.split_once("::").ok_or_else(shape)?;
        let (r, s) = lhs.split_once(':').ok_or_else(shape)?;
        let rhs = rhs.trim();
        let inner = rhs
            .strip_prefix('(')
            .and_then(|x| x.strip_suffix(')'))
            .ok_or_else(shape)?;
        let (r, s) = (
            names.get(r.trim(), comp_file, i + 1)?,
            names.get(s.trim(), comp_file, i + 1)?,
        );
        let mut result = Vec::new();
        for t in inner.split_whitespace() {
            result.push(id(names.get(t, comp_file, i + 1)?));
        }
        if rows[r][s].replace(result).is_some() {
            return Err(spec_error(
                comp_file,
                format!(
                    "line {}: `{} : {}` is given twice",
                    i + 1,
                    names.labels[r],
                    names.labels[s]
                ),
            ));
        }
    }
    let compose = complete_rows(rows, &names.labels, comp_file)?;
    let identity = id(names.get(identity, "the identity", 1).map_err(|_| {
        spec_error(
            name,
            format!(
                "the identity `{}` is not a base relation",
                shorten(identity)
            ),
        )
    })?);
    let weights = match weights {
        None => None,
        Some((file, text)) => Some(read_weights(&names, &file, text)?),
    };
    BinaryAlgebra::from_tables(
        name,
        names.labels,
        converse,
        compose,
        Some(identity),
        weights,
    )
}

fn complete_rows(
    rows: Vec<Vec<Option<Vec<StateId>>>>,
    labels: &[String],
    file: &str,
) -> Result<ComposeTable> {
    let mut full = Vec::with_capacity(rows.len());
    for (r, row) in rows.into_iter().enumerate() {
        let mut done = Vec::with_capacity(row.len());
        for (s, entry) in row.into_iter().enumerate() {
            done.push(entry.ok_or_else(|| {
                spec_error(
                    file,
                    format!("no entry for `{} : {}`", labels[r], labels[s]),
                )
            })?);
        }
        full.push(done);
    }
    ComposeTable::from_rows(full)
}

fn read_weights(names: &Names, file: &str, text: &str) -> Result<Vec<u32>> {
    let mut weights = vec![None; names.labels.len()];
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let mut parts = line.split_whitespace();
        let (Some(r), Some(w), None) = (parts.next(), parts.next(), parts.next()) else {
            return Err(spec_error(
                file,
                format!(
                    "line {}: expected `r weight`, got `{}`",
                    i + 1,
                    shorten(line)
                ),
            ));
        };
        let r = names.get(r, file, i + 1)?;
        let w: u32 = w.parse().ok().filter(|w| *w >= 1).ok_or_else(|| {
            spec_error(
                file,
                format!(
                    "line {}: weight `{}` is not a whole number ≥ 1",
                    i + 1,
                    shorten(w)
                ),
            )
        })?;
        weights[r] = Some(w);
    }
    weights
        .into_iter()
        .enumerate()
        .map(|(r, w)| {
            w.ok_or_else(|| spec_error(file, format!("no weight for `{}`", names.labels[r])))
        })
        .collect()
}

/// `#| … |#` block comments removed (the s-expression reader knows only `;`).
fn strip_block_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("#|") {
        out.push_str(&rest[..start]);
        match rest[start..].find("|#") {
            Some(end) => {
                // Keep the line count for error positions.
                let skipped = &rest[start..start + end + 2];
                out.extend(skipped.chars().filter(|c| *c == '\n'));
                rest = &rest[start + end + 2..];
            }
            None => {
                rest = "";
            }
        }
    }
    out.push_str(rest);
    out
}

fn sparq_algebra(text: &str) -> Result<BinaryAlgebra> {
    let file = "SparQ definition";
    let wrapped = format!("({}\n)", strip_block_comments(text));
    let top = sexpr::parse(&wrapped).map_err(|e| spec_error(file, e.to_string()))?;
    let form = top
        .as_list()
        .unwrap_or(&[])
        .iter()
        .filter_map(sexpr::Expr::as_list)
        .find(|l| {
            l.first()
                .and_then(sexpr::Expr::as_atom)
                .is_some_and(|a| a.eq_ignore_ascii_case("def-calculus"))
        })
        .ok_or_else(|| spec_error(file, "no (def-calculus ...) form"))?;
    let name = form
        .get(1)
        .and_then(sexpr::Expr::as_atom)
        .map_or("sparq", |a| a.trim_matches('"'))
        .to_owned();
    let key = |k: &str| {
        form.iter()
            .position(|e| e.as_atom().is_some_and(|a| a.eq_ignore_ascii_case(k)))
            .and_then(|i| form.get(i + 1))
    };
    if let Some(arity) = key(":arity").and_then(sexpr::Expr::as_atom)
        && !arity.eq_ignore_ascii_case(":binary")
    {
        return Err(spec_error(
            &name,
            format!("arity {arity}: only binary calculi are read as tables"),
        ));
    }
    let atoms = |e: &sexpr::Expr| -> Vec<String> {
        match &e.kind {
            sexpr::Kind::Atom(a) if a.eq_ignore_ascii_case("nil") => Vec::new(),
            sexpr::Kind::Atom(a) => vec![a.clone()],
            sexpr::Kind::List(l) => l
                .iter()
                .filter_map(|x| x.as_atom().map(str::to_owned))
                .collect(),
        }
    };
    let base = key(":base-relations")
        .map(atoms)
        .ok_or_else(|| spec_error(&name, "no :base-relations"))?;
    let mut names = Names::default();
    let mut folded: HashMap<String, usize> = HashMap::new();
    for b in &base {
        let i = names.add(b);
        folded.insert(b.to_ascii_lowercase(), i);
    }
    let find = |label: &str, e: &sexpr::Expr| {
        folded
            .get(&label.to_ascii_lowercase())
            .copied()
            .ok_or_else(|| {
                spec_error(
                    &name,
                    format!(
                        "line {}: `{}` is not one of :base-relations",
                        e.line,
                        shorten(label)
                    ),
                )
            })
    };
    let n = names.labels.len();
    let rows_of = |k: &str| -> Result<&[sexpr::Expr]> {
        key(k)
            .and_then(sexpr::Expr::as_list)
            .ok_or_else(|| spec_error(&name, format!("no {k} table")))
    };
    let mut converse = vec![Vec::new(); n];
    for row in rows_of(":converse-operation")? {
        let items = row.as_list().filter(|l| l.len() == 2).ok_or_else(|| {
            spec_error(&name, format!("line {}: a converse row is (r t)", row.line))
        })?;
        let r = find(items[0].as_atom().unwrap_or(""), row)?;
        for t in atoms(&items[1]) {
            converse[r].push(id(find(&t, row)?));
        }
    }
    let mut rows = vec![vec![None::<Vec<StateId>>; n]; n];
    for row in rows_of(":composition-operation")? {
        let items = row.as_list().filter(|l| l.len() == 3).ok_or_else(|| {
            spec_error(
                &name,
                format!("line {}: a composition row is (r s (t ...))", row.line),
            )
        })?;
        let r = find(items[0].as_atom().unwrap_or(""), row)?;
        let s = find(items[1].as_atom().unwrap_or(""), row)?;
        let mut result = Vec::new();
        for t in atoms(&items[2]) {
            result.push(id(find(&t, row)?));
        }
        rows[r][s] = Some(result);
    }
    let compose = complete_rows(rows, &names.labels, &name)?;
    let identity = match key(":identity-relation").and_then(sexpr::Expr::as_atom) {
        Some(i) => Some(id(find(i, form.first().unwrap_or(&top))?)),
        None => None,
    };
    BinaryAlgebra::from_tables(&name, names.labels, converse, compose, identity, None)
}

/// A calculus's tables in GQR's text forms, as [`BinaryAlgebra::to_gqr_tables`] writes them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GqrTables {
    /// Converse lines `r :: t`.
    pub converse: String,
    /// Composition lines `r : s :: ( t1 t2 ... )`.
    pub composition: String,
    /// Weight lines `r w`.
    pub weights: String,
    /// The `.spec` file naming them as `NAME/calculus/NAME.{comp,conv,weights}` (GQR's
    /// layout), with the identity and the size.
    pub spec: String,
}

impl BinaryAlgebra {
    /// The tables in GQR's forms, so a derived calculus (OPRA-m, STAR-m) can be given to GQR,
    /// and a loaded one written back. [`BinaryAlgebra::from_gqr_tables`] reads them again.
    ///
    /// # Errors
    /// [`QsrError::Unsupported`] for a calculus without an identity or with a multi-valued
    /// converse (GQR's files cannot say it); as [`BinaryAlgebra::compose_table`].
    pub fn to_gqr_tables(&self) -> Result<GqrTables> {
        let unsupported = |reason: &str| QsrError::Unsupported {
            operation: "GQR tables".into(),
            calculus: self.name().to_owned(),
            reason: reason.into(),
        };
        let identity = self
            .identity()
            .ok_or_else(|| unsupported("it names no identity relation"))?;
        let table = self.compose_table()?;
        let mut converse = String::new();
        let mut composition = String::new();
        let mut weights = String::new();
        for r in self.states() {
            let [t] = self.converse(r) else {
                return Err(unsupported("a relation has more than one converse"));
            };
            converse.push_str(&format!("{} :: {}\n", self.label(r), self.label(*t)));
            weights.push_str(&format!("{} {}\n", self.label(r), self.weight(r)));
            for s in self.states() {
                let result: Vec<&str> = table.get(r, s).iter().map(|t| self.label(*t)).collect();
                composition.push_str(&format!(
                    "{} : {} :: ( {} )\n",
                    self.label(r),
                    self.label(s),
                    result.join(" ")
                ));
            }
        }
        let name = self.name();
        let spec = format!(
            "# {name}, written by qrm\ncomp_table_file {name}/calculus/{name}.comp\n\
             converse_file {name}/calculus/{name}.conv\nweights {name}/calculus/{name}.weights\n\
             identity {}\ncalculus_size {}\n",
            self.label(identity),
            self.n_states()
        );
        Ok(GqrTables {
            converse,
            composition,
            weights,
            spec,
        })
    }
}
