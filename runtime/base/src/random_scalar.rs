//! Random scalars declared on a MaterialX graph's interface — a rule's per-material draws, a
//! training class's per-tile and per-row draws: a range (`uimin`/`uimax`) and a distribution
//! (`uplift_distribution`: uniform by default, `normal(MEAN, SD)` truncated to the range, or
//! `optional(P)`: 0 with probability 1 − P, else uniform), drawn counter-based, so that a
//! scalar's value depends only on the seed and its name.

use crate::rng::{hash_str, mix64, unit_f64};

/// The largest magnitude of a random scalar's `uimin` and `uimax` (and so of its draws): every
/// draw, its f32 value and the rule arithmetic on it stay finite (a range of ±1e30 made `fit`
/// overflow). The widest range a shipped rule or class uses is 1,500–25,000 (a temperature).
pub const SCALAR_LIMIT: f64 = 1e6;

/// How a random scalar is drawn within `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distribution {
    Uniform,
    /// A normal distribution truncated to the range.
    Normal { mean: f64, sd: f64 },
    /// 0 with probability 1 − `p`, else uniform in the range.
    Optional { p: f64 },
}

/// A random scalar declared on a graph's interface.
#[derive(Clone, Debug, PartialEq)]
pub struct RandomScalar {
    pub name: String,
    pub min: f64,
    pub max: f64,
    pub distribution: Distribution,
}

/// Parses an `uplift_distribution` attribute (`normal(MEAN, SD)` or `optional(P)`).
pub fn parse_distribution(text: &str) -> Option<Distribution> {
    let text = text.trim();
    let open = text.find('(')?;
    let args: Vec<f64> = text[open + 1..].strip_suffix(')')?.split(',').map(|a| a.trim().parse::<f64>()).collect::<Result<_, _>>().ok()?;
    match (&text[..open], args.as_slice()) {
        ("normal", [mean, sd]) if mean.is_finite() && sd.is_finite() && *sd > 0.0 => Some(Distribution::Normal { mean: *mean, sd: *sd }),
        ("optional", [p]) if (0.0..=1.0).contains(p) => Some(Distribution::Optional { p: *p }),
        _ => None,
    }
}

/// The `k`-th uniform number in [0, 1) of the stream (`seed`, `stream`).
pub fn uniform(seed: u64, stream: u64, k: u64) -> f64 {
    unit_f64(mix64(mix64(seed ^ mix64(stream)).wrapping_add(k)))
}

impl RandomScalar {
    /// The scalar an interface input declares: its name, `type` (a float), `uimin`, `uimax` and
    /// optional `uplift_distribution`. The error says what is wrong (the caller adds where).
    pub fn from_attributes(name: &str, ty: &str, uimin: &str, uimax: &str, distribution: Option<&str>) -> Result<RandomScalar, String> {
        if ty != "float" {
            return Err(format!("random scalar `{name}` is {ty}; random scalars are floats"));
        }
        let number = |s: &str, what: &str| {
            let x = s.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("`{name}` has {what} `{s}`, not a number"))?;
            match x.abs() <= SCALAR_LIMIT {
                true => Ok(x),
                false => Err(format!("`{name}` has {what} `{s}`, outside ±{SCALAR_LIMIT:e} (the range random scalars may span)")),
            }
        };
        let (min, max) = (number(uimin, "uimin")?, number(uimax, "uimax")?);
        if min > max {
            return Err(format!("`{name}` has uimin {min} above uimax {max}"));
        }
        let distribution = match distribution {
            None => Distribution::Uniform,
            Some(d) => parse_distribution(d).ok_or_else(|| format!("`{name}`: uplift_distribution `{d}` is not `normal(MEAN, SD)` or `optional(P)`"))?,
        };
        Ok(RandomScalar { name: name.to_string(), min, max, distribution })
    }

    /// This scalar's value for a material seed.
    pub fn draw(&self, seed: u64) -> f64 {
        let stream = hash_str(&self.name);
        let u = |k| uniform(seed, stream, k);
        let within = |t: f64| self.min + (self.max - self.min) * t;
        match self.distribution {
            Distribution::Uniform => within(u(0)),
            Distribution::Optional { p } => {
                if u(0) < p {
                    within(u(1))
                } else {
                    0.0
                }
            }
            Distribution::Normal { mean, sd } => {
                // Rejection from the normal (Box–Muller); the rules' ranges hold most of the
                // mass, so 64 tries essentially never run out. If they do, the draw is uniform
                // in the range: still inside it, and still deterministic.
                for k in 0..64 {
                    let (u1, u2) = (u(2 * k).max(1e-300), u(2 * k + 1));
                    let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    let x = mean + sd * z;
                    if (self.min..=self.max).contains(&x) {
                        return x;
                    }
                }
                within(u(200))
            }
        }
    }
}


#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_range_past_the_limit_or_f32_is_refused_where_it_is_read() {
        for (lo, hi) in [("0", "1e39"), ("-1e30", "1e30"), ("0", "1000001"), ("nan", "1"), ("0", "inf")] {
            let e = RandomScalar::from_attributes("rust_amount", "float", lo, hi, None).unwrap_err();
            assert!(e.starts_with("`rust_amount` has "), "{lo}..{hi}: {e}");
        }
        let s = RandomScalar::from_attributes("t", "float", "1500", "25000", None).unwrap();
        assert_eq!((s.min, s.max), (1500.0, 25000.0));
        let e = RandomScalar::from_attributes("t", "float", "0", "2e6", None).unwrap_err();
        assert_eq!(e, "`t` has uimax `2e6`, outside ±1e6 (the range random scalars may span)");
    }

    #[test]
    fn a_distribution_with_a_non_finite_parameter_is_refused() {
        for d in ["normal(nan, 0.08)", "normal(0.5, nan)", "normal(inf, 1)", "normal(0.5, 0)", "optional(nan)", "optional(1.5)"] {
            assert_eq!(parse_distribution(d), None, "{d}");
            assert!(RandomScalar::from_attributes("x", "float", "0", "1", Some(d)).is_err(), "{d}");
        }
        assert_eq!(parse_distribution("normal(0.5, 0.08)"), Some(Distribution::Normal { mean: 0.5, sd: 0.08 }));
    }
}
