//! Statistics over repeated GPU timings (median, min, max, mean).

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    pub mean_ms: f64,
    pub samples: usize,
}

impl Stats {
    /// Statistics of `values` (empty input gives all zeros). The median of an even count is
    /// the mean of the two middle values.
    pub fn of(values: &[f64]) -> Stats {
        if values.is_empty() {
            return Stats::default();
        }
        let mut v: Vec<f64> = values.to_vec();
        v.sort_by(|a, b| a.total_cmp(b));
        let n = v.len();
        let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        Stats {
            median_ms: median,
            min_ms: v[0],
            max_ms: v[n - 1],
            mean_ms: v.iter().sum::<f64>() / n as f64,
            samples: n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        let s = Stats::of(&[3.0, 1.0, 2.0]);
        assert_eq!((s.median_ms, s.min_ms, s.max_ms, s.mean_ms), (2.0, 1.0, 3.0, 2.0));
        assert_eq!(Stats::of(&[4.0, 1.0, 2.0, 3.0]).median_ms, 2.5);
        assert_eq!(Stats::of(&[]).samples, 0);
    }
}
