//! The number of band builds one tooth's stitching may make. Each build is bounded (the band's
//! size, the untangling's tests per band face), but the remedies chain builds: trims and
//! rebuilds, the crown with its slits closed, wider fringe reaches, other tangent lengths, a
//! root peeled at the cut, each up to its own limit. This caps their sum: the builds of the
//! tooth as cut and their remedies make at most [`MAX_BUILDS`] bounded builds whatever the
//! input; once they are spent no further build is started and the best build so far is kept.
//! The last two remedies, for a tooth still crossed after all of them, make new cuts of the
//! tooth (its fold trimmed farther, [`super::fold_wide`]; its CBCT tooth cut again flatter,
//! [`super::flat_cut`]) whose builds have a cap of their own each, so a tooth's stitching costs
//! at most three times [`MAX_BUILDS`] builds.
//!
//! The count lives in a thread-local: a tooth is stitched on one thread from start to end
//! ([`Scope`] starts its count), and the builds are counted where they are made
//! ([`super::assembly::assemble`]), whichever remedy asks for them.

use std::cell::Cell;

/// Band builds per tooth at most, over its builds and remedies as cut (and as many again for
/// each of the last two remedies' new cuts). On the rough phantom exports and the foreign jaws
/// a tooth takes at most 36 (median 4; a clean tooth takes one).
pub(super) const MAX_BUILDS: usize = 48;

thread_local! {
    /// Builds made by the tooth being stitched on this thread.
    static MADE: Cell<usize> = const { Cell::new(0) };
    /// The builds allowed per tooth on this thread ([`MAX_BUILDS`]; tests lower it).
    static LIMIT: Cell<usize> = const { Cell::new(MAX_BUILDS) };
    /// Builds made by the last tooth whose stitching ended on this thread.
    #[cfg(test)]
    static LAST: Cell<usize> = const { Cell::new(0) };
    /// Builds asked for on this thread in every scope (a tooth's builds with those of the scopes
    /// inside its own): what [`all_asked`] reads.
    static ALL: Cell<usize> = const { Cell::new(0) };
    /// Scopes open on this thread: the builds kept for reuse ([`super::build_memo`]) are
    /// forgotten where the outermost opens and closes.
    static DEPTH: Cell<usize> = const { Cell::new(0) };
}

/// The stitching of one tooth: starts its count of builds, and restores the count it found on
/// drop (a tooth stitched inside another's stitching, as a test may do, does not spend the
/// outer tooth's builds).
pub(super) struct Scope {
    outer: usize,
}

impl Scope {
    /// Starts counting a tooth's builds from zero.
    pub(super) fn start() -> Scope {
        if DEPTH.with(|d| d.replace(d.get() + 1)) == 0 {
            super::build_memo::clear();
        }
        Scope {
            outer: MADE.with(|m| m.replace(0)),
        }
    }
}

impl Drop for Scope {
    fn drop(&mut self) {
        let made = MADE.with(|m| m.replace(self.outer));
        if DEPTH.with(|d| d.replace(d.get() - 1)) == 1 {
            super::build_memo::clear();
        }
        #[cfg(test)]
        LAST.with(|l| l.set(made));
        #[cfg(not(test))]
        let _ = made;
    }
}

/// Counts one build asked for (made, or reused from [`super::build_memo`]).
pub(super) fn count() {
    MADE.with(|m| m.set(m.get() + 1));
    ALL.with(|a| a.set(a.get() + 1));
}

/// Builds asked for on this thread so far in every scope: the difference over a tooth's
/// stitching is every build it asked for, those of its remedies' new cuts included (less
/// [`super::build_memo::all_reused`]'s, the builds it made).
pub(super) fn all_asked() -> usize {
    ALL.with(Cell::get)
}

/// Builds made so far by the tooth being stitched.
pub(super) fn made() -> usize {
    MADE.with(Cell::get)
}

/// Whether another build may be started: the tooth has builds left and the caller's progress
/// callback has not asked to stop ([`crate::progress`]; on the calling thread it is asked here,
/// so a cancel is answered within one build).
pub(super) fn more() -> bool {
    made() < LIMIT.with(Cell::get) && crate::progress::go_on()
}

#[cfg(test)]
mod tests;
