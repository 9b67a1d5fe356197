//! Report of discover.
