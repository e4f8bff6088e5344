//! The registry a program runs raybench with: the built-in entries plus the structures the
//! program registers itself, so a user benchmarks their own structure from their own crate
//! instead of editing raybench. Every command that looks a structure up by name (`run`,
//! `verify`, `replay`, `watertight`, `list`) reads this one value, so a registered entry is
//! built, timed, checked and reported exactly as a built-in one. Registration refuses what
//! would break a command later (a name `--structures a,b` cannot carry, a name already taken,
//! an empty description) with an error value, never a panic: the caller is a user's `main`.

use super::{StructureEntry, register, registry};
use raybench_accel::Accel;

/// The structures a program knows, in the order `list`, reports and default selections use:
/// the built-in entries first, then registered ones in the order they were added.
#[derive(Clone)]
pub struct Registry {
    entries: Vec<StructureEntry>,
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.entries.iter().map(|e| e.name))
            .finish()
    }
}

/// Why [`Registry::register`] refused an entry.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RegisterError {
    #[error("structure name `{0}` is already registered; pick another name")]
    Duplicate(String),
    #[error("a structure name must not be empty")]
    EmptyName,
    #[error(
        "structure name `{name}` {reason}: use ASCII letters, digits, `-`, `_` and `.`, \
         starting with a letter or digit, so that `--structures a,b` can name it"
    )]
    BadName { name: String, reason: &'static str },
    #[error("structure `{0}` needs a description (what it is: layout, build, traversal)")]
    EmptyDescription(String),
    #[error(
        "the description of structure `{0}` holds a control character (a line break?): \
         `raybench list` prints each description on one line"
    )]
    BadDescription(String),
}

impl Registry {
    /// Every structure raybench itself knows (ours, Embree's and, with the `peers` feature,
    /// other crates'): what the stock `raybench` binary runs with.
    pub fn builtin() -> Registry {
        Registry {
            entries: registry(),
        }
    }

    /// Adds `A`, built with `params` (written into every report as the entry's parameters,
    /// like a built-in entry's) under `name`, described by `description` in `raybench list`.
    /// The name and the description are `&'static str` like the built-in ones; a program that
    /// makes names at run time can leak them (`String::leak`), once per entry.
    pub fn register<A>(
        &mut self,
        name: &'static str,
        description: &'static str,
        params: A::Params,
    ) -> Result<&mut Registry, RegisterError>
    where
        A: Accel + 'static,
        A::Params: Send + Sync + 'static,
    {
        check_name(name)?;
        if self.entries.iter().any(|e| e.name == name) {
            return Err(RegisterError::Duplicate(name.to_string()));
        }
        if description.trim().is_empty() {
            return Err(RegisterError::EmptyDescription(name.to_string()));
        }
        if description.chars().any(char::is_control) {
            return Err(RegisterError::BadDescription(name.to_string()));
        }
        let mut entry = register::<A>(name, description, None, move |_| params.clone());
        entry.registered = true;
        self.entries.push(entry);
        Ok(self)
    }

    /// Every entry, in registry order.
    pub fn entries(&self) -> &[StructureEntry] {
        &self.entries
    }

    /// Every entry's name, in registry order: the default `--structures` of `run` and `verify`.
    pub fn names(&self) -> Vec<String> {
        self.entries.iter().map(|e| e.name.to_string()).collect()
    }

    /// Looks up names, keeping the registry order; an unknown name is an error listing the
    /// known ones.
    pub fn select(&self, names: &[String]) -> anyhow::Result<Vec<StructureEntry>> {
        if let Some(bad) = names
            .iter()
            .find(|n| !self.entries.iter().any(|e| e.name == n.as_str()))
        {
            anyhow::bail!(
                "unknown structure '{bad}'; known: {}",
                self.names().join(", ")
            );
        }
        Ok(self
            .entries
            .iter()
            .filter(|e| names.iter().any(|n| n == e.name))
            .cloned()
            .collect())
    }

    /// The entry called `name` (an error listing the known ones if there is none).
    pub fn find(&self, name: &str) -> anyhow::Result<StructureEntry> {
        Ok(self.select(&[name.to_string()])?.remove(0))
    }
}

/// A name every command can carry: `--structures` splits on commas, shells split on spaces,
/// a leading `-` reads as a flag, and names become parts of file names (pictures, dumps).
fn check_name(name: &str) -> Result<(), RegisterError> {
    let bad = |reason| {
        Err(RegisterError::BadName {
            name: name.to_string(),
            reason,
        })
    };
    let Some(first) = name.chars().next() else {
        return Err(RegisterError::EmptyName);
    };
    if !first.is_ascii_alphanumeric() {
        return bad("does not start with a letter or digit");
    }
    if name.contains(',') {
        return bad("holds a comma, which separates names in `--structures`");
    }
    if name.chars().any(char::is_whitespace) {
        return bad("holds white space");
    }
    if !name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
    {
        return bad("holds a character other than ASCII letters, digits, `-`, `_` and `.`");
    }
    Ok(())
}
