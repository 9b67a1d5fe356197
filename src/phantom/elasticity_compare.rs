//! Final radius after a pressure change with no mass transfer, for every tissue-elasticity
//! form (the paper's Fig. 2a; the `elasticity` command and `reproduce fig2a`).

use crate::error::{Error, InputError};
use crate::phantom::bubble::Balance;
use crate::phantom::config::MIN_BUBBLE_RADIUS_M;
use crate::phantom::elasticity::{law_names, AllLawParams};

/// Inputs of the comparison (SI units).
#[derive(Debug, Clone)]
pub struct ElasticityRequest {
    /// Initial ambient pressure P0, Pa.
    pub p0: f64,
    /// Final ambient pressure, Pa.
    pub pf: f64,
    /// Surface tension γ, N/m.
    pub gamma: f64,
    /// Law parameters (μ, M, K).
    pub laws: AllLawParams,
    /// Initial radii R0, m.
    pub r0: Vec<f64>,
}

/// One row: R0, form, final radius (None where no physical root exists).
pub type ElasticityRow = (f64, &'static str, Option<f64>);

/// Final radius for every R0 and every form: the gas content n is fixed by the Laplace
/// balance at (P0, R0); R_f solves the same balance at P_f.
pub fn compare(req: &ElasticityRequest) -> Result<Vec<ElasticityRow>, Error> {
    // every option against the physical ranges of the phantom files
    // (profiles/phantoms/README.md), named as typed: `--p0`, not the field `p0`
    let option =
        |f: &str, m: String| Error::Input(InputError::new(m).in_file("<command line>").field(f));
    if req.r0.is_empty() {
        return Err(option(
            "--r0",
            "give the initial radii in m, comma-separated".into(),
        ));
    }
    let p_max = crate::profile::MAX_AMBIENT_PA;
    let mut ranged = vec![
        ("--p0", req.p0, 1.0, p_max, "Pa"),
        ("--pf", req.pf, 1.0, p_max, "Pa"),
        ("--gamma", req.gamma, 0.0, 1.0, "N/m"),
        ("--mu", req.laws.shear_modulus, 0.0, 1e7, "Pa"),
        ("--m", req.laws.bulk_modulus_per_volume, 0.0, 1e22, "Pa/m³"),
        ("--k", req.laws.bulk_modulus, 1e3, 1e12, "Pa"),
    ];
    ranged.extend(
        req.r0
            .iter()
            .map(|r| ("--r0", *r, MIN_BUBBLE_RADIUS_M, 1e-2, "m")),
    );
    for (f, v, lo, hi, unit) in ranged {
        if !(v.is_finite() && v >= lo && v <= hi) {
            // the pressures are absolute (a gauge pressure of 0 is not a vacuum)
            let note = if matches!(f, "--p0" | "--pf") {
                " (absolute pressure)"
            } else {
                ""
            };
            return Err(option(
                f,
                format!("{}{note}", crate::error::outside_range(v, lo, hi, unit)),
            ));
        }
    }
    let mut rows = Vec::new();
    for &r0 in &req.r0 {
        for name in law_names() {
            let law = req
                .laws
                .build(name)
                .map_err(|e| option("--mu/--m/--k", format!("law {name}: {e}")))?;
            let at = |p: f64| Balance {
                ambient: p,
                surface_tension: req.gamma,
                law: law.as_ref(),
                initial_radius: r0,
                initial_ambient: req.p0,
                fixed_gases: 0.0,
            };
            let nrt = at(req.p0).pv(r0);
            let rf = if nrt > 0.0 {
                at(req.pf).radius_for(nrt, r0)
            } else {
                None
            };
            rows.push((r0, name, rf));
        }
    }
    Ok(rows)
}

/// The rows as CSV `r0_m,form,rf_m` (empty `rf_m` where no root exists).
pub fn to_csv(rows: &[ElasticityRow]) -> String {
    let mut s = String::from("r0_m,form,rf_m\n");
    for (r0, form, rf) in rows {
        match rf {
            Some(r) => s.push_str(&format!("{r0:.6e},{form},{r:.9e}\n")),
            None => s.push_str(&format!("{r0:.6e},{form},\n")),
        }
    }
    s
}
