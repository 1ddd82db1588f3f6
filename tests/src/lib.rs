//! Cross-crate tests of qrm live in `tests/tests/`; this library only holds helpers they
//! share: where the workspace, the `qrm` binary and `shared/` are.

use std::path::PathBuf;

pub mod fuzz;

/// The workspace root.
#[must_use]
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default()
}

/// `shared/` beside the checkout (oracles, data), if present.
#[must_use]
pub fn shared_dir() -> Option<PathBuf> {
    let dir = workspace_root().parent()?.join("shared");
    dir.is_dir().then_some(dir)
}

/// A reader for the Lisp tables of SparQ (`shared/oracles/sparq/*.lisp`). Test data only:
/// malformed input panics with the reason.
#[allow(clippy::unwrap_used, clippy::missing_panics_doc)]
pub mod sexp {
    /// A Lisp s-expression (atoms lower-cased: SparQ's names are case-insensitive).
    #[derive(Debug, Clone)]
    pub enum Sexp {
        /// A symbol or number.
        Atom(String),
        /// A parenthesised list.
        List(Vec<Sexp>),
    }

    impl Sexp {
        /// The atom, if this is one.
        #[must_use]
        pub fn atom(&self) -> Option<&str> {
            match self {
                Self::Atom(a) => Some(a),
                Self::List(_) => None,
            }
        }
        /// The items, if this is a list (empty otherwise).
        #[must_use]
        pub fn list(&self) -> &[Sexp] {
            match self {
                Self::List(l) => l,
                Self::Atom(_) => &[],
            }
        }
    }

    /// Every top-level form of a Lisp file.
    ///
    /// # Panics
    /// On unbalanced parentheses (test data only).
    #[must_use]
    pub fn parse(text: &str) -> Vec<Sexp> {
        let mut tokens = Vec::new();
        let mut cur = String::new();
        let mut chars = text.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                ';' => {
                    for d in chars.by_ref() {
                        if d == '\n' {
                            break;
                        }
                    }
                }
                '(' | ')' => {
                    if !cur.is_empty() {
                        tokens.push(std::mem::take(&mut cur));
                    }
                    tokens.push(c.to_string());
                }
                c if c.is_whitespace() => {
                    if !cur.is_empty() {
                        tokens.push(std::mem::take(&mut cur));
                    }
                }
                c => cur.push(c),
            }
        }
        let mut stack: Vec<Vec<Sexp>> = vec![Vec::new()];
        for t in tokens {
            match t.as_str() {
                "(" => stack.push(Vec::new()),
                ")" => {
                    let done = stack.pop().unwrap();
                    stack.last_mut().unwrap().push(Sexp::List(done));
                }
                _ => stack.last_mut().unwrap().push(Sexp::Atom(t.to_lowercase())),
            }
        }
        stack.pop().unwrap()
    }

    /// The value following `key` in the `def-calculus` form.
    ///
    /// # Panics
    /// When `key` is absent (test data only).
    #[must_use]
    pub fn keyword<'a>(form: &'a [Sexp], key: &str) -> &'a Sexp {
        let i = form.iter().position(|s| s.atom() == Some(key)).unwrap();
        &form[i + 1]
    }
}
