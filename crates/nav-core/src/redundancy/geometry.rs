//! Sensor geometry of a redundant IMU: Platonic-solid face normals, per-face sensor frames,
//! user mountings, the improvement factor `k_r` (eqs. 38–40) and the least-squares
//! covariance `(HᵀWH)⁻¹`.
//!
//! A configuration is a list of *sensor axes*: unit vectors `h_i` (IMU frame) along which
//! one scalar is measured, `z_i = h_iᵀ·ω + b_i + v_i`. Stacked, they form the design matrix
//! `H` (one row per axis). A triaxial sensor contributes the three rows of its mounting
//! matrix; a single-axis gyro on a face contributes the face normal.
use nalgebra::{Matrix3, Vector3};

use crate::scalar::lit;
use crate::{NavError, Real};

/// The five regular (Platonic) polyhedra on whose faces sensors can be mounted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Polyhedron {
    /// 4 faces; normals along `(±1, ±1, ±1)/√3` with an even number of minus signs.
    Tetrahedron,
    /// 6 faces; normals `+x, +y, +z, −x, −y, −z` (in that order).
    Cube,
    /// 8 faces; normals `(±1, ±1, ±1)/√3`.
    Octahedron,
    /// 12 faces; normals along the icosahedron's vertices `(0, ±1, ±φ)` and cyclic.
    Dodecahedron,
    /// 20 faces; normals along the dodecahedron's vertices `(±1, ±1, ±1)`,
    /// `(0, ±1/φ, ±φ)` and cyclic.
    Icosahedron,
}

/// How many axes each mounted sensor measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisKind {
    /// One sensitive axis along the face normal (Table 14's "gyros per face").
    Single,
    /// A triaxial sensor whose z axis is the outward face normal and whose x axis is the
    /// projection of the IMU axis least aligned with the normal onto the face (for the cube,
    /// every sensor axis is parallel to an IMU axis).
    Triaxial,
}

const PHI: f64 = 1.618_033_988_749_895;
const IPHI: f64 = 0.618_033_988_749_895;

// Unnormalised outward face normals. Faces are ordered so that the first half holds one face
// of every antipodal pair (all but the tetrahedron come in pairs): taking only the first half
// still observes all three axes, which Table 14's "0.5 gyros per face" row needs.
const TETRA: [[f64; 3]; 4] = [[1., 1., 1.], [1., -1., -1.], [-1., 1., -1.], [-1., -1., 1.]];
const CUBE: [[f64; 3]; 6] = [
    [1., 0., 0.],
    [0., 1., 0.],
    [0., 0., 1.],
    [-1., 0., 0.],
    [0., -1., 0.],
    [0., 0., -1.],
];
const OCTA: [[f64; 3]; 8] = [
    [1., 1., 1.],
    [1., -1., -1.],
    [-1., 1., -1.],
    [-1., -1., 1.],
    [-1., -1., -1.],
    [-1., 1., 1.],
    [1., -1., 1.],
    [1., 1., -1.],
];
const DODECA: [[f64; 3]; 12] = [
    [0., 1., PHI],
    [0., -1., PHI],
    [1., PHI, 0.],
    [-1., PHI, 0.],
    [PHI, 0., 1.],
    [PHI, 0., -1.],
    [0., -1., -PHI],
    [0., 1., -PHI],
    [-1., -PHI, 0.],
    [1., -PHI, 0.],
    [-PHI, 0., -1.],
    [-PHI, 0., 1.],
];
const ICOSA: [[f64; 3]; 20] = [
    [1., 1., 1.],
    [1., 1., -1.],
    [1., -1., 1.],
    [1., -1., -1.],
    [0., IPHI, PHI],
    [0., IPHI, -PHI],
    [IPHI, PHI, 0.],
    [IPHI, -PHI, 0.],
    [PHI, 0., IPHI],
    [-PHI, 0., IPHI],
    [-1., -1., -1.],
    [-1., -1., 1.],
    [-1., 1., -1.],
    [-1., 1., 1.],
    [0., -IPHI, -PHI],
    [0., -IPHI, PHI],
    [-IPHI, -PHI, 0.],
    [-IPHI, PHI, 0.],
    [-PHI, 0., -IPHI],
    [PHI, 0., -IPHI],
];

impl Polyhedron {
    /// All five solids, by increasing number of faces.
    pub const ALL: [Polyhedron; 5] = [
        Polyhedron::Tetrahedron,
        Polyhedron::Cube,
        Polyhedron::Octahedron,
        Polyhedron::Dodecahedron,
        Polyhedron::Icosahedron,
    ];

    /// Number of faces.
    pub fn faces(self) -> usize {
        self.raw().len()
    }

    /// Lower-case name (`"tetrahedron"`, `"cube"`, …).
    pub fn name(self) -> &'static str {
        match self {
            Polyhedron::Tetrahedron => "tetrahedron",
            Polyhedron::Cube => "cube",
            Polyhedron::Octahedron => "octahedron",
            Polyhedron::Dodecahedron => "dodecahedron",
            Polyhedron::Icosahedron => "icosahedron",
        }
    }

    /// Parses a name as returned by [`Polyhedron::name`].
    pub fn from_name(name: &str) -> Result<Self, NavError> {
        Polyhedron::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or(NavError::InvalidParameter {
                what: "shape",
                reason: "expected tetrahedron, cube, octahedron, dodecahedron or icosahedron",
            })
    }

    fn raw(self) -> &'static [[f64; 3]] {
        match self {
            Polyhedron::Tetrahedron => &TETRA,
            Polyhedron::Cube => &CUBE,
            Polyhedron::Octahedron => &OCTA,
            Polyhedron::Dodecahedron => &DODECA,
            Polyhedron::Icosahedron => &ICOSA,
        }
    }

    /// Outward unit normal of face `i` (IMU frame).
    pub fn face_normal<T: Real>(self, i: usize) -> Result<Vector3<T>, NavError> {
        let r = self.raw().get(i).ok_or(NavError::InvalidParameter {
            what: "face",
            reason: "face index beyond the polyhedron's faces",
        })?;
        Ok(Vector3::new(lit::<T>(r[0]), lit(r[1]), lit(r[2])).normalize())
    }

    /// Mounting `C` (IMU → sensor) of a triaxial sensor on face `i`: rows are the sensor's
    /// x, y, z axes in the IMU frame, z the outward normal (see [`AxisKind::Triaxial`]).
    pub fn face_frame<T: Real>(self, i: usize) -> Result<Matrix3<T>, NavError> {
        let n = self.face_normal::<T>(i)?;
        // The IMU axis least aligned with the normal (first on ties) gives a well-conditioned
        // in-plane x axis.
        let mut k = 0;
        for j in 1..3 {
            if num_traits::Float::abs(n[j]) < num_traits::Float::abs(n[k]) - lit(1e-12) {
                k = j;
            }
        }
        let e = Vector3::ith(k, T::one());
        let x = (e - n * n.dot(&e)).normalize();
        let y = n.cross(&x);
        Ok(Matrix3::from_rows(&[
            x.transpose(),
            y.transpose(),
            n.transpose(),
        ]))
    }
}

/// A tolerance must be finite and ≥ 0: a NaN would make every `x > tol` test false and
/// accept anything.
fn check_tol<T: Real>(tol: T) -> Result<(), NavError> {
    if num_traits::Float::is_finite(tol) && tol >= T::zero() {
        Ok(())
    } else {
        Err(NavError::InvalidParameter {
            what: "tol",
            reason: "must be finite and >= 0",
        })
    }
}

/// Checks that `c` is a proper rotation: `‖CᵀC − I‖_max ≤ tol` and `det C > 0`.
pub fn check_rotation<T: Real>(c: &Matrix3<T>, tol: T) -> Result<(), NavError> {
    check_tol(tol)?;
    if c.iter().any(|v| !num_traits::Float::is_finite(*v)) {
        return Err(NavError::NonFinite {
            what: "mounting",
            index: 0,
        });
    }
    let e = c.transpose() * c - Matrix3::identity();
    if e.amax() > tol {
        return Err(NavError::InvalidParameter {
            what: "mounting",
            reason: "not orthonormal (CᵀC differs from I by more than the tolerance)",
        });
    }
    if c.determinant() <= T::zero() {
        return Err(NavError::InvalidParameter {
            what: "mounting",
            reason: "determinant is negative: a reflection, not a rotation",
        });
    }
    Ok(())
}

/// A set of up to `M` sensor axes (the design matrix `H`), grouped into sensors.
///
/// Fixed capacity so that per-sample fusion never allocates; `M` is the compile-time maximum
/// number of axes (e.g. 60 for three triaxial sensors on each face of a 20-face icosahedron
/// needs `M = 180`).
#[derive(Debug, Clone, Copy)]
pub struct SensorArray<T: Real, const M: usize> {
    axes: [Vector3<T>; M],
    sensor: [usize; M],
    n_axes: usize,
    n_sensors: usize,
}

impl<T: Real, const M: usize> SensorArray<T, M> {
    /// An empty array (no axes yet).
    pub fn empty() -> Self {
        Self {
            axes: [Vector3::zeros(); M],
            sensor: [0; M],
            n_axes: 0,
            n_sensors: 0,
        }
    }

    fn push_axis(&mut self, h: Vector3<T>, sensor: usize) -> Result<(), NavError> {
        if self.n_axes >= M {
            return Err(NavError::InvalidParameter {
                what: "sensor axes",
                reason: "more axes than the compile-time capacity M",
            });
        }
        self.axes[self.n_axes] = h;
        self.sensor[self.n_axes] = sensor;
        self.n_axes += 1;
        Ok(())
    }

    /// Adds a triaxial sensor with mounting `c` (IMU → sensor, validated as a rotation to
    /// `tol`); its three axes are the rows of `c`, in the order x, y, z.
    pub fn push_triaxial(&mut self, c: &Matrix3<T>, tol: T) -> Result<(), NavError> {
        check_rotation(c, tol)?;
        if self.n_axes + 3 > M {
            return Err(NavError::InvalidParameter {
                what: "sensor axes",
                reason: "more axes than the compile-time capacity M",
            });
        }
        let s = self.n_sensors;
        for r in 0..3 {
            self.push_axis(c.row(r).transpose(), s)?;
        }
        self.n_sensors += 1;
        Ok(())
    }

    /// Adds a single-axis sensor with sensitive axis `h` (IMU frame, unit length to `tol`).
    pub fn push_single(&mut self, h: &Vector3<T>, tol: T) -> Result<(), NavError> {
        check_tol(tol)?;
        if h.iter().any(|v| !num_traits::Float::is_finite(*v)) {
            return Err(NavError::NonFinite {
                what: "sensor axis",
                index: self.n_axes,
            });
        }
        if num_traits::Float::abs(h.norm() - T::one()) > tol {
            return Err(NavError::InvalidParameter {
                what: "sensor axis",
                reason: "not a unit vector",
            });
        }
        let s = self.n_sensors;
        self.push_axis(*h, s)?;
        self.n_sensors += 1;
        Ok(())
    }

    /// `counts[f]` sensors of `kind` on face `f` of `shape` (all sensors of one face share
    /// the face frame). Fails if the result cannot observe three axes.
    pub fn from_face_counts(
        shape: Polyhedron,
        counts: &[usize],
        kind: AxisKind,
    ) -> Result<Self, NavError> {
        if counts.len() != shape.faces() {
            return Err(NavError::LengthMismatch {
                what: "face counts",
                expected: shape.faces(),
                got: counts.len(),
            });
        }
        let mut a = Self::empty();
        for (f, &c) in counts.iter().enumerate() {
            let frame = shape.face_frame::<T>(f)?;
            for _ in 0..c {
                match kind {
                    AxisKind::Single => a.push_single(&frame.row(2).transpose(), lit(1e-9))?,
                    AxisKind::Triaxial => a.push_triaxial(&frame, lit(1e-9))?,
                }
            }
        }
        a.check_observable()?;
        Ok(a)
    }

    /// `per_face` sensors of `kind` on every face of `shape`.
    pub fn from_polyhedron(
        shape: Polyhedron,
        per_face: usize,
        kind: AxisKind,
    ) -> Result<Self, NavError> {
        let counts = [per_face; 20];
        Self::from_face_counts(shape, &counts[..shape.faces()], kind)
    }

    /// Triaxial sensors with the given mountings (IMU → sensor; each validated as a rotation
    /// to `tol`).
    pub fn from_mountings(mountings: &[Matrix3<T>], tol: T) -> Result<Self, NavError> {
        let mut a = Self::empty();
        for c in mountings {
            a.push_triaxial(c, tol)?;
        }
        a.check_observable()?;
        Ok(a)
    }

    /// Axes `axes[i]` (IMU frame, unit to `tol`) grouped into sensors by `sensor_of[i]`,
    /// which must start at 0 and never decrease or skip (axes of one sensor are adjacent).
    pub fn from_axes(axes: &[Vector3<T>], sensor_of: &[usize], tol: T) -> Result<Self, NavError> {
        check_tol(tol)?;
        if axes.len() != sensor_of.len() {
            return Err(NavError::LengthMismatch {
                what: "sensor_of",
                expected: axes.len(),
                got: sensor_of.len(),
            });
        }
        let mut a = Self::empty();
        for (i, (h, &s)) in axes.iter().zip(sensor_of).enumerate() {
            let next = if i == 0 { 0 } else { sensor_of[i - 1] + 1 };
            if !(s == next || (i > 0 && s == sensor_of[i - 1])) {
                return Err(NavError::InvalidParameter {
                    what: "sensor_of",
                    reason: "sensor indices must start at 0 and increase by at most 1 per axis",
                });
            }
            if h.iter().any(|v| !num_traits::Float::is_finite(*v)) {
                return Err(NavError::NonFinite {
                    what: "sensor axis",
                    index: i,
                });
            }
            if num_traits::Float::abs(h.norm() - T::one()) > tol {
                return Err(NavError::InvalidParameter {
                    what: "sensor axis",
                    reason: "not a unit vector",
                });
            }
            a.push_axis(*h, s)?;
            a.n_sensors = s + 1;
        }
        a.check_observable()?;
        Ok(a)
    }

    /// Number of sensor axes (rows of `H`).
    pub fn n_axes(&self) -> usize {
        self.n_axes
    }

    /// Number of sensors.
    pub fn n_sensors(&self) -> usize {
        self.n_sensors
    }

    /// Sensitive direction of axis `i` (IMU frame, unit).
    pub fn axis(&self, i: usize) -> Vector3<T> {
        self.axes[i.min(M.saturating_sub(1))]
    }

    /// Index of the sensor that axis `i` belongs to.
    pub fn sensor_of(&self, i: usize) -> usize {
        self.sensor[i.min(M.saturating_sub(1))]
    }

    /// Replaces the direction of axis `i` (used by misalignment compensation).
    pub fn set_axis(&mut self, i: usize, h: &Vector3<T>) -> Result<(), NavError> {
        if i >= self.n_axes {
            return Err(NavError::InvalidParameter {
                what: "axis index",
                reason: "beyond the array's axes",
            });
        }
        self.axes[i] = *h;
        Ok(())
    }

    /// Information matrix `HᵀWH` of the axes with weights `w_i = 1/σ_i²` (`sigma` per axis,
    /// in the measurement's unit) restricted to axes with `use_axis[i]`.
    pub fn information(&self, sigma: &[T], use_axis: &[bool]) -> Matrix3<T> {
        let mut a = Matrix3::zeros();
        for i in 0..self.n_axes {
            if use_axis.get(i).copied().unwrap_or(false) {
                let s = sigma.get(i).copied().unwrap_or(T::one());
                let h = self.axes[i];
                a += h * h.transpose() / (s * s);
            }
        }
        a
    }

    /// Fails unless the axes observe all three IMU axes (the information matrix is well
    /// conditioned: smallest / largest eigenvalue above 1e-9).
    pub fn check_observable(&self) -> Result<(), NavError> {
        let ones = [T::one(); M];
        let use_all = [true; M];
        check_info(&self.information(&ones, &use_all))
    }

    /// Improvement factor `k_r` per IMU axis, eq. (40): `k_r,j = 1/√(Σ_i cos² α_ij)` over all
    /// axes (equal noise, averaging of projections as eq. 38 assumes).
    pub fn k_r(&self) -> Result<Vector3<T>, NavError> {
        let mut s = Vector3::zeros();
        for i in 0..self.n_axes {
            let h = self.axes[i];
            s += h.component_mul(&h);
        }
        if s.iter().any(|v| *v <= T::zero()) {
            return Err(NavError::InvalidParameter {
                what: "sensor axes",
                reason: "an IMU axis is orthogonal to every sensor axis",
            });
        }
        Ok(s.map(|v| T::one() / num_traits::Float::sqrt(v)))
    }

    /// Least-squares covariance `(HᵀWH)⁻¹` (unit² of the measurement) for per-axis noise
    /// standard deviations `sigma` (length ≥ `n_axes`). With unit `sigma`, the square roots
    /// of its diagonal are the LS counterpart of `k_r` (equal to eq. 40 when `HᵀH` is
    /// diagonal, as for every Platonic configuration here).
    pub fn ls_covariance(&self, sigma: &[T]) -> Result<Matrix3<T>, NavError> {
        if sigma.len() < self.n_axes {
            return Err(NavError::LengthMismatch {
                what: "sigma",
                expected: self.n_axes,
                got: sigma.len(),
            });
        }
        if sigma[..self.n_axes]
            .iter()
            .any(|s| !num_traits::Float::is_finite(*s) || *s <= T::zero())
        {
            return Err(NavError::InvalidParameter {
                what: "sigma",
                reason: "every axis noise must be finite and positive",
            });
        }
        let use_all = [true; M];
        let a = self.information(sigma, &use_all);
        check_info(&a)?;
        a.try_inverse().ok_or(NavError::NotPositiveDefinite {
            what: "information matrix HᵀWH",
        })
    }
}

/// Rejects an information matrix that does not observe three axes.
pub(crate) fn check_info<T: Real>(a: &Matrix3<T>) -> Result<(), NavError> {
    let ev = a.symmetric_eigenvalues();
    let (mut lo, mut hi) = (ev[0], ev[0]);
    for v in ev.iter() {
        lo = num_traits::Float::min(lo, *v);
        hi = num_traits::Float::max(hi, *v);
    }
    if !(hi > T::zero()) || lo <= hi * lit(1e-9) {
        return Err(NavError::InvalidParameter {
            what: "sensor axes",
            reason: "fewer than three independent axes: the IMU rate is not observable",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn single(counts: &[usize]) -> SensorArray<f64, 64> {
        SensorArray::from_face_counts(Polyhedron::Cube, counts, AxisKind::Single).unwrap()
    }

    #[test]
    fn table14_rows_exact() {
        // Table 14: 3, 6, 9, 12, 18 single-axis gyros along the cube's face normals.
        let rows: [(&[usize], f64); 5] = [
            (&[1, 1, 1, 0, 0, 0], 1.0),
            (&[1, 1, 1, 1, 1, 1], 0.71),
            (&[2, 2, 2, 1, 1, 1], 0.58),
            (&[2, 2, 2, 2, 2, 2], 0.50),
            (&[3, 3, 3, 3, 3, 3], 0.41),
        ];
        for (counts, want) in rows {
            let k = single(counts).k_r().unwrap();
            for j in 0..3 {
                assert!(((k[j] * 100.0).round() / 100.0 - want).abs() < 1e-12, "{k}");
            }
        }
        // Six triaxial sensors (the thesis prototype) ≡ 18 gyros: k_r = 1/√6.
        let tri = SensorArray::<f64, 64>::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Triaxial)
            .unwrap();
        let k = tri.k_r().unwrap();
        assert!((k[0] - 1.0 / 6f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn platonic_normals_are_isotropic() {
        // Σ n nᵀ = (F/3)·I for every Platonic solid, so k_r = √(3/F) and LS == eq. (40).
        for p in Polyhedron::ALL {
            let a = SensorArray::<f64, 64>::from_polyhedron(p, 1, AxisKind::Single).unwrap();
            let f = p.faces() as f64;
            let cov = a.ls_covariance(&[1.0; 64]).unwrap();
            let k = a.k_r().unwrap();
            for j in 0..3 {
                assert!((k[j] - (3.0 / f).sqrt()).abs() < 1e-12, "{p:?}");
                assert!((cov[(j, j)].sqrt() - k[j]).abs() < 1e-12);
                for i in 0..3 {
                    if i != j {
                        assert!(cov[(i, j)].abs() < 1e-12);
                    }
                }
            }
            for i in 0..p.faces() {
                let c: Matrix3<f64> = p.face_frame(i).unwrap();
                check_rotation(&c, 1e-12).unwrap();
            }
        }
    }

    #[test]
    fn first_half_observes_three_axes() {
        for p in Polyhedron::ALL.into_iter().skip(1) {
            let mut counts = [0usize; 20];
            for c in counts.iter_mut().take(p.faces() / 2) {
                *c = 1;
            }
            SensorArray::<f64, 64>::from_face_counts(p, &counts[..p.faces()], AxisKind::Single)
                .unwrap();
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let mut c = Matrix3::<f64>::identity();
        c[(0, 1)] = 0.1;
        assert!(matches!(
            SensorArray::<f64, 9>::from_mountings(&[c], 1e-6),
            Err(NavError::InvalidParameter {
                what: "mounting",
                ..
            })
        ));
        let refl = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        assert!(SensorArray::<f64, 9>::from_mountings(&[refl], 1e-6).is_err());
        // Two single axes (opposite faces, same line) cannot observe three axes.
        let r = SensorArray::<f64, 9>::from_face_counts(
            Polyhedron::Cube,
            &[1, 0, 0, 1, 0, 0],
            AxisKind::Single,
        );
        assert!(matches!(
            r,
            Err(NavError::InvalidParameter {
                what: "sensor axes",
                ..
            })
        ));
        // Capacity exceeded is an error, not a panic.
        assert!(
            SensorArray::<f64, 5>::from_polyhedron(Polyhedron::Cube, 1, AxisKind::Single).is_err()
        );
        assert!(Polyhedron::from_name("sphere").is_err());
    }
}
