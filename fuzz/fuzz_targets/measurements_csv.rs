#![no_main]
//! Fuzz target: the measurements CSV reader.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("csv");
    check(
        decophantom::fit::data::parse_measurements(text, &p),
        &p,
        &[],
    );
});
