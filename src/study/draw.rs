//! The parameters' distributions and the cases they expand to: the grid of the `values` lists
//! crossed with `cases` random draws, each case's draws from its own random stream.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rand_distr::{Distribution as _, Normal};
use serde::Serialize;

/// The least probability mass a truncated normal's bounds may hold: below it the rejection
/// sampling would take more than a million tries a draw.
pub const MIN_TRUNCATED_MASS: f64 = 1e-6;

/// How a parameter varies.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Distribution {
    /// A grid axis: each value in turn.
    Values(Vec<toml::Value>),
    Uniform {
        lo: f64,
        hi: f64,
    },
    /// Uniform in log x, 0 < lo < hi.
    LogUniform {
        lo: f64,
        hi: f64,
    },
    /// Normal, truncated to `bounds` by rejection when given.
    Normal {
        mean: f64,
        sd: f64,
        bounds: Option<[f64; 2]>,
    },
}

impl Distribution {
    pub fn is_random(&self) -> bool {
        !matches!(self, Distribution::Values(_))
    }

    /// A value the key can take, for checking the key at load: the first value, the lower
    /// bound, or the mean (moved into the bounds).
    pub fn typical(&self) -> toml::Value {
        match self {
            Distribution::Values(v) => v[0].clone(),
            Distribution::Uniform { lo, .. } | Distribution::LogUniform { lo, .. } => {
                toml::Value::Float(*lo)
            }
            Distribution::Normal { mean, bounds, .. } => {
                toml::Value::Float(bounds.map_or(*mean, |[lo, hi]| mean.clamp(lo, hi)))
            }
        }
    }

    /// One draw. Never called for `Values`.
    fn draw(&self, rng: &mut ChaCha8Rng) -> f64 {
        match *self {
            Distribution::Values(_) => f64::NAN,
            Distribution::Uniform { lo, hi } => lo + (hi - lo) * rng.random::<f64>(),
            Distribution::LogUniform { lo, hi } => {
                (lo.ln() + (hi.ln() - lo.ln()) * rng.random::<f64>()).exp()
            }
            Distribution::Normal { mean, sd, bounds } => {
                // Checked at load: finite mean, sd > 0.
                let normal = Normal::new(mean, sd).unwrap_or_else(|_| unreachable!());
                let Some([lo, hi]) = bounds else {
                    return normal.sample(rng);
                };
                // The bounds hold at least MIN_TRUNCATED_MASS: this ends.
                loop {
                    let x = normal.sample(rng);
                    if (lo..=hi).contains(&x) {
                        return x;
                    }
                }
            }
        }
    }

    /// A one-line problem with the distribution's numbers, if any.
    pub fn check(&self) -> Result<(), String> {
        let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        match *self {
            Distribution::Values(ref v) if v.is_empty() => {
                Err("values = []: give at least one".into())
            }
            Distribution::Values(_) => Ok(()),
            Distribution::Uniform { lo, hi } if !(finite(&[lo, hi]) && lo < hi) => {
                Err(format!("uniform = [{lo}, {hi}]: needs finite lo < hi"))
            }
            Distribution::LogUniform { lo, hi } if !(finite(&[lo, hi]) && 0.0 < lo && lo < hi) => {
                Err(format!(
                    "log_uniform = [{lo}, {hi}]: needs finite 0 < lo < hi"
                ))
            }
            Distribution::Normal { mean, sd, .. } if !(finite(&[mean, sd]) && sd > 0.0) => Err(
                format!("normal = [{mean}, {sd}]: needs a finite mean and sd > 0"),
            ),
            Distribution::Normal {
                mean,
                sd,
                bounds: Some([lo, hi]),
            } => {
                if !(finite(&[lo, hi]) && lo < hi) {
                    return Err(format!("bounds = [{lo}, {hi}]: needs finite lo < hi"));
                }
                let mass = normal_mass(mean, sd, lo, hi);
                if mass < MIN_TRUNCATED_MASS {
                    return Err(format!(
                        "bounds = [{lo}, {hi}] hold {mass:.3e} of normal = [{mean}, {sd}], less \
                         than {MIN_TRUNCATED_MASS:e}: widen them or move the mean"
                    ));
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }
}

/// P(lo ≤ X ≤ hi) for X ~ N(mean, sd²), accurate relative to itself in either tail.
pub fn normal_mass(mean: f64, sd: f64, lo: f64, hi: f64) -> f64 {
    let (a, b) = ((lo - mean) / sd, (hi - mean) / sd);
    // Upper tails Q(z) = ½ erfc(z/√2) keep their relative accuracy where both bounds lie
    // far on one side.
    let q = |z: f64| 0.5 * erfc(z / std::f64::consts::SQRT_2);
    if a >= 0.0 {
        q(a) - q(b)
    } else if b <= 0.0 {
        q(-b) - q(-a)
    } else {
        1.0 - q(-a) - q(b)
    }
}

/// The complementary error function, to a relative error below 1.2e-7 everywhere (Numerical
/// Recipes' `erfcc`, a Chebyshev fit).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// The random stream of case `case`: a function of the seed and the case alone, so that a case
/// draws the same values whichever worker runs it, in whatever order, and `--case K` alone.
pub fn case_rng(seed: u64, case: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(case as u64);
    rng
}

/// The grid's size: the product of the `values` lists' lengths (1 without any), or `None` past
/// `limit`.
pub fn grid_len(dists: &[&Distribution], limit: usize) -> Option<usize> {
    dists.iter().try_fold(1usize, |n, d| match d {
        Distribution::Values(v) => n.checked_mul(v.len()).filter(|&n| n <= limit),
        _ => Some(n),
    })
}

/// The values of case `case` for every parameter, in file order: grid point g = case / draws
/// (the first `values` parameter varying slowest), and the random parameters drawn in file
/// order from the case's stream.
pub fn case_values(dists: &[&Distribution], draws: usize, seed: u64, case: usize) -> Vec<Drawn> {
    let mut g = case / draws.max(1);
    // Mixed radix, last `values` axis fastest.
    let mut grid = vec![0; dists.len()];
    for (k, d) in dists.iter().enumerate().rev() {
        if let Distribution::Values(v) = d {
            grid[k] = g % v.len();
            g /= v.len();
        }
    }
    let mut rng = case_rng(seed, case);
    dists
        .iter()
        .zip(grid)
        .map(|(d, i)| match d {
            Distribution::Values(v) => Drawn::Value(v[i].clone()),
            random => Drawn::Number(random.draw(&mut rng)),
        })
        .collect()
}

/// A case's value of one parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum Drawn {
    /// From a `values` list, as written.
    Value(toml::Value),
    /// A random draw.
    Number(f64),
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draws(d: &Distribution, n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| match &case_values(&[d], 1, 7, k)[0] {
                Drawn::Number(x) => *x,
                Drawn::Value(_) => unreachable!(),
            })
            .collect()
    }

    fn median(mut x: Vec<f64>) -> f64 {
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    }

    #[test]
    fn uniform_draws_fill_their_range() {
        let x = draws(&Distribution::Uniform { lo: 2.0, hi: 6.0 }, 20_000);
        assert!(x.iter().all(|v| (2.0..6.0).contains(v)));
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        // sd of the mean: (4/√12)/√20000 = 0.008.
        assert!((mean - 4.0).abs() < 0.04, "mean {mean}");
        assert!(x.iter().any(|&v| v < 2.05) && x.iter().any(|&v| v > 5.95));
    }

    #[test]
    fn log_uniform_median_is_the_geometric_mean() {
        let (lo, hi) = (2.0e7, 2.0e10);
        let x = draws(&Distribution::LogUniform { lo, hi }, 20_000);
        assert!(x.iter().all(|v| (lo..=hi).contains(v)));
        let m = median(x);
        // The median of log x is within ±0.02 of the range of log x at 5 sd.
        let want = (lo * hi).sqrt();
        assert!(
            (m.ln() - want.ln()).abs() < 0.02 * (hi / lo).ln(),
            "{m} vs {want}"
        );
    }

    #[test]
    fn normal_draws_have_their_mean_and_spread() {
        let x = draws(
            &Distribution::Normal {
                mean: 10.0,
                sd: 2.0,
                bounds: None,
            },
            20_000,
        );
        let n = x.len() as f64;
        let mean = x.iter().sum::<f64>() / n;
        let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n).sqrt();
        assert!((mean - 10.0).abs() < 0.1, "mean {mean}");
        assert!((sd - 2.0).abs() < 0.1, "sd {sd}");
    }

    #[test]
    fn truncated_normal_stays_inside_its_bounds() {
        let d = Distribution::Normal {
            mean: 0.0,
            sd: 1.0,
            bounds: Some([0.5, 3.0]),
        };
        d.check().unwrap();
        let x = draws(&d, 5000);
        assert!(x.iter().all(|v| (0.5..=3.0).contains(v)));
        // The median of N(0,1) truncated to [0.5, 3]: Φ⁻¹((Φ(0.5) + Φ(3))/2) = 1.0155.
        let m = median(x);
        assert!((m - 1.0155).abs() < 0.05, "{m}");
        let far = Distribution::Normal {
            mean: 0.0,
            sd: 1.0,
            bounds: Some([6.0, 7.0]),
        };
        assert!(
            far.check().unwrap_err().contains("hold 9.85"),
            "{:?}",
            far.check()
        );
    }

    #[test]
    fn normal_mass_matches_known_values() {
        assert!((normal_mass(0.0, 1.0, -1.0, 1.0) - 0.682_689_49).abs() < 1e-6);
        assert!((normal_mass(5.0, 2.0, 5.0, 1e9) - 0.5).abs() < 1e-7);
        // Q(6) = 9.8659e-10: far in the tail the relative error stays small.
        let q6 = normal_mass(0.0, 1.0, 6.0, f64::MAX);
        assert!((q6 / 9.865_876_45e-10 - 1.0).abs() < 1e-5, "{q6}");
    }

    #[test]
    fn the_grid_varies_the_first_list_slowest() {
        let a = Distribution::Values(vec![1.into(), 2.into()]);
        let b = Distribution::Values(vec!["x".into(), "y".into(), "z".into()]);
        let u = Distribution::Uniform { lo: 0.0, hi: 1.0 };
        let dists = [&a, &u, &b];
        assert_eq!(grid_len(&dists, 100), Some(6));
        assert_eq!(grid_len(&dists, 5), None);
        let at = |k| case_values(&dists, 4, 1, k);
        // Case k = g × 4 + d.
        assert_eq!(at(0)[0], Drawn::Value(1.into()));
        assert_eq!(at(0)[2], Drawn::Value("x".into()));
        assert_eq!(at(4)[2], Drawn::Value("y".into()));
        assert_eq!(at(11)[2], Drawn::Value("z".into()));
        assert_eq!(at(12)[0], Drawn::Value(2.into()));
        assert_eq!(at(12)[2], Drawn::Value("x".into()));
        assert_eq!(at(23)[2], Drawn::Value("z".into()));
        // A case's draws depend on the seed and the case alone.
        assert_eq!(at(13), at(13));
        assert_ne!(at(13)[1], at(14)[1]);
    }
}
