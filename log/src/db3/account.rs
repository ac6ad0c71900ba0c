//! Accounting for the rows of one `.db3` file: the completeness check that replaces SQLite's
//! `PRAGMA quick_check` where the bag's metadata counts the file's messages.
//!
//! rosbag2 (and `rosbags`) insert messages without an explicit id, so SQLite numbers a file's
//! rows `1, 2, …, N` in insertion order, and the metadata records `N` per file (`files[i].
//! message_count`). The reading thread walks the time index and fetches each row from the table
//! (a row the index names but the table lacks is an SQLite error), or for the audit walks the
//! table itself in its own order (then the index is not read at all); a row the index lacks, a
//! subtree read twice, or a table holding rows the metadata does not count shows here as an id
//! missing, repeated or out of `1..=N`. When every id `1..=N` is read exactly once — and the
//! table's own largest id, found through the table's b-tree rather than the index, is `N` — no
//! row was lost or repeated on the way, which is what the audit needs from the file's structure
//! (SQLite keeps no checksums: `quick_check` does not vouch for the bytes of a payload either).
//!
//! Where accounting is not possible (no count in the metadata, a largest id other than the
//! count, more than [`MAX_ACCOUNTED_ROWS`] rows) the file is checked with `quick_check` before it
//! is read, as before; where accounting fails after reading (rows deleted by an editing tool
//! leave gaps, for instance) `quick_check` runs then, and a damaged file is an error. Either way a
//! file is read completely or the audit ends in an error, never in a verdict on part of it.

/// Most rows a file may have for the accounting (one bit each: 16 MiB); larger files are checked
/// by `quick_check` instead, so memory stays bounded.
pub(super) const MAX_ACCOUNTED_ROWS: u64 = 1 << 27;

/// The ids seen of a file expected to hold rows `1..=n`.
#[derive(Debug)]
pub(super) struct RowAccount {
    n: u64,
    seen: Vec<u64>,
    count: u64,
    /// An id outside `1..=n`, or one seen twice.
    broken: bool,
}

impl RowAccount {
    /// Accounting for rows `1..=n`, or `None` above [`MAX_ACCOUNTED_ROWS`].
    pub(super) fn new(n: u64) -> Option<Self> {
        if n > MAX_ACCOUNTED_ROWS {
            return None;
        }
        Some(Self {
            n,
            seen: vec![0; n.div_ceil(64) as usize],
            count: 0,
            broken: false,
        })
    }

    /// Note one row read.
    pub(super) fn see(&mut self, id: i64) {
        let Some(k) = u64::try_from(id)
            .ok()
            .filter(|&i| i >= 1 && i <= self.n)
            .map(|i| i - 1)
        else {
            self.broken = true;
            return;
        };
        let (word, bit) = ((k / 64) as usize, 1u64 << (k % 64));
        if self.seen[word] & bit != 0 {
            self.broken = true;
        }
        self.seen[word] |= bit;
        self.count += 1;
    }

    /// Rows read.
    pub(super) fn read(&self) -> u64 {
        self.count
    }

    /// Rows the metadata counts (`n`).
    pub(super) fn expected(&self) -> u64 {
        self.n
    }

    /// Whether exactly the ids `1..=n` were seen, each once.
    pub(super) fn complete(&self) -> bool {
        !self.broken && self.count == self.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift).
    fn next(x: &mut u64) -> u64 {
        *x ^= *x << 13;
        *x ^= *x >> 7;
        *x ^= *x << 17;
        *x
    }

    #[test]
    fn every_id_once_in_any_order_is_complete() {
        let mut x = 0x1234_5678_9abc_def1u64;
        for case in 0..2000 {
            let n = next(&mut x) % 300;
            let mut ids: Vec<i64> = (1..=n as i64).collect();
            for i in (1..ids.len()).rev() {
                ids.swap(i, (next(&mut x) % (i as u64 + 1)) as usize);
            }
            let mut a = RowAccount::new(n).unwrap();
            for &id in &ids {
                a.see(id);
            }
            assert!(a.complete(), "case {case}: n = {n}");
        }
    }

    #[test]
    fn a_missing_repeated_or_foreign_id_is_never_complete() {
        let mut x = 0x0fed_cba9_8765_4321u64;
        for case in 0..3000 {
            let n = 1 + next(&mut x) % 300;
            let mut ids: Vec<i64> = (1..=n as i64).collect();
            for i in (1..ids.len()).rev() {
                ids.swap(i, (next(&mut x) % (i as u64 + 1)) as usize);
            }
            let at = (next(&mut x) % n) as usize;
            match case % 4 {
                // One row lost.
                0 => {
                    ids.remove(at);
                }
                // One row read twice, another lost (the count is right).
                1 => {
                    let other = ids[(at + 1) % ids.len()];
                    ids[at] = other;
                    if n == 1 {
                        ids.push(other);
                    }
                }
                // A row the metadata does not count.
                2 => ids.push(n as i64 + 1 + (next(&mut x) % 5) as i64),
                // An id SQLite never assigns by itself (0 or negative) in place of one.
                _ => ids[at] = -((next(&mut x) % 3) as i64),
            }
            let mut a = RowAccount::new(n).unwrap();
            for &id in &ids {
                a.see(id);
            }
            assert!(!a.complete(), "case {case}: n = {n}, ids {ids:?}");
        }
    }

    #[test]
    fn no_accounting_above_the_cap() {
        assert!(RowAccount::new(MAX_ACCOUNTED_ROWS).is_some());
        assert!(RowAccount::new(MAX_ACCOUNTED_ROWS + 1).is_none());
        assert!(RowAccount::new(0).unwrap().complete());
    }
}
