//! Levenberg–Marquardt: the one damped least-squares loop behind the
//! calibration's bundle adjustment and the boards' poses.

use nalgebra::{DMatrix, DVector};

/// Where the loop ended: the parameters, their residuals and the
/// residuals' Jacobian there.
#[derive(Debug, Clone)]
pub struct Minimum {
    /// Parameters at the minimum.
    pub x: DVector<f64>,
    /// Residuals there.
    pub residuals: DVector<f64>,
    /// d residuals / d x there.
    pub jacobian: DMatrix<f64>,
}

impl Minimum {
    /// Standard deviation of each parameter, σ²(JᵀJ)⁻¹ with σ² the
    /// residuals' variance; `None` when JᵀJ is singular (a parameter the
    /// residuals do not see) or there are no more residuals than parameters.
    pub fn std_devs(&self) -> Option<DVector<f64>> {
        let (m, n) = self.jacobian.shape();
        if m <= n {
            return None;
        }
        let sigma2 = self.residuals.norm_squared() / (m - n) as f64;
        let inverse = (self.jacobian.transpose() * &self.jacobian)
            .cholesky()?
            .inverse();
        Some(DVector::from_fn(n, |k, _| {
            (sigma2 * inverse[(k, k)]).max(0.0).sqrt()
        }))
    }
}

/// Minimises the sum of squared `residuals(x)` from `x0`, `jacobian(x)`
/// giving d residuals / d x. Either returns `None` where the model cannot
/// be evaluated (a point behind the camera): such a step is refused. Stops
/// when no step lowers the cost by a relative 1e-14, or after
/// `max_iterations`. `None` when `x0` itself cannot be evaluated.
pub fn levenberg_marquardt(
    x0: DVector<f64>,
    residuals: impl Fn(&DVector<f64>) -> Option<DVector<f64>>,
    jacobian: impl Fn(&DVector<f64>) -> Option<DMatrix<f64>>,
    max_iterations: usize,
) -> Option<Minimum> {
    let mut x = x0;
    let mut r = residuals(&x)?;
    let mut j = jacobian(&x)?;
    let mut cost = r.norm_squared();
    let mut lambda = 1e-3;
    let n = x.len();
    for _ in 0..max_iterations {
        let jtj = j.transpose() * &j;
        let g = -(j.transpose() * &r);
        let mut improved = false;
        while lambda < 1e12 {
            let mut a = jtj.clone();
            for d in 0..n {
                a[(d, d)] += lambda * jtj[(d, d)].max(1e-12);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&g)) else {
                lambda *= 10.0;
                continue;
            };
            let candidate = &x + step;
            if let Some(rc) = residuals(&candidate) {
                let c = rc.norm_squared();
                if c < cost {
                    improved = (cost - c) > 1e-14 * cost;
                    x = candidate;
                    r = rc;
                    cost = c;
                    lambda = (lambda / 10.0).max(1e-12);
                    break;
                }
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
        j = jacobian(&x)?;
    }
    Some(Minimum {
        x,
        residuals: r,
        jacobian: j,
    })
}

/// Central differences of `residuals` about `x`, parameter k stepped by
/// `steps[k]`.
pub fn numeric_jacobian(
    x: &DVector<f64>,
    residuals: impl Fn(&DVector<f64>) -> Option<DVector<f64>>,
    steps: &[f64],
) -> Option<DMatrix<f64>> {
    let mut columns = Vec::with_capacity(x.len());
    for (k, &h) in steps.iter().enumerate() {
        let mut plus = x.clone();
        plus[k] += h;
        let mut minus = x.clone();
        minus[k] -= h;
        columns.push((residuals(&plus)? - residuals(&minus)?) / (2.0 * h));
    }
    Some(DMatrix::from_columns(&columns))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exponential_decay() {
        let samples: Vec<(f64, f64)> = (0..20)
            .map(|k| {
                let t = f64::from(k) * 0.25;
                (t, 3.0 * (-0.7 * t).exp() + 0.5)
            })
            .collect();
        let residuals = |x: &DVector<f64>| {
            Some(DVector::from_iterator(
                samples.len(),
                samples
                    .iter()
                    .map(|&(t, y)| y - (x[0] * (-x[1] * t).exp() + x[2])),
            ))
        };
        let jacobian = |x: &DVector<f64>| numeric_jacobian(x, residuals, &[1e-6; 3]);
        let m = levenberg_marquardt(
            DVector::from_vec(vec![1.0, 0.1, 0.0]),
            residuals,
            jacobian,
            100,
        )
        .unwrap();
        assert!(
            (m.x[0] - 3.0).abs() < 1e-8 && (m.x[1] - 0.7).abs() < 1e-8,
            "{}",
            m.x
        );
        assert!(m.residuals.norm() < 1e-9);
    }
}
