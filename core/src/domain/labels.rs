//! Point labels interned: each distinct label stored once, in one text
//! buffer, and found by its hash — so that a file of millions of distinct
//! labels costs a few bytes beyond their text per label (no allocation of
//! its own, no second copy as a map key), and every growth is fallible.

use std::hash::BuildHasher;

use hashbrown::HashTable;

use crate::memory::{OutOfMemory, try_grow};

/// Distinct labels, numbered in order of first appearance.
///
/// ```text
/// "S1" → 0, "S2" → 1, "S1" → 0;  text "S1S2", ends [2, 4]
/// ```
#[derive(Clone, Default)]
pub(crate) struct Labels {
    /// The labels, one after another.
    text: String,
    /// Where each label ends in `text`.
    ends: Vec<usize>,
    /// Each label's number, found by the label's hash.
    table: HashTable<u32>,
    /// The hash of the table (its layout only: numbers do not depend on it).
    hasher: std::hash::RandomState,
}

impl Labels {
    /// How many distinct labels.
    pub(crate) fn len(&self) -> usize {
        self.ends.len()
    }

    /// Label number `id`.
    pub(crate) fn get(&self, id: usize) -> &str {
        label(&self.text, &self.ends, id as u32)
    }

    /// Every label, in order of first appearance.
    pub(crate) fn iter(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        (0..self.len()).map(|id| self.get(id))
    }

    /// The number of `label`, if it was seen.
    #[cfg(test)]
    fn find(&self, label: &str) -> Option<u32> {
        let hash = self.hasher.hash_one(label);
        self.table
            .find(hash, |&id| self.get(id as usize) == label)
            .copied()
    }

    /// The number of `label`, added if new; an [`OutOfMemory`] when its
    /// room cannot be had, or past 2³² labels (`what` names them).
    pub(crate) fn intern(&mut self, label: &str, what: &str) -> Result<u32, OutOfMemory> {
        let hash = self.hasher.hash_one(label);
        let (text, ends) = (&self.text, &self.ends);
        if let Some(&id) = self
            .table
            .find(hash, |&id| self::label(text, ends, id) == label)
        {
            return Ok(id);
        }
        self.push_hashed(label, hash, what)
    }

    /// Adds `label` as a new number even if it was seen: labels of points
    /// keyed by more than their label (a point touched by two tools is
    /// two points, [`super::Poses::keyed_by_tool`]). [`Labels::intern`]
    /// of such a label later finds one of its numbers.
    pub(crate) fn push_new(&mut self, label: &str, what: &str) -> Result<u32, OutOfMemory> {
        let hash = self.hasher.hash_one(label);
        self.push_hashed(label, hash, what)
    }

    /// Adds `label`, of hash `hash`, as a new number.
    fn push_hashed(&mut self, label: &str, hash: u64, what: &str) -> Result<u32, OutOfMemory> {
        let Labels {
            text,
            ends,
            table,
            hasher,
        } = self;
        let id = u32::try_from(ends.len()).map_err(|_| OutOfMemory::new(what, usize::MAX))?;
        let rehash = |&id: &u32| hasher.hash_one(self::label(text, ends, id));
        table
            .try_reserve(1, rehash)
            .map_err(|_| OutOfMemory::new(what, (table.len() + 1).saturating_mul(2 * 5)))?;
        text.try_reserve(label.len())
            .map_err(|_| OutOfMemory::new(what, text.len().saturating_add(label.len())))?;
        try_grow(ends, what, 1)?;
        text.push_str(label);
        ends.push(text.len());
        let rehash = |&id: &u32| hasher.hash_one(self::label(text, ends, id));
        table.insert_unique(hash, id, rehash);
        Ok(id)
    }
}

/// Label `id` of `text` cut at `ends`.
fn label<'a>(text: &'a str, ends: &[usize], id: u32) -> &'a str {
    let id = id as usize;
    &text[if id == 0 { 0 } else { ends[id - 1] }..ends[id]]
}

impl PartialEq for Labels {
    fn eq(&self, other: &Labels) -> bool {
        self.text == other.text && self.ends == other.ends
    }
}

impl std::fmt::Debug for Labels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_numbered_in_order_of_first_appearance() {
        let mut l = Labels::default();
        let ids: Vec<u32> = ["S1", "S2", "S1", "", "S3", "S2"]
            .iter()
            .map(|s| l.intern(s, "labels").unwrap())
            .collect();
        assert_eq!(ids, [0, 1, 0, 2, 3, 1]);
        assert_eq!(l.iter().collect::<Vec<_>>(), ["S1", "S2", "", "S3"]);
        assert_eq!((l.find("S3"), l.find("S4")), (Some(3), None));
        assert_eq!(format!("{l:?}"), r#"["S1", "S2", "", "S3"]"#);
        // Many labels: the table grows and every one is found again.
        for i in 0..10_000 {
            assert_eq!(l.intern(&format!("P{i}"), "labels").unwrap(), 4 + i);
        }
        assert_eq!(l.find("P9999"), Some(10_003));
        assert_eq!(l.get(4), "P0");
        let mut again = Labels::default();
        for s in l.iter() {
            again.intern(s, "labels").unwrap();
        }
        assert_eq!(again, l);
    }
}
