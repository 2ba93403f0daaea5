//! Parametric displacement models (Odobez et al. 2003, Eq. 13) and their parameter layouts.

use nalgebra::SMatrix;

/// The geometric part of a displacement model. Coordinates (x, y) are relative to the estimate's
/// origin (the object centre in Odobez Eq. 15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MotionModel {
    /// d(r) = (t_x, t_y); parameters `[t_x, t_y]`.
    Translation,
    /// Translation plus isotropic scale: d(r) = (t_x + k·x, t_y + k·y); parameters `[t_x, t_y, k]`.
    Scale,
    /// Odobez Eq. 13: d(r) = (a1 + a2·x + a3·y, a4 + a5·x + a6·y); parameters `[a1, …, a6]`.
    Affine,
}

impl MotionModel {
    /// Number of geometric parameters (2, 3 or 6).
    pub fn geometric_len(self) -> usize {
        match self {
            MotionModel::Translation => 2,
            MotionModel::Scale => 3,
            MotionModel::Affine => 6,
        }
    }

    /// The lower-case name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            MotionModel::Translation => "translation",
            MotionModel::Scale => "scale",
            MotionModel::Affine => "affine",
        }
    }

    /// Displacement at (x, y) relative to the origin. `p` must hold at least
    /// [`geometric_len`](Self::geometric_len) values.
    #[inline]
    pub(crate) fn displacement(self, p: &[f64], x: f64, y: f64) -> [f64; 2] {
        match self {
            MotionModel::Translation => [p[0], p[1]],
            MotionModel::Scale => [p[0] + p[2] * x, p[1] + p[2] * y],
            MotionModel::Affine => [p[0] + p[1] * x + p[2] * y, p[3] + p[4] * x + p[5] * y],
        }
    }

    /// Derivatives of the displacement with respect to the parameters, contracted with the image
    /// gradient (gx, gy): ∂(∇I·d)/∂p. Writes [`geometric_len`](Self::geometric_len) values.
    /// The estimator computes these rows in f32 lanes; this scalar form is the reference its tests
    /// compare against.
    #[cfg(test)]
    pub(crate) fn gradient_row(self, gx: f64, gy: f64, x: f64, y: f64, out: &mut [f64; 7]) {
        match self {
            MotionModel::Translation => {
                out[0] = gx;
                out[1] = gy;
            }
            MotionModel::Scale => {
                out[0] = gx;
                out[1] = gy;
                out[2] = gx * x + gy * y;
            }
            MotionModel::Affine => {
                out[0] = gx;
                out[1] = gx * x;
                out[2] = gx * y;
                out[3] = gy;
                out[4] = gy * x;
                out[5] = gy * y;
            }
        }
    }

    /// Rescales geometric parameters from level 0 to level `l` (translations divided by 2^l).
    pub(crate) fn to_coarser_level(self, p: &mut [f64], l: usize) {
        let f = 0.5f64.powi(l as i32);
        let idx: &[usize] = match self {
            MotionModel::Translation | MotionModel::Scale => &[0, 1],
            MotionModel::Affine => &[0, 3],
        };
        for &i in idx {
            p[i] *= f;
        }
    }

    /// Rescales geometric parameters from pyramid level l+1 to level l (translations double,
    /// linear terms are scale-free).
    pub(crate) fn to_finer_level(self, p: &mut [f64]) {
        match self {
            MotionModel::Translation | MotionModel::Scale => {
                p[0] *= 2.0;
                p[1] *= 2.0;
            }
            MotionModel::Affine => {
                p[0] *= 2.0;
                p[3] *= 2.0;
            }
        }
    }

    /// The 6×7 linear map from this model's parameters (padded to 7, offset last and ignored) to the
    /// affine parameters `[a1..a6]` of Odobez Eq. 13.
    pub fn affine_map(self) -> SMatrix<f64, 6, 7> {
        let mut m = SMatrix::<f64, 6, 7>::zeros();
        match self {
            MotionModel::Translation => {
                m[(0, 0)] = 1.0;
                m[(3, 1)] = 1.0;
            }
            MotionModel::Scale => {
                m[(0, 0)] = 1.0;
                m[(3, 1)] = 1.0;
                m[(1, 2)] = 1.0;
                m[(5, 2)] = 1.0;
            }
            MotionModel::Affine => {
                for i in 0..6 {
                    m[(i, i)] = 1.0;
                }
            }
        }
        m
    }
}

impl std::fmt::Display for MotionModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for MotionModel {
    type Err = crate::Error;

    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "translation" => Ok(MotionModel::Translation),
            "scale" => Ok(MotionModel::Scale),
            "affine" => Ok(MotionModel::Affine),
            other => Err(crate::Error::InvalidSetting {
                name: "model",
                reason: format!("`{other}` is not one of translation, scale, affine"),
            }),
        }
    }
}

/// A displacement model with or without a global intensity offset c, so that the residual is
/// DFD(r) = z₁(r + d(r)) − z₀(r) − c.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct ModelSpec {
    /// The geometric model.
    pub model: MotionModel,
    /// Whether a global intensity offset is estimated (stored as the last parameter).
    pub offset: bool,
}

impl ModelSpec {
    /// A spec for `model`, with or without offset.
    pub fn new(model: MotionModel, offset: bool) -> Self {
        Self { model, offset }
    }

    /// Total number of parameters (geometric plus one for the offset), at most 7.
    pub fn len(self) -> usize {
        self.model.geometric_len() + usize::from(self.offset)
    }

    /// Always false: every model has parameters (present for API symmetry with `len`).
    pub fn is_empty(self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn affine_map_reproduces_displacement() {
        // Scale parameters mapped to affine must give the same displacement everywhere.
        let p = [1.5, -2.0, 0.03, 0.0, 0.0, 0.0, 0.0];
        let a = MotionModel::Scale.affine_map() * nalgebra::SVector::<f64, 7>::from(p);
        for &(x, y) in &[(0.0, 0.0), (10.0, -7.0), (-3.0, 40.0)] {
            let d0 = MotionModel::Scale.displacement(&p, x, y);
            let d1 = MotionModel::Affine.displacement(a.as_slice(), x, y);
            assert!((d0[0] - d1[0]).abs() < 1e-12 && (d0[1] - d1[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn level_scaling_round_trips() {
        let mut p = [1.0, 0.1, 0.2, -2.0, 0.3, 0.4];
        MotionModel::Affine.to_finer_level(&mut p);
        MotionModel::Affine.to_finer_level(&mut p);
        assert_eq!(p, [4.0, 0.1, 0.2, -8.0, 0.3, 0.4]);
    }

    #[test]
    fn parses_names() {
        assert_eq!("affine".parse::<MotionModel>(), Ok(MotionModel::Affine));
        assert!("bogus".parse::<MotionModel>().is_err());
        assert_eq!(ModelSpec::new(MotionModel::Affine, true).len(), 7);
    }
}
