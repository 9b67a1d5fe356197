#![no_main]
//! Fuzz target: the legacy two-column reader (min, msw), also as a schedule.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("txt");
    use decophantom::profile::legacy::{parse, LegacyUnits};
    use decophantom::units::{PressureUnit, TimeUnit};
    check(
        parse(
            text,
            &p,
            &LegacyUnits::new(TimeUnit::Min, PressureUnit::Msw),
        ),
        &p,
        &[],
    );
});
