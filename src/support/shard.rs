//! Work split across machines: `--shard K/N` takes every N-th item starting at the K-th, and
//! [`merge_tables`] puts the shards' tables back together into the bytes one machine writes.
//!
//! Items are dealt out in turn rather than in blocks: the reference's cases differ in cost by an
//! order of magnitude (twilight, long horizontal rays) and lie in runs, so blocks would leave
//! one shard with all of the night. Every item's result depends on its own seed only (never on
//! which items share its shard), which is what makes a merge byte for byte the unsharded run.

use std::fmt;

/// One part of a piece of work split `count` ways (`--shard K/N`: `index` is K - 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which part, from 0.
    pub index: usize,
    /// How many parts.
    pub count: usize,
}

/// Why shards could not be merged, or a `--shard` value read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum ShardError {
    /// `--shard` is not K/N with 1 <= K <= N.
    #[error("--shard: expected K/N with 1 <= K <= N (for example 2/8), `auto` or `auto/N`, found \"{0}\"")]
    Arg(String),
    /// `--shard auto` found no job array to read its shard from.
    #[error("--shard {0}: {1}")]
    Auto(String, String),
    /// A part is not a shard's table, or does not fit with the others.
    #[error("{file}:{line}: {message}")]
    Part {
        /// The part's file.
        file: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
}

impl Shard {
    /// The whole of the work: one part.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Reads `K/N`.
    pub fn parse(s: &str) -> Result<Self, ShardError> {
        let bad = || ShardError::Arg(s.to_string());
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n): (usize, usize) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if k == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { index: k - 1, count: n })
    }

    /// Reads `K/N`, `auto` or `auto/N`, the environment read through `var`.
    ///
    /// `auto` takes the shard from the scheduler that started the process:
    /// - a Slurm job array: `SLURM_ARRAY_TASK_ID` from `SLURM_ARRAY_TASK_MIN` (1 if unset) is
    ///   shard 1, of `SLURM_ARRAY_TASK_COUNT`;
    /// - a Kubernetes indexed Job: `JOB_COMPLETION_INDEX` (from 0) is shard index + 1, of the
    ///   count given as `auto/N` (the Job's `completions`; Kubernetes does not tell it).
    pub fn parse_with(s: &str, var: impl Fn(&str) -> Option<String>) -> Result<Self, ShardError> {
        let Some(rest) = s.trim().strip_prefix("auto") else { return Self::parse(s) };
        let given: Option<usize> = match rest.strip_prefix('/') {
            Some(n) => Some(n.trim().parse().ok().filter(|n| *n > 0).ok_or_else(|| ShardError::Arg(s.to_string()))?),
            None if rest.is_empty() => None,
            None => return Err(ShardError::Arg(s.to_string())),
        };
        let auto = |why: String| ShardError::Auto(s.to_string(), why);
        let num = |name: &str| -> Result<Option<usize>, ShardError> {
            var(name).map(|v| v.trim().parse::<usize>().map_err(|_| auto(format!("{name} is \"{v}\", not a whole number")))).transpose()
        };
        let (index, count) = if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(1);
            let count = num("SLURM_ARRAY_TASK_COUNT")?.or(given).ok_or_else(|| auto("SLURM_ARRAY_TASK_COUNT is not set".into()))?;
            (id.checked_sub(min).ok_or_else(|| auto(format!("SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}")))?, count)
        } else if let Some(index) = num("JOB_COMPLETION_INDEX")? {
            (index, given.ok_or_else(|| auto("a Kubernetes indexed Job does not tell its completions: give them as auto/N".into()))?)
        } else {
            return Err(auto("neither SLURM_ARRAY_TASK_ID (a Slurm job array) nor JOB_COMPLETION_INDEX (a Kubernetes indexed Job) is set".into()));
        };
        if given.is_some_and(|n| n != count) {
            return Err(auto(format!("the job array has {count} tasks, not {}", given.unwrap_or(0))));
        }
        if index >= count {
            return Err(auto(format!("task {} of {count} is past the last shard", index + 1)));
        }
        Ok(Shard { index, count })
    }

    /// Whether this is the whole of the work.
    pub fn is_whole(self) -> bool {
        self.count == 1
    }

    /// Whether item `i` (0-based, of the whole work) is this shard's.
    pub fn owns(self, i: usize) -> bool {
        i % self.count == self.index
    }

    /// This shard's items out of `items`, in order.
    pub fn take<T: Clone>(self, items: &[T]) -> Vec<T> {
        items.iter().enumerate().filter(|(i, _)| self.owns(*i)).map(|(_, t)| t.clone()).collect()
    }

    /// The line a shard's table starts with; [`merge_tables`] reads it back. The table has
    /// `total` rows in items of `rows_per_item` (1 for a row per item), dealt out in turn by item;
    /// `inputs` names everything the rows depend on (a hash of the settings and inputs), so that
    /// a shard whose complete output is already there can be told from one of other settings.
    pub fn table_line(self, total: usize, rows_per_item: usize, inputs: u64) -> String {
        format!(
            "# skytune shard {self} of {total} rows, {rows_per_item} per item, inputs {inputs:016x} (every {}th item from item {}); combine the shards with `skytune merge`",
            self.count,
            self.index + 1
        )
    }

    /// How many of a table's `total` rows in items of `rows_per_item` are this shard's.
    fn rows_of(self, total: usize, rows_per_item: usize) -> usize {
        (0..total).filter(|i| self.owns(i / rows_per_item.max(1))).count()
    }

    /// Whether `text` is this shard's whole table for these inputs ([`Self::table_line`], its
    /// heading lines and every row): a rerun of an interrupted array may skip it.
    pub fn is_complete(self, text: &str, total: usize, rows_per_item: usize, inputs: u64) -> bool {
        let mut lines = text.lines();
        if lines.next() != Some(self.table_line(total, rows_per_item, inputs).as_str()) || !text.ends_with('\n') {
            return false;
        }
        let rest: Vec<&str> = lines.collect();
        let head = rest.iter().take_while(|l| l.starts_with('#')).count() + 1;
        rest.len() == head + self.rows_of(total, rows_per_item)
    }
}

impl std::str::FromStr for Shard {
    type Err = ShardError;

    /// `K/N`, `auto` or `auto/N` ([`Shard::parse_with`] on the process's environment).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Shard::parse_with(s, |k| std::env::var(k).ok())
    }
}

/// A hash of everything a shard's rows depend on, for [`Shard::table_line`]: the same on every
/// machine and build (FNV-1a over the bytes of `parts`).
pub fn inputs_key(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for b in part.iter().chain(&[0xff]) {
            h ^= u64::from(*b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index + 1, self.count)
    }
}

/// Reads a shard's first line: (shard, total rows, rows per item), or `None` when the text is
/// no shard's table.
fn read_table_line(line: &str) -> Option<(Shard, usize, usize)> {
    let rest = line.strip_prefix("# skytune shard ")?;
    let (shard, rest) = rest.split_once(" of ")?;
    let (total, rest) = rest.split_once(" rows")?;
    // Tables of an earlier build name no item size: a row per item.
    let per_item = match rest.strip_prefix(", ").and_then(|r| r.split_once(" per item")) {
        Some((g, _)) => g.parse().ok().filter(|g| *g > 0)?,
        None => 1,
    };
    Some((Shard::parse(shard).ok()?, total.parse().ok()?, per_item))
}

/// Whether `text` is a shard's table (as [`Shard::table_line`] starts it).
pub fn is_shard_table(text: &str) -> bool {
    text.lines().next().and_then(read_table_line).is_some()
}

/// Merges the shards of one table: each part is [`Shard::table_line`] followed by the same
/// lines the unsharded run writes before its rows (its `#` comments and the column names, equal
/// in every part: else the parts come from different settings) and then its own rows. Returns
/// the unsharded table.
pub fn merge_tables(parts: &[(String, String)]) -> Result<String, ShardError> {
    let bad = |file: &str, line: usize, message: String| ShardError::Part { file: file.into(), line, message };
    let mut read: Vec<(Shard, &str, Vec<&str>, Vec<&str>)> = Vec::new();
    let mut expected: Option<(usize, usize, usize)> = None;
    for (file, text) in parts {
        let mut lines = text.lines();
        let first = lines.next().unwrap_or("");
        let (shard, total, per_item) =
            read_table_line(first).ok_or_else(|| bad(file, 1, "not a shard's table (its first line is not \"# skytune shard K/N of M rows, G per item, ...\")".into()))?;
        match expected {
            None => expected = Some((shard.count, total, per_item)),
            Some((n, t, g)) if (n, t, g) != (shard.count, total, per_item) => {
                return Err(bad(
                    file,
                    1,
                    format!("shard {shard} of {total} rows in items of {per_item} does not fit with {}'s {n} shards of {t} rows in items of {g}", parts[0].0),
                ));
            }
            Some(_) => {}
        }
        let lines: Vec<&str> = lines.collect();
        let head_lines = lines.iter().take_while(|l| l.starts_with('#')).count() + 1;
        if lines.len() < head_lines {
            return Err(bad(file, lines.len() + 1, format!("ends before its {head_lines} heading lines")));
        }
        let (head, rows) = lines.split_at(head_lines);
        if let Some((_, other_file, other_head, _)) = read.first() {
            if let Some(k) = (0..head_lines.max(other_head.len())).find(|k| head.get(*k) != other_head.get(*k)) {
                return Err(bad(file, k + 2, format!("differs from {other_file}'s line {}: the shards were run with different settings", k + 2)));
            }
        }
        if let Some((_, other, _, _)) = read.iter().find(|(s, ..)| *s == shard) {
            return Err(bad(file, 1, format!("shard {shard} again (also {other})")));
        }
        let owned = shard.rows_of(total, per_item);
        if rows.len() != owned {
            return Err(bad(file, head_lines + 2, format!("shard {shard} of {total} rows should hold {owned} rows, found {}", rows.len())));
        }
        read.push((shard, file.as_str(), head.to_vec(), rows.to_vec()));
    }
    let (count, total, per_item) = expected.ok_or_else(|| bad("", 0, "no parts to merge".into()))?;
    if read.len() != count {
        let missing: Vec<String> = (0..count).filter(|k| !read.iter().any(|(s, ..)| s.index == *k)).map(|k| Shard { index: k, count }.to_string()).collect();
        return Err(bad(read[0].1, 1, format!("{} of {count} shards given; missing {}", read.len(), missing.join(", "))));
    }
    read.sort_by_key(|(s, ..)| s.index);
    let mut out = String::new();
    for line in &read[0].2 {
        out.push_str(line);
        out.push('\n');
    }
    for i in 0..total {
        let item = i / per_item;
        out.push_str(read[item % count].3[(item / count) * per_item + i % per_item]);
        out.push('\n');
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(shard: Shard, total: usize) -> String {
        grouped(shard, total, 1)
    }

    fn grouped(shard: Shard, total: usize, per_item: usize) -> String {
        let mut s = format!("{}\n# settings\nx,y\n", shard.table_line(total, per_item, 7));
        for i in (0..total).filter(|i| shard.owns(i / per_item)) {
            s.push_str(&format!("{i},{}\n", i * i));
        }
        s
    }

    #[test]
    fn shards_read_and_own_every_nth_item() {
        assert_eq!(Shard::parse("2/3"), Ok(Shard { index: 1, count: 3 }));
        assert!(Shard::parse("0/3").is_err() && Shard::parse("4/3").is_err() && Shard::parse("3").is_err() && Shard::parse("a/b").is_err());
        let s = Shard { index: 1, count: 3 };
        assert_eq!(s.take(&[0, 1, 2, 3, 4, 5, 6, 7]), vec![1, 4, 7]);
        assert_eq!(s.to_string(), "2/3");
    }

    #[test]
    fn auto_reads_slurm_and_kubernetes() {
        let env = |vars: &'static [(&'static str, &'static str)]| move |k: &str| vars.iter().find(|(n, _)| *n == k).map(|(_, v)| v.to_string());
        // Slurm: 1-based by default, or from the array's first index.
        assert_eq!(Shard::parse_with("auto", env(&[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_COUNT", "8")])), Ok(Shard { index: 2, count: 8 }));
        assert_eq!(
            Shard::parse_with("auto", env(&[("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_MIN", "0"), ("SLURM_ARRAY_TASK_COUNT", "4")])),
            Ok(Shard { index: 0, count: 4 })
        );
        // Kubernetes: 0-based index, the count given once.
        assert_eq!(Shard::parse_with("auto/16", env(&[("JOB_COMPLETION_INDEX", "15")])), Ok(Shard { index: 15, count: 16 }));
        let msg = Shard::parse_with("auto", env(&[("JOB_COMPLETION_INDEX", "2")])).unwrap_err().to_string();
        assert!(msg.contains("auto/N"), "{msg}");
        let msg = Shard::parse_with("auto/4", env(&[("JOB_COMPLETION_INDEX", "4")])).unwrap_err().to_string();
        assert!(msg.contains("past the last shard"), "{msg}");
        let msg = Shard::parse_with("auto", env(&[])).unwrap_err().to_string();
        assert!(msg.contains("SLURM_ARRAY_TASK_ID") && msg.contains("JOB_COMPLETION_INDEX"), "{msg}");
        // Plain K/N needs no environment.
        assert_eq!(Shard::parse_with("1/2", env(&[("JOB_COMPLETION_INDEX", "1")])), Ok(Shard { index: 0, count: 2 }));
    }

    #[test]
    fn a_complete_part_is_recognised_and_a_cut_one_is_not() {
        let s = Shard { index: 1, count: 3 };
        let t = table(s, 10);
        assert!(s.is_complete(&t, 10, 1, 7));
        assert!(!s.is_complete(&t, 10, 1, 8), "other inputs");
        assert!(!Shard { index: 0, count: 3 }.is_complete(&t, 10, 1, 7), "another shard");
        let cut = &t[..t.len() - 4];
        assert!(!s.is_complete(cut, 10, 1, 7));
        let fewer: String = t.lines().take(t.lines().count() - 1).map(|l| format!("{l}\n")).collect();
        assert!(!s.is_complete(&fewer, 10, 1, 7));
        assert_ne!(inputs_key(&[b"a", b"bc"]), inputs_key(&[b"ab", b"c"]));
    }

    #[test]
    fn merged_shards_are_the_whole_table() {
        let whole = {
            let mut s = String::from("# settings\nx,y\n");
            for i in 0..10 {
                s.push_str(&format!("{i},{}\n", i * i));
            }
            s
        };
        let parts: Vec<(String, String)> = [2, 0, 1].iter().map(|k| (format!("part{k}"), table(Shard { index: *k, count: 3 }, 10))).collect();
        assert_eq!(merge_tables(&parts).as_deref(), Ok(whole.as_str()));
        // Items of 4 rows each (the last one short), dealt out by item.
        let parts: Vec<(String, String)> = [1, 2, 0].iter().map(|k| (format!("part{k}"), grouped(Shard { index: *k, count: 3 }, 10, 4))).collect();
        assert_eq!(merge_tables(&parts).as_deref(), Ok(whole.as_str()));
    }

    #[test]
    fn a_missing_or_mismatched_shard_is_named() {
        let a = ("a.csv".to_string(), table(Shard { index: 0, count: 3 }, 10));
        let b = ("b.csv".to_string(), table(Shard { index: 1, count: 3 }, 10));
        let msg = merge_tables(&[a.clone(), b.clone()]).unwrap_err().to_string();
        assert!(msg.contains("missing 3/3"), "{msg}");
        let other = ("c.csv".to_string(), table(Shard { index: 2, count: 3 }, 10).replace("# settings", "# other settings"));
        let msg = merge_tables(&[a.clone(), b.clone(), other]).unwrap_err().to_string();
        assert!(msg.starts_with("c.csv:2:"), "{msg}");
        let msg = merge_tables(&[a.clone(), a]).unwrap_err().to_string();
        assert!(msg.contains("again"), "{msg}");
    }
}
