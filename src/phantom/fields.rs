//! The gel's dissolved-gas concentration fields, one per gas (mol/m³ per cell, in the grid's
//! cell order), in stores with room for the explicit step that moves the field by two planes
//! instead of copying a plane (session 24, [`super::diffusion::explicit_steps_shifting_per_field`]).
//!
//! A field is always read and written through its view, `fields[g]`: the grid's cells, in
//! order. Behind it, each field's store may hold two planes more, and the view starts at plane
//! 0 or plane 2 of it ([`Fields::offset_planes`]). Every field has the same offset.
//!
//! Invariant: every cell that is not inside the gel (outside the shape, or taken by a bubble)
//! holds 0 in every field: the initial fields are 0 there, and a cell a bubble takes is set to
//! 0. The shifting step relies on it. It writes a plane's inside cells into a store plane that
//! held another plane; the cells outside the shape are the same in every plane (shapes are
//! prisms along z), so they keep that plane's zeros, and in a plane with cells taken by bubbles
//! the step sets every cell not inside to 0 (`diffusion::zero_excluded`).

use std::ops::{Index, IndexMut};

/// The concentration fields of a simulation (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Fields {
    store: Vec<Vec<f64>>,
    /// Cells of the grid (every view's length).
    cells: usize,
    /// Cells of a z-plane.
    plane: usize,
    /// Where the views start in the stores, in planes: 0 or 2.
    offset: usize,
}

impl Fields {
    /// Fields from one vector per gas, each a whole grid of `plane`-cell z-planes.
    ///
    /// # Panics
    /// If the vectors differ in length or a plane has no cell.
    pub fn new(fields: Vec<Vec<f64>>, plane: usize) -> Fields {
        assert!(plane > 0, "a plane has cells");
        let cells = fields.first().map_or(0, Vec::len);
        assert!(
            fields.iter().all(|f| f.len() == cells),
            "fields of one grid"
        );
        Fields {
            store: fields,
            cells,
            plane,
            offset: 0,
        }
    }

    /// Number of fields (gases).
    pub fn len(&self) -> usize {
        self.store.len()
    }

    /// Whether there is no field.
    pub fn is_empty(&self) -> bool {
        self.store.is_empty()
    }

    /// Each field's view, in gas order.
    pub fn iter(&self) -> impl Iterator<Item = &[f64]> {
        let (a, b) = self.view_range();
        self.store.iter().map(move |f| &f[a..b])
    }

    /// Each field's view, mutable.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut [f64]> {
        let (a, b) = self.view_range();
        self.store.iter_mut().map(move |f| &mut f[a..b])
    }

    /// The views, collected.
    pub fn slices(&self) -> Vec<&[f64]> {
        self.iter().collect()
    }

    /// The mutable views, collected.
    pub fn slices_mut(&mut self) -> Vec<&mut [f64]> {
        self.iter_mut().collect()
    }

    /// A copy of every view.
    pub fn to_vecs(&self) -> Vec<Vec<f64>> {
        self.iter().map(<[f64]>::to_vec).collect()
    }

    /// Where the views start in the stores, in planes (0 or 2).
    pub fn offset_planes(&self) -> usize {
        self.offset
    }

    /// The views' range in the stores, [a, b).
    pub(super) fn view_range(&self) -> (usize, usize) {
        let a = self.offset * self.plane;
        (a, a + self.cells)
    }

    /// The whole stores, each grown to two planes more than the grid (new planes zero), and
    /// the views' offset in planes, for a shifting step; [`Self::shifted`] then sets the new
    /// offset.
    pub fn stores_for_shift(&mut self) -> (Vec<&mut [f64]>, usize) {
        let len = self.cells + 2 * self.plane;
        for f in &mut self.store {
            if f.len() < len {
                f.resize(len, 0.0);
            }
        }
        let stores = self.store.iter_mut().map(|f| &mut f[..len]).collect();
        (stores, self.offset)
    }

    /// After a shifting step: the views start at plane `offset` (0 or 2).
    pub fn shifted(&mut self, offset: usize) {
        assert!(offset == 0 || offset == 2, "a shift of 0 or 2 planes");
        self.offset = offset;
    }

    /// Field `g`'s whole store (its view is `[a, a + cells)` of it, a = [`Self::offset_planes`]
    /// × the plane's cells).
    pub(super) fn store(&self, g: usize) -> &[f64] {
        &self.store[g]
    }

    /// Exchange field `g`'s store with `other`, a vector of the store's length laid out as it
    /// (the same offset): field `g`'s view is then `other`'s cells at the views' range.
    pub(super) fn swap_store(&mut self, g: usize, other: &mut Vec<f64>) {
        assert_eq!(
            other.len(),
            self.store[g].len(),
            "a store of field {g}'s length"
        );
        std::mem::swap(&mut self.store[g], other);
    }

    /// Exchange the stores with `back` (one vector of at least a grid's cells per field, the
    /// grid's cells from its start): the views are then `back`'s first cells, and `back` holds
    /// the old stores.
    pub(super) fn swap_stores(&mut self, back: &mut Vec<Vec<f64>>) {
        assert!(
            back.len() == self.store.len() && back.iter().all(|f| f.len() >= self.cells),
            "a second set of fields of the grid"
        );
        std::mem::swap(&mut self.store, back);
        self.offset = 0;
    }
}

impl Index<usize> for Fields {
    type Output = [f64];

    fn index(&self, g: usize) -> &[f64] {
        let (a, b) = self.view_range();
        &self.store[g][a..b]
    }
}

impl IndexMut<usize> for Fields {
    fn index_mut(&mut self, g: usize) -> &mut [f64] {
        let (a, b) = self.view_range();
        &mut self.store[g][a..b]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The views follow the offset; growing the stores keeps the view; a swap starts the views
    /// at the new stores' start.
    #[test]
    fn views_follow_the_offset_and_the_swap() {
        let plane = 4;
        let a: Vec<f64> = (0..12).map(f64::from).collect();
        let b: Vec<f64> = (100..112).map(f64::from).collect();
        let mut f = Fields::new(vec![a.clone(), b.clone()], plane);
        assert_eq!((f.len(), f.offset_planes()), (2, 0));
        assert_eq!(&f[0], &a[..]);
        let (stores, off) = f.stores_for_shift();
        assert_eq!(off, 0);
        assert!(stores.iter().all(|s| s.len() == 12 + 2 * plane));
        // the view is unchanged by the growth
        assert_eq!(&f[1], &b[..]);
        // a store whose view starts two planes in
        let (mut stores, _) = f.stores_for_shift();
        for (s, src) in stores.iter_mut().zip([&a, &b]) {
            s[2 * plane..].copy_from_slice(src);
        }
        f.shifted(2);
        assert_eq!(f.to_vecs(), vec![a.clone(), b.clone()]);
        f[0][3] = -1.0;
        assert_eq!(f.iter().next().unwrap()[3], -1.0);
        let mut back = vec![vec![7.0; 12], vec![8.0; 12]];
        f.swap_stores(&mut back);
        assert_eq!((f.offset_planes(), f[1][0]), (0, 8.0));
        assert_eq!(back[0][2 * plane + 3], -1.0);
    }

    /// One field's store exchanged at an offset of two planes: its view is the new store's
    /// cells at the same range, the other field and the offset untouched.
    #[test]
    fn one_store_swaps_at_the_offset() {
        let plane = 4;
        let a: Vec<f64> = (0..12).map(f64::from).collect();
        let b: Vec<f64> = (100..112).map(f64::from).collect();
        let mut f = Fields::new(vec![a, b], plane);
        let _ = f.stores_for_shift();
        f.shifted(2);
        let (lo, hi) = f.view_range();
        assert_eq!((lo, hi), (2 * plane, 2 * plane + 12));
        let mut other: Vec<f64> = (0..12 + 2 * plane).map(|i| -(i as f64)).collect();
        let want: Vec<f64> = other[lo..hi].to_vec();
        let (before, second) = (f[0].to_vec(), f[1].to_vec());
        f.swap_store(0, &mut other);
        assert_eq!((&f[0], f.offset_planes()), (&want[..], 2));
        assert_eq!(f.store(0).len(), 12 + 2 * plane);
        assert_eq!(&other[lo..hi], &before[..]);
        assert_eq!(&f[1], &second[..]);
    }
}
