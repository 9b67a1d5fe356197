#![no_main]
//! Fuzz target: the schedule TOML reader and the schedule it gives.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("toml");
    let s = decophantom::algorithm::Schedule::from_toml_str(text, &p);
    check(decophantom_fuzz::history(s, &p), &p, &[]);
});
