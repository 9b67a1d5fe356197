//! Gases and breathing/chamber mixes. Gases are a list, never a hard-coded pair:
//! every field, bubble and boundary condition loops over the gases present.

use serde::{Deserialize, Serialize};

/// A gas the model transports. Oxygen is carried as an inert diffusing gas in the
/// phantom (no metabolism: the gels are acellular, the paper's section 2.1.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Gas {
    /// Nitrogen.
    N2,
    /// Oxygen.
    O2,
    /// Helium.
    He,
}

impl Gas {
    /// All gases in a fixed order (used for column order in outputs).
    pub const ALL: [Gas; 3] = [Gas::N2, Gas::O2, Gas::He];

    /// Short lower-case name used in TOML keys and CSV columns (`n2`, `o2`, `he`).
    pub fn name(self) -> &'static str {
        match self {
            Gas::N2 => "n2",
            Gas::O2 => "o2",
            Gas::He => "he",
        }
    }

    /// Parse `n2`, `o2`, `he` (case-insensitive).
    pub fn parse(s: &str) -> Option<Gas> {
        match s.trim().to_ascii_lowercase().as_str() {
            "n2" | "nitrogen" => Some(Gas::N2),
            "o2" | "oxygen" => Some(Gas::O2),
            "he" | "helium" => Some(Gas::He),
            _ => None,
        }
    }
}

/// A breathing or chamber gas as volume (= mole) fractions. N2 is the balance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GasMix {
    /// Oxygen fraction, 0..1.
    pub o2: f64,
    /// Helium fraction, 0..1.
    pub he: f64,
}

impl GasMix {
    /// Air as 21 % O2, 79 % N2 (argon lumped with N2, as dive planners do).
    pub const AIR: GasMix = GasMix { o2: 0.21, he: 0.0 };

    /// A mix from fractions; errors if they are outside 0..1 or sum above 1.
    pub fn new(o2: f64, he: f64) -> Result<GasMix, String> {
        if !(0.0..=1.0).contains(&o2) || !(0.0..=1.0).contains(&he) || o2 + he > 1.0 + 1e-12 {
            return Err(format!(
                "gas fractions O2 {o2} and He {he} must each be in 0..1 and sum to at most 1"
            ));
        }
        Ok(GasMix { o2, he })
    }

    /// Nitrogen fraction (the balance).
    pub fn n2(&self) -> f64 {
        (1.0 - self.o2 - self.he).max(0.0)
    }

    /// Fraction of one gas.
    pub fn fraction(&self, gas: Gas) -> f64 {
        match gas {
            Gas::N2 => self.n2(),
            Gas::O2 => self.o2,
            Gas::He => self.he,
        }
    }

    /// Parse `air`, `oxygen`/`o2`, `ean32`/`nx32`/`32` (nitrox percent), `18/45` (trimix O2/He
    /// percent) or `tx18/45`.
    pub fn parse(s: &str) -> Result<GasMix, String> {
        let t = s.trim().to_ascii_lowercase();
        let bad = || {
            format!("cannot read gas '{s}': write air, oxygen, ean32 (nitrox %O2), 32, or 18/45 (trimix %O2/%He)")
        };
        if t == "air" {
            return Ok(GasMix::AIR);
        }
        if t == "oxygen" || t == "o2" {
            return Ok(GasMix { o2: 1.0, he: 0.0 });
        }
        let body = t
            .trim_start_matches("ean")
            .trim_start_matches("nx")
            .trim_start_matches("tx")
            .trim_start_matches("tmx");
        let pct = |x: &str| x.trim().parse::<f64>().map_err(|_| bad());
        let (o2, he) = match body.split_once('/') {
            Some((a, b)) => (pct(a)?, pct(b)?),
            None => (pct(body)?, 0.0),
        };
        GasMix::new(o2 / 100.0, he / 100.0).map_err(|e| format!("gas '{s}': {e}"))
    }

    /// Gases with a non-zero fraction, in [`Gas::ALL`] order.
    pub fn present(&self) -> Vec<Gas> {
        Gas::ALL
            .into_iter()
            .filter(|g| self.fraction(*g) > 0.0)
            .collect()
    }

    /// A short label: `air`, `EAN32`, `18/45`, `O2`.
    pub fn label(&self) -> String {
        let o = (self.o2 * 100.0).round() as i64;
        let h = (self.he * 100.0).round() as i64;
        if h > 0 {
            format!("{o}/{h}")
        } else if o == 21 {
            "air".into()
        } else if o == 100 {
            "O2".into()
        } else {
            format!("EAN{o}")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn parses_common_mixes() {
        assert_eq!(GasMix::parse("air").unwrap(), GasMix::AIR);
        let t = GasMix::parse("18/45").unwrap();
        assert!((t.o2 - 0.18).abs() < 1e-12 && (t.he - 0.45).abs() < 1e-12);
        assert!((t.n2() - 0.37).abs() < 1e-12);
        assert!((GasMix::parse("EAN32").unwrap().o2 - 0.32).abs() < 1e-12);
        assert!(GasMix::parse("60/60").is_err());
        assert!(GasMix::parse("foo").is_err());
        assert_eq!(GasMix::parse("50").unwrap().label(), "EAN50");
    }
}
