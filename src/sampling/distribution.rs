//! Piecewise-constant distributions on [0, 1) and [0, 1)^2 (pbrt's `PiecewiseConstant1D/2D`):
//! the environment light samples its map's texels in proportion to their luminance times
//! sin(theta) with [`Distribution2D`]. Each `sample` comes with the density `pdf` gives for the
//! same point, so the chi-square tests can check the pair.

/// A piecewise-constant density on [0, 1) with `n` equal cells, cell i's density in proportion
/// to `f[i]`. A function that is zero everywhere (or not finite) gives the uniform density, so
/// sampling never divides by zero.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f64>,
    /// cdf[i] = integral of the density over [0, i / n]; n + 1 entries, the last exactly 1.
    cdf: Vec<f64>,
    /// The integral of `func` over [0, 1) (the mean of its values), before any fallback.
    integral: f64,
}

/// A point drawn from a [`Distribution1D`]: where, its density, and the cell it fell in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample1D {
    pub x: f64,
    pub pdf: f64,
    pub cell: usize,
}

impl Distribution1D {
    /// `f` must be non-empty; negative or non-finite entries count as zero.
    pub fn new(f: &[f64]) -> Self {
        assert!(!f.is_empty(), "a distribution needs at least one cell");
        let n = f.len();
        let mut func: Vec<f64> = f
            .iter()
            .map(|&v| if v.is_finite() && v > 0.0 { v } else { 0.0 })
            .collect();
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut acc = 0.0;
        for &v in &func {
            acc += v / n as f64;
            cdf.push(acc);
        }
        let integral = acc;
        if integral > 0.0 && integral.is_finite() {
            for c in &mut cdf {
                *c /= integral;
            }
        } else {
            func.iter_mut().for_each(|v| *v = 1.0);
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
        }
        cdf[n] = 1.0;
        Distribution1D {
            func,
            cdf,
            integral,
        }
    }

    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// The integral of the function over [0, 1) (0 for an all-zero function).
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The normalising constant of the density: the integral, or 1 for the uniform fallback.
    fn norm(&self) -> f64 {
        if self.integral > 0.0 && self.integral.is_finite() {
            self.integral
        } else {
            1.0
        }
    }

    /// Density of cell `cell`.
    #[inline]
    pub fn cell_pdf(&self, cell: usize) -> f64 {
        self.func.get(cell).map_or(0.0, |f| f / self.norm())
    }

    /// Density at `x` in [0, 1) (0 outside).
    #[inline]
    pub fn pdf(&self, x: f64) -> f64 {
        if !(0.0..1.0).contains(&x) {
            return 0.0;
        }
        let n = self.func.len();
        self.cell_pdf(((x * n as f64) as usize).min(n - 1))
    }

    /// Invert the cdf at `u` in [0, 1). Cells of zero density are never returned.
    #[inline]
    pub fn sample(&self, u: f64) -> Sample1D {
        let n = self.func.len();
        // Samplers give u < 1; were it 1, the last cell of nonzero density still gets it.
        let u = u.min(f64_prev(1.0));
        // The last cell whose cdf start is <= u; a zero-density cell has an empty cdf step,
        // so the search passes over it.
        let cell = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let width = self.cdf[cell + 1] - self.cdf[cell];
        let du = if width > 0.0 {
            ((u - self.cdf[cell]) / width).clamp(0.0, 1.0)
        } else {
            0.0
        };
        // Keep x inside the cell (and below 1) whatever the rounding.
        let x = ((cell as f64 + du) / n as f64).min(f64_prev((cell + 1) as f64 / n as f64));
        Sample1D {
            x,
            pdf: self.cell_pdf(cell),
            cell,
        }
    }
}

/// The largest f64 below `x` (x > 0).
fn f64_prev(x: f64) -> f64 {
    f64::from_bits(x.to_bits() - 1)
}

/// A piecewise-constant density on [0, 1)^2 over an `nu` x `nv` grid of cells, cell (iu, iv)'s
/// density in proportion to `f[iv * nu + iu]`: v is chosen from the rows' marginal, then u from
/// the row's conditional.
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

/// A point drawn from a [`Distribution2D`]: (u, v), its density, and its cell (iu, iv).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample2D {
    pub uv: (f64, f64),
    pub pdf: f64,
    pub cell: (usize, usize),
}

impl Distribution2D {
    /// `f` holds `nv` rows of `nu` values; both counts at least 1.
    pub fn new(f: &[f64], nu: usize, nv: usize) -> Self {
        assert!(nu > 0 && nv > 0 && f.len() == nu * nv, "a {nu}x{nv} grid");
        let conditional: Vec<Distribution1D> =
            f.chunks_exact(nu).map(Distribution1D::new).collect();
        let rows: Vec<f64> = conditional.iter().map(Distribution1D::integral).collect();
        Distribution2D {
            conditional,
            marginal: Distribution1D::new(&rows),
        }
    }

    /// The integral of the function over the unit square (0 if it is zero everywhere).
    pub fn integral(&self) -> f64 {
        self.marginal.integral()
    }

    pub fn size(&self) -> (usize, usize) {
        (self.conditional[0].len(), self.conditional.len())
    }

    #[inline]
    pub fn sample(&self, u: (f64, f64)) -> Sample2D {
        let v = self.marginal.sample(u.1);
        let row = &self.conditional[v.cell];
        let s = row.sample(u.0);
        Sample2D {
            uv: (s.x, v.x),
            pdf: s.pdf * v.pdf,
            cell: (s.cell, v.cell),
        }
    }

    /// Density of cell (iu, iv).
    #[inline]
    pub fn cell_pdf(&self, iu: usize, iv: usize) -> f64 {
        match self.conditional.get(iv) {
            Some(row) => row.cell_pdf(iu) * self.marginal.cell_pdf(iv),
            None => 0.0,
        }
    }

    /// Density at (u, v) in [0, 1)^2 (0 outside).
    #[inline]
    pub fn pdf(&self, (u, v): (f64, f64)) -> f64 {
        if !(0.0..1.0).contains(&u) || !(0.0..1.0).contains(&v) {
            return 0.0;
        }
        let (nu, nv) = self.size();
        let iu = ((u * nu as f64) as usize).min(nu - 1);
        let iv = ((v * nv as f64) as usize).min(nv - 1);
        self.cell_pdf(iu, iv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    #[test]
    fn one_dimension_follows_its_function() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 0.0]);
        assert_eq!(d.integral(), 1.0);
        assert_eq!(d.pdf(0.1), 1.0);
        assert_eq!(d.pdf(0.3), 0.0);
        assert_eq!(d.pdf(0.6), 3.0);
        assert_eq!(d.pdf(1.0), 0.0);
        // A quarter of the mass lies in the first cell: u below 1/4 lands there, linearly.
        let s = d.sample(0.125);
        assert_eq!((s.cell, s.pdf), (0, 1.0));
        assert!((s.x - 0.125).abs() < 1e-15);
        let s = d.sample(0.25);
        assert_eq!(s.cell, 2, "the zero cell is passed over");
        assert!((s.x - 0.5).abs() < 1e-15);
        let s = d.sample(1.0);
        assert_eq!(s.cell, 2);
        assert!(s.x < 0.75);
    }

    #[test]
    fn a_zero_function_samples_uniformly() {
        let d = Distribution1D::new(&[0.0, f64::NAN, -1.0]);
        assert_eq!(d.integral(), 0.0);
        assert_eq!(d.pdf(0.5), 1.0);
        let s = d.sample(0.5);
        assert_eq!((s.cell, s.pdf), (1, 1.0));
    }

    /// Cell frequencies of many samples match the normalised function, and every sample's pdf
    /// is the function's value there over its integral.
    #[test]
    fn two_dimensions_sample_in_proportion() {
        let (nu, nv) = (5, 3);
        let f: Vec<f64> = (0..nu * nv).map(|i| ((i * 7) % 5) as f64).collect();
        let d = Distribution2D::new(&f, nu, nv);
        let total: f64 = f.iter().sum::<f64>() / (nu * nv) as f64;
        assert!((d.integral() - total).abs() < 1e-12);
        let mut rng = Rng::new(3);
        let n = 200_000;
        let mut counts = vec![0usize; nu * nv];
        for _ in 0..n {
            let s = d.sample((rng.next_f64(), rng.next_f64()));
            let (iu, iv) = s.cell;
            assert_eq!(iu, (s.uv.0 * nu as f64) as usize);
            assert_eq!(iv, (s.uv.1 * nv as f64) as usize);
            assert!((s.pdf - f[iv * nu + iu] / total).abs() < 1e-12);
            assert_eq!(s.pdf, d.pdf(s.uv));
            counts[iv * nu + iu] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            let p = f[i] / (total * (nu * nv) as f64);
            let sd = (n as f64 * p * (1.0 - p)).sqrt().max(1.0);
            let z = (c as f64 - n as f64 * p) / sd;
            assert!(
                z.abs() < 5.0,
                "cell {i}: {c} samples, expected {}",
                n as f64 * p
            );
        }
    }
}
