//! The algorithm registry: the `kind` written in an algorithm TOML → its [`Builder`].
//! Adding an algorithm is one file with a `build` function and one line here.
//!
//! A builder's error string should start with the offending `[params]` field followed by `: `
//! (e.g. `gf_low: ...`); the loader then points at that field's line.

use super::{buhlmann, vpmb, Builder};

/// The registered algorithms, keyed by `kind`.
pub static REGISTRY: &[(&str, Builder)] = &[("zhl16", buhlmann::build), ("vpm-b", vpmb::build)];

/// The builder registered for `kind` (case-insensitive).
pub fn builder(kind: &str) -> Option<Builder> {
    REGISTRY
        .iter()
        .find(|(k, _)| k.eq_ignore_ascii_case(kind.trim()))
        .map(|(_, b)| *b)
}

/// The registered kinds, for error messages.
pub fn kinds() -> Vec<&'static str> {
    REGISTRY.iter().map(|(k, _)| *k).collect()
}
