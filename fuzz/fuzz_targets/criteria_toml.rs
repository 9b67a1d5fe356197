#![no_main]
//! Fuzz target: the criteria TOML reader.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("toml");
    check(
        decophantom::risk::parse_criteria(text, &p),
        &p,
        &["no criteria"],
    );
});
