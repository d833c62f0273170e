//! Error classification. Library errors are typed (each module has its own `thiserror` enum);
//! they say whether the *input* was bad or the *run* failed, and only the binary turns that into
//! an exit code (FORMATS.md: 1 failure of the run, 2 bad input or usage).

/// What kind of failure an error is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The user's input (a file, a value, an argument) is wrong: exit code 2.
    BadInput,
    /// The run itself failed (device lost, solver failed, I/O): exit code 1.
    Failure,
}

/// Implemented by every library error type.
pub trait Classify {
    fn kind(&self) -> ErrorKind;
}

/// Levenshtein distance between `a` and `b` (characters), for "did you mean" lists.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for (i, ca) in a.chars().enumerate() {
        cur[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// The names `known`, nearest to `name` first (edit distance, ties in their given order),
/// back-quoted and comma-separated; past `max` of them "and N more".
pub fn nearest_first<'a>(
    name: &str,
    known: impl IntoIterator<Item = &'a str>,
    max: usize,
) -> String {
    let mut all: Vec<(usize, usize, &str)> = known
        .into_iter()
        .enumerate()
        .map(|(i, k)| (edit_distance(&name.to_lowercase(), &k.to_lowercase()), i, k))
        .collect();
    all.sort();
    all.dedup_by(|a, b| a.2 == b.2);
    let mut out: Vec<String> = all
        .iter()
        .take(max)
        .map(|(_, _, k)| format!("`{k}`"))
        .collect();
    if all.len() > max {
        out.push(format!("and {} more", all.len() - max));
    }
    out.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_listed_nearest_first() {
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("", "abc"), 3);
        let links = ["world", "panda_link0", "panda_link1", "panda_hand", "base"];
        assert_eq!(
            nearest_first("base_link", links, 3),
            // Levenshtein: base_link -> panda_link0 is 4 edits, -> base 5
            "`panda_link0`, `panda_link1`, `base`, and 2 more"
        );
        assert_eq!(
            nearest_first("panda_lnk1", links, 10).split(", ").next(),
            Some("`panda_link1`")
        );
    }
}
