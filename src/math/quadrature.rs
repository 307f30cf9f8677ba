//! Gauss-Legendre quadrature on [-1, 1], for the tables rough plastic precomputes at scene
//! build (as Mitsuba's `quad::gauss_legendre`).

/// The `n` nodes and weights of Gauss-Legendre quadrature on [-1, 1]: exact for polynomials of
/// degree up to 2n - 1. Nodes by Newton's method on the Legendre polynomial from Chebyshev
/// guesses, to full f64 precision.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and its derivative by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            // p1 = P_n(x), p0 = P_{n-1}(x).
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let step = p1 / dp;
            x -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[i] = -x;
        nodes[n - 1 - i] = x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        for n in [1, 2, 5, 32, 128] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n {n}");
            for degree in 0..(2 * n).min(40) {
                let got: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(x, w)| w * x.powi(degree as i32))
                    .sum();
                let want = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree + 1) as f64
                };
                assert!((got - want).abs() < 1e-12, "n {n} degree {degree}: {got}");
            }
        }
    }
}
