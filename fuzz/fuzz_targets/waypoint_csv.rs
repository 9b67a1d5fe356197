#![no_main]
//! Fuzz target: the waypoint CSV reader and the schedule it gives.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("csv");
    let s = decophantom::algorithm::waypoints::parse_waypoints_csv(
        text,
        &p,
        &decophantom::algorithm::conventions::DECOTENGU,
        decophantom::gas::GasMix::AIR,
    );
    check(decophantom_fuzz::history(s, &p), &p, &[]);
});
