#![no_main]
//! Fuzz target: the TOML profile reader.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("toml");
    check(decophantom::profile::toml::parse(text, &p), &p, &[]);
});
