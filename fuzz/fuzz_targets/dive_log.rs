#![no_main]
//! Fuzz target: the Subsurface XML and UDDF reader, and every dive as a history.
use decophantom_fuzz::{check, path};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let p = path("xml");
    let r = decophantom::profile::divelog::parse(text, &p).and_then(|dives| {
        for d in &dives {
            decophantom::profile::dive_log_history(d, 0.0, decophantom::profile::DIVE_LOG_WATCH_S)
                .map_err(|e| e.in_file(&p))?;
        }
        Ok(())
    });
    check(r, &p, &[]);
});
