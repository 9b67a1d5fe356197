//! Ranking the schedules of an evaluation under each law ([`ranking`]), the criteria on which
//! they are tied ([`ties`]), and the numerical uncertainty that decides a tie
//! ([`criterion_uncertainty`]).

use super::{Evaluation, RunOutcome};

/// Relative floor of the numerical uncertainty of a criterion's value, as a fraction of the
/// larger of the largest |value| and the limit: the round-off and solver-tolerance noise of
/// runs that should give the same number (nuclei that never grow give dA/dt of 10⁻¹⁰ µm²/s
/// and volume·time of 10⁻¹² mm³·min, zero up to that noise). The discretisation error (grid
/// step; the step tolerance, ≈ 0.3 % on a radius at the default `bubble_tolerance`) is not in
/// it: it shifts the values of every schedule run on the same grid alike.
pub const TIE_RELATIVE_UNCERTAINTY: f64 = 1e-6;

/// The numerical uncertainty of one criterion across runs with `values` and `limit`
/// ([`TIE_RELATIVE_UNCERTAINTY`]).
pub fn criterion_uncertainty(values: &[f64], limit: f64) -> f64 {
    let big = values.iter().fold(limit.abs(), |m, v| m.max(v.abs()));
    TIE_RELATIVE_UNCERTAINTY * big
}

/// A criterion on which every schedule under one law scores the same within the numerical
/// uncertainty: it does not rank them.
#[derive(Debug, Clone, PartialEq)]
pub struct Tie {
    /// Elasticity law.
    pub law: &'static str,
    /// Index of the criterion (criteria-file order).
    pub criterion: usize,
    /// Largest minus smallest value over the schedules, in the criterion's unit.
    pub spread: f64,
    /// The numerical uncertainty ([`criterion_uncertainty`]), in the criterion's unit.
    pub uncertainty: f64,
}

/// The criteria on which the schedules are tied, per law (only with two or more schedules).
pub fn ties(ev: &Evaluation) -> Vec<Tie> {
    let mut out = Vec::new();
    for law in &ev.laws {
        let runs: Vec<&RunOutcome> = ev.runs.iter().filter(|r| r.law == *law).collect();
        if runs.len() < 2 {
            continue;
        }
        for (k, c) in ev.criteria.criteria.iter().enumerate() {
            let v: Vec<f64> = runs.iter().map(|r| r.scores[k].value).collect();
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(*x), b.max(*x))
                });
            let u = criterion_uncertainty(&v, c.limit);
            if hi - lo <= u {
                out.push(Tie {
                    law,
                    criterion: k,
                    spread: hi - lo,
                    uncertainty: u,
                });
            }
        }
    }
    out
}

/// One ranked run.
#[derive(Debug, Clone, PartialEq)]
pub struct Ranked {
    /// Elasticity law.
    pub law: &'static str,
    /// 1-based rank within the law; tied schedules share a rank (1, 1, 3).
    pub rank: usize,
    /// True when another schedule shares this rank.
    pub tied: bool,
    /// Candidate index.
    pub candidate: usize,
    /// Failed criteria.
    pub failures: usize,
    /// Largest value/limit and its criterion label, over the criteria that separate the
    /// schedules (all criteria when none does).
    pub worst: (f64, String),
    /// Mean value/limit over the same criteria.
    pub mean_ratio: f64,
}

/// Rank the schedules under each law: fewest failed criteria first, then the smallest
/// worst value/limit, then the smallest mean value/limit, both over the criteria that
/// separate the schedules ([`ties`] leaves out the others). Two schedules share a rank when
/// they fail as many criteria and their worst and mean value/limit differ by no more than the
/// numerical uncertainty ([`criterion_uncertainty`] over the limit).
pub fn ranking(ev: &Evaluation) -> Vec<Ranked> {
    let ties = ties(ev);
    let mut out = Vec::new();
    for law in &ev.laws {
        let runs: Vec<&RunOutcome> = ev.runs.iter().filter(|r| r.law == *law).collect();
        let nk = ev.criteria.criteria.len();
        let mut used: Vec<usize> = (0..nk)
            .filter(|k| !ties.iter().any(|t| t.law == *law && t.criterion == *k))
            .collect();
        if used.is_empty() {
            used = (0..nk).collect();
        }
        // uncertainty of each used criterion's value/limit
        let u_ratio: Vec<f64> = used
            .iter()
            .map(|&k| {
                let v: Vec<f64> = runs.iter().map(|r| r.scores[k].value).collect();
                let limit = ev.criteria.criteria[k].limit;
                criterion_uncertainty(&v, limit) / limit
            })
            .collect();
        let u_worst = u_ratio.iter().copied().fold(0.0, f64::max);
        let u_mean = u_ratio.iter().sum::<f64>() / u_ratio.len().max(1) as f64;
        let mut rows: Vec<Ranked> = runs
            .iter()
            .map(|r| {
                let worst = used
                    .iter()
                    .map(|&k| (r.scores[k].ratio(), r.scores[k].label.clone()))
                    .fold((f64::NEG_INFINITY, String::new()), |a, b| {
                        if b.0 > a.0 {
                            b
                        } else {
                            a
                        }
                    });
                let n = used.len().max(1) as f64;
                Ranked {
                    law,
                    rank: 0,
                    tied: false,
                    candidate: r.candidate,
                    failures: r.scores.iter().filter(|s| !s.pass).count(),
                    worst,
                    mean_ratio: used.iter().map(|&k| r.scores[k].ratio()).sum::<f64>() / n,
                }
            })
            .collect();
        rows.sort_by(|a, b| {
            a.failures
                .cmp(&b.failures)
                .then(a.worst.0.total_cmp(&b.worst.0))
                .then(a.mean_ratio.total_cmp(&b.mean_ratio))
        });
        for i in 0..rows.len() {
            let same = i > 0 && {
                let (p, q) = (&rows[i - 1], &rows[i]);
                p.failures == q.failures
                    && (p.worst.0 - q.worst.0).abs() <= u_worst
                    && (p.mean_ratio - q.mean_ratio).abs() <= u_mean
            };
            if same {
                rows[i].rank = rows[i - 1].rank;
                rows[i].tied = true;
                rows[i - 1].tied = true;
            } else {
                rows[i].rank = i + 1;
            }
        }
        out.extend(rows);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncertainty_floor_ties_numerical_zeros_not_real_differences() {
        // the demo under the Bulk-Modulus law: dA/dt of nuclei that never grow, 4.69e-10 and
        // 8.88e-11 µm²/s against a limit of 80: u = 1e-6 · 80 = 8e-5 µm²/s ≫ the spread
        let u = criterion_uncertainty(&[4.694e-10, 8.876e-11], 80.0);
        assert!((u - 8e-5).abs() < 1e-18);
        assert!(4.694e-10 - 8.876e-11 <= u);
        // peak radii 107.8 and 102.9 µm (limit 118): u = 1e-6 · 118 µm, far below 4.9 µm
        let u = criterion_uncertainty(&[107.8, 102.9], 118.0);
        assert!((u - 1.18e-4).abs() < 1e-15 && 107.8 - 102.9 > u);
        // a value above the limit sets the scale: 1e-6 · 131.6
        assert!((criterion_uncertainty(&[131.6, 102.9], 118.0) - 1.316e-4).abs() < 1e-15);
    }
}
