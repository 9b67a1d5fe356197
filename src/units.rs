//! Physical constants and unit conversions. SI inside the library; everything a
//! person writes (bar, psi, msw, fsw, minutes) is converted at the edges with these.

/// Universal gas constant R_u, J/(mol·K). Source: CODATA 2018 (exact since the 2019 SI redefinition).
pub const GAS_CONSTANT: f64 = 8.314_462_618;
/// One standard atmosphere, Pa. Source: ISO 2533 / BIPM SI brochure (exact).
pub const ATM_PA: f64 = 101_325.0;
/// One bar, Pa (exact, SI brochure).
pub const BAR_PA: f64 = 100_000.0;
/// One pound-force per square inch, Pa. Source: NIST SP 811, B.8 (6.894 757 E+03).
pub const PSI_PA: f64 = 6_894.757_293_168;
/// Standard gravity, m/s² (exact, CGPM 1901).
pub const STANDARD_GRAVITY: f64 = 9.806_65;
/// One metre of sea water as used by the US Navy and Baker's VPM-B code: 1 atm per 10.1325 msw,
/// i.e. 10 000 Pa per msw. Source: US Navy Diving Manual rev. 7, table 2-10 (1 msw = 0.1 bar nominal).
pub const MSW_PA: f64 = 10_000.0;
/// One foot of sea water, Pa: 1 atm = 33 fsw (US Navy Diving Manual rev. 7, §2-9).
pub const FSW_PA: f64 = ATM_PA / 33.0;
/// Body/incubation temperature of the gels, K (37 °C, the paper's section 3.2).
pub const BODY_TEMPERATURE_K: f64 = 310.15;

/// One millimetre of mercury (torr), Pa: 101 325/760 (exact by definition of the torr; the
/// physiology texts below give partial pressures in mmHg).
pub const MMHG_PA: f64 = ATM_PA / 760.0;
/// Water-vapour pressure in the lungs and tissue at 37 °C, Pa: 47 mmHg = 6.27 kPa (saturated
/// vapour at body temperature). Sources: Guyton & Hall, *Textbook of Medical Physiology*, 13th
/// ed., ch. 40 (alveolar air: P_H2O 47 mmHg); West, *Respiratory Physiology: The Essentials*,
/// 9th ed., ch. 1 and 3. Bühlmann and DecoTengu use 0.0627 bar.
pub const BODY_WATER_VAPOUR_PA: f64 = 6_270.0;
/// Partial pressure of CO2 in a bubble in tissue, Pa: 5.3 kPa (40 mmHg, the alveolar and
/// arterial PCO2; mixed venous is 45–46 mmHg = 6.0–6.1 kPa). Sources: Guyton & Hall, 13th ed.,
/// ch. 40–41 (alveolar PCO2 40 mmHg, venous 45 mmHg); West, 9th ed., ch. 5 and 6. 5.3 kPa is the
/// figure of the usual oxygen-window arithmetic; `[protocol] co2_pa` changes it.
pub const TISSUE_CO2_PA: f64 = 5_300.0;
/// Partial pressure of O2 in a bubble in metabolising tissue, Pa: 5.3 kPa (40 mmHg, the
/// mixed-venous PO2 breathing air at 1 atm). Sources: Guyton & Hall, 13th ed., ch. 41 (venous
/// PO2 40 mmHg); West, 9th ed., ch. 6 (mixed venous PO2 40 mmHg).
pub const VENOUS_O2_PA: f64 = 5_300.0;

/// Pressure units accepted in profiles and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PressureUnit {
    /// Absolute pascal.
    Pa,
    /// Absolute kilopascal.
    Kpa,
    /// Absolute bar.
    Bar,
    /// Absolute atmospheres.
    Atm,
    /// Gauge psi: absolute = surface + value · PSI_PA (the paper's chamber profiles).
    PsiGauge,
    /// Absolute psi.
    Psia,
    /// Metres of sea water (depth): absolute = surface + value · MSW_PA.
    Msw,
    /// Feet of sea water (depth): absolute = surface + value · FSW_PA.
    Fsw,
}

impl PressureUnit {
    /// Convert a value in this unit to absolute Pa, given the surface (chamber-zero) pressure in Pa.
    pub fn to_absolute_pa(self, value: f64, surface_pa: f64) -> f64 {
        match self {
            PressureUnit::Pa => value,
            PressureUnit::Kpa => value * 1e3,
            PressureUnit::Bar => value * BAR_PA,
            PressureUnit::Atm => value * ATM_PA,
            PressureUnit::PsiGauge => surface_pa + value * PSI_PA,
            PressureUnit::Psia => value * PSI_PA,
            PressureUnit::Msw => surface_pa + value * MSW_PA,
            PressureUnit::Fsw => surface_pa + value * FSW_PA,
        }
    }

    /// Parse the name used in TOML and on the command line (`pa`, `kpa`, `bar`, `atm`,
    /// `psi-gauge` (alias `psig`, `psi`), `psia`, `msw`, `fsw`).
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "pa" => PressureUnit::Pa,
            "kpa" => PressureUnit::Kpa,
            "bar" => PressureUnit::Bar,
            "atm" => PressureUnit::Atm,
            "psi-gauge" | "psig" | "psi" => PressureUnit::PsiGauge,
            "psia" => PressureUnit::Psia,
            "msw" | "m" => PressureUnit::Msw,
            "fsw" | "ft" => PressureUnit::Fsw,
            _ => return None,
        })
    }
}

/// Time units accepted in profiles and on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TimeUnit {
    /// Seconds.
    S,
    /// Minutes.
    Min,
    /// Hours.
    H,
}

impl TimeUnit {
    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Min => 60.0,
            TimeUnit::H => 3600.0,
        }
    }
    /// Parse `s`/`sec`, `min`, `h`.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "s" | "sec" | "second" | "seconds" => TimeUnit::S,
            "min" | "minute" | "minutes" => TimeUnit::Min,
            "h" | "hour" | "hours" => TimeUnit::H,
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn paper_130_psi_gauge_is_about_1e6_pa_absolute() {
        // The issue: "130 psi gauge ≈ 1.0e6 Pa absolute".
        let p = PressureUnit::PsiGauge.to_absolute_pa(130.0, ATM_PA);
        assert!((p - 9.976e5).abs() < 1e3, "{p}");
    }
}
