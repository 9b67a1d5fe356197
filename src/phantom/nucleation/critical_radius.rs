//! `critical-radius`: a seeded population of sub-grid gas micronuclei that activate into
//! bubbles where the gel's supersaturation exceeds their Laplace pressure 2γ/r (eq. 2.11 of
//! the paper, read for a given radius: a nucleus grows when its radius is above the critical
//! radius R_c = 2γ/P_ss).
//!
//! Sizes follow Yount's varying-permeability model (VPM): the number of nuclei per unit
//! volume with radius above r is exponential, N(>r) = N₀·e^(−βr) (Yount 1979, "Skins of varying
//! permeability: a stabilization mechanism for gas cavitation nuclei", J. Acoust. Soc. Am. 65,
//! 1429–1439; Yount & Hoffman 1986, "On the use of a bubble formation model to calculate
//! diving tables", Aviat. Space Environ. Med. 57, 149–156), so radii are drawn from the
//! exponential density β·e^(−βr) and the fraction of nuclei that a uniform supersaturation
//! P_ss activates is e^(−β·2γ/P_ss). A log-normal size distribution is the alternative (σ = 0:
//! every nucleus the same radius). Positions are uniform over the phantom's cells (no closer
//! than `margin_m` to a face), drawn with ChaCha8 from `seed`.
//!
//! No numerical default is given for N₀, β or the log-normal parameters: neither the paper nor
//! VPM fits them to this gel (the paper's §4.2.1 and §6 name that fit as the open problem),
//! so a phantom file states them. The VPM's own critical radii (0.55 µm for N2, 0.45 µm for
//! He in VPM-B, `src/algorithm/vpmb/mod.rs`) give the scale of 1/β.
//!
//! TOML:
//! ```toml
//! [nucleation]
//! model = "critical-radius"
//! number_density_per_m3 = 1e9   # N₀, nuclei of any size per m³ of gel (required)
//! distribution = "exponential"  # or "log-normal"; default exponential
//! slope_per_m = 2e6             # β, 1/m (exponential; required): mean radius 1/β = 0.5 µm
//! # median_radius_m = 0.5e-6    # log-normal: median radius, m (required)
//! # sigma = 0.5                 # log-normal: σ of ln r (required; 0 = monodisperse)
//! margin_m = 0.2e-3             # no nucleus closer to a face, m; default one grid step h
//! seed = 2017                   # ChaCha8 seed (required)
//! # skin_compression = 0.257    # γc, N/m: VPM skins and crushing (Yount 1979); omit for bare
//! #                             # nuclei (threshold 2γ/r). See the parent module.
//! ```

use super::{raw, NucleationError, NucleationModel, Nucleus};
use crate::phantom::grid::Grid;
use rand::distributions::Open01;
use rand::{Rng, SeedableRng};
use serde::Deserialize;

/// Most nuclei a phantom may hold (N₀ × the gel volume).
pub const MAX_NUCLEI: usize = 1_000_000;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    number_density_per_m3: f64,
    distribution: Option<String>,
    slope_per_m: Option<f64>,
    median_radius_m: Option<f64>,
    sigma: Option<f64>,
    margin_m: Option<f64>,
    seed: u64,
    skin_compression: Option<f64>,
}

/// The size distribution of the nuclei's radii.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SizeDistribution {
    /// Density β·e^(−βr) (Yount's VPM): β in 1/m, mean radius 1/β.
    Exponential {
        /// β, 1/m.
        slope: f64,
    },
    /// ln r normal with median `median` (m) and standard deviation `sigma`.
    LogNormal {
        /// Median radius, m.
        median: f64,
        /// σ of ln r (0: every nucleus `median`).
        sigma: f64,
    },
}

impl SizeDistribution {
    /// Fraction of nuclei with radius above `r` (m): e^(−βr), or the log-normal tail.
    pub fn fraction_above(&self, r: f64) -> f64 {
        match *self {
            SizeDistribution::Exponential { slope } => (-slope * r.max(0.0)).exp(),
            SizeDistribution::LogNormal { median, sigma } => {
                if sigma == 0.0 {
                    return if median > r { 1.0 } else { 0.0 };
                }
                let z = (r / median).ln() / sigma;
                0.5 * statrs::function::erf::erfc(z / std::f64::consts::SQRT_2)
            }
        }
    }

    fn draw(&self, rng: &mut impl Rng) -> f64 {
        match *self {
            SizeDistribution::Exponential { slope } => {
                let u: f64 = rng.sample(Open01);
                -u.ln() / slope
            }
            SizeDistribution::LogNormal { median, sigma } => {
                // Box–Muller: one standard normal from two uniforms on (0, 1)
                let (u1, u2): (f64, f64) = (rng.sample(Open01), rng.sample(Open01));
                let z = (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos();
                median * (sigma * z).exp()
            }
        }
    }
}

/// The validated `critical-radius` model (SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CriticalRadius {
    /// N₀: nuclei of any size per m³ of gel. The phantom holds round(N₀ × its gel volume).
    pub number_density: f64,
    /// Radii.
    pub distribution: SizeDistribution,
    /// Smallest distance from a nucleus to any face, m; `None`: one grid step.
    pub margin: Option<f64>,
    /// ChaCha8 seed.
    pub seed: u64,
    /// γc, N/m: VPM skin compression (Yount 1979: 0.257 N/m); `None`: bare nuclei.
    pub skin_compression: Option<f64>,
}

impl CriticalRadius {
    /// Number of nuclei in `grid`: round(N₀ × inside cells × h³).
    pub fn count(&self, grid: &Grid) -> f64 {
        (self.number_density * grid.n_inside as f64 * grid.cell_volume()).round()
    }
}

impl NucleationModel for CriticalRadius {
    fn name(&self) -> &'static str {
        "critical-radius"
    }

    fn nuclei(&self, grid: &Grid) -> Result<Vec<Nucleus>, NucleationError> {
        let count = self.count(grid);
        if count > MAX_NUCLEI as f64 {
            return Err(NucleationError::new(
                "number_density_per_m3",
                format!(
                    "{count:.0} nuclei in this phantom is too many (limit {MAX_NUCLEI}); lower the density"
                ),
            ));
        }
        let count = count as usize;
        let margin = self.margin.unwrap_or(grid.h);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.seed);
        let e = grid.extent();
        let mut out = Vec::with_capacity(count);
        let mut tries = 0usize;
        while out.len() < count {
            tries += 1;
            if tries > 1000 + 100 * count {
                return Err(NucleationError::new(
                    "margin_m",
                    format!(
                        "cannot place nuclei {margin} m from every face: the phantom has almost no gel that far in"
                    ),
                ));
            }
            let p = [
                rng.gen::<f64>() * e[0],
                rng.gen::<f64>() * e[1],
                rng.gen::<f64>() * e[2],
            ];
            let inside = super::cell_of(grid, p).is_some_and(|c| grid.inside(c));
            if !inside || grid.distance_to_faces(p).any(|(_, d)| d < margin) {
                continue;
            }
            out.push(Nucleus {
                position: p,
                radius: self.distribution.draw(&mut rng),
            });
        }
        Ok(out)
    }

    fn skin_compression(&self) -> Option<f64> {
        self.skin_compression
    }
}

/// Build from the `[nucleation]` table: field names, ranges and units are checked here.
pub fn build(t: toml::Table) -> Result<Box<dyn NucleationModel>, NucleationError> {
    let r: Raw = raw(t)?;
    let range = |key: &str, v: f64, lo: f64, hi: f64, unit: &str| {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(NucleationError::new(
                key,
                crate::error::outside_range(v, lo, hi, unit),
            ))
        }
    };
    let number_density = range(
        "number_density_per_m3",
        r.number_density_per_m3,
        0.0,
        1e18,
        "per m³",
    )?;
    let unused = |key: &str, v: Option<f64>, dist: &str| match v {
        Some(_) => Err(NucleationError::new(
            key,
            format!("`{key}` does not apply to distribution \"{dist}\""),
        )),
        None => Ok(()),
    };
    let need = |key: &str, v: Option<f64>, dist: &str| {
        v.ok_or_else(|| NucleationError::new(key, format!("distribution \"{dist}\" needs `{key}`")))
    };
    let distribution = match r.distribution.as_deref().unwrap_or("exponential") {
        "exponential" => {
            unused("median_radius_m", r.median_radius_m, "exponential")?;
            unused("sigma", r.sigma, "exponential")?;
            let slope = need("slope_per_m", r.slope_per_m, "exponential")?;
            SizeDistribution::Exponential {
                slope: range("slope_per_m", slope, 1e2, 1e10, "1/m")?,
            }
        }
        "log-normal" => {
            unused("slope_per_m", r.slope_per_m, "log-normal")?;
            let median = need("median_radius_m", r.median_radius_m, "log-normal")?;
            let sigma = need("sigma", r.sigma, "log-normal")?;
            SizeDistribution::LogNormal {
                median: range("median_radius_m", median, 1e-9, 1e-2, "m")?,
                sigma: range("sigma", sigma, 0.0, 5.0, "")?,
            }
        }
        other => {
            return Err(NucleationError::new(
                "distribution",
                format!("unknown distribution '{other}'; use \"exponential\" or \"log-normal\""),
            ))
        }
    };
    let margin = match r.margin_m {
        Some(m) => Some(range("margin_m", m, 0.0, 10.0, "m")?),
        None => None,
    };
    let skin_compression = match r.skin_compression {
        // γc > γ is checked against the material when the pool is built
        Some(g) => Some(range("skin_compression", g, 1e-3, 10.0, "N/m")?),
        None => None,
    };
    Ok(Box::new(CriticalRadius {
        number_density,
        distribution,
        margin,
        seed: r.seed,
        skin_compression,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::grid::Shape;

    fn table(s: &str) -> toml::Table {
        toml::from_str(s).unwrap()
    }

    #[test]
    fn errors_name_the_field() {
        let e = build(table("number_density_per_m3 = 1e9\nseed = 1")).unwrap_err();
        assert_eq!(e.field, "nucleation.slope_per_m");
        let e = build(table(
            "number_density_per_m3 = -1.0\nslope_per_m = 1e6\nseed = 1",
        ))
        .unwrap_err();
        assert_eq!(e.field, "nucleation.number_density_per_m3");
        let e = build(table(
            "number_density_per_m3 = 1.0\nslope_per_m = 1e6\nseed = 1\nslop = 2.0",
        ))
        .unwrap_err();
        assert_eq!(e.field, "nucleation.slop");
        let e = build(table("number_density_per_m3 = 1.0\nslope_per_m = 1e6")).unwrap_err();
        assert_eq!(e.field, "nucleation.seed");
        let e = build(table(
            "number_density_per_m3 = 1.0\ndistribution = \"log-normal\"\nmedian_radius_m = 1e-6\nseed = 1",
        ))
        .unwrap_err();
        assert_eq!(e.field, "nucleation.sigma");
    }

    #[test]
    fn population_size_and_the_exponential_mean() {
        // 1 mm³ of gel at N₀ = 2e12 /m³: 2000 nuclei; the exponential's mean radius is 1/β
        // (standard error 1/(β√n) ≈ 2.2 %: a 10 % band is > 4 standard errors)
        let g = Grid::new(Shape::Box { size: [1e-3; 3] }, 1e-4, &[]).unwrap();
        let m = CriticalRadius {
            number_density: 2e12,
            distribution: SizeDistribution::Exponential { slope: 1e6 },
            margin: Some(0.0),
            seed: 3,
            skin_compression: None,
        };
        let n = m.nuclei(&g).unwrap();
        assert_eq!(n.len(), 2000);
        let mean = n.iter().map(|x| x.radius).sum::<f64>() / n.len() as f64;
        assert!((mean - 1e-6).abs() < 0.1e-6, "mean radius {mean}");
        assert_eq!(n, m.nuclei(&g).unwrap());
    }
}
