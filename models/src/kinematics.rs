//! Forward kinematics, point Jacobians, the joint-space mass matrix and sub-chain kinetic energies.
//!
//! Everything here is computed in ordinary (round-to-nearest) floating point: these are the
//! *nominal* values. Where safety depends on a bound, `pacs-reach` encloses them with outward
//! rounding.

use crate::robot::{MAX_DOF, RobotModel};
use crate::shape::Capsule;
use nalgebra::{DMatrix, Isometry3, Point3, UnitQuaternion, Vector3};

impl RobotModel {
    /// World poses of frames 0..=n for configuration `q` (rad), written into `out`
    /// (`out.len() == dof + 1`; frame 0 is the base). Allocates nothing.
    ///
    /// # Panics
    /// If `q.len() != dof` or `out.len() != dof + 1` (a programming error, not an input error).
    pub fn frames_into(&self, q: &[f64], out: &mut [Isometry3<f64>]) {
        assert_eq!(q.len(), self.dof(), "configuration length");
        assert_eq!(out.len(), self.dof() + 1, "frame buffer length");
        out[0] = *self.base();
        for (i, j) in self.joints().iter().enumerate() {
            let rot = UnitQuaternion::from_axis_angle(&j.axis, q[i]);
            out[i + 1] = out[i] * j.origin * Isometry3::from_parts(Default::default(), rot);
        }
    }

    /// World poses of frames 0..=n for `q` (allocating convenience form of [`Self::frames_into`]).
    pub fn frames(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        let mut out = vec![Isometry3::identity(); self.dof() + 1];
        self.frames_into(q, &mut out);
        out
    }

    /// World-frame capsules of every link for `q`, in link order then capsule order.
    pub fn capsules_world(&self, q: &[f64]) -> Vec<(usize, Capsule)> {
        let f = self.frames(q);
        let f = &f;
        self.links()
            .iter()
            .enumerate()
            .flat_map(|(li, l)| {
                l.capsules
                    .iter()
                    .map(move |c| (li, c.transformed(&f[l.frame])))
            })
            .collect()
    }

    /// Linear-velocity Jacobian (3 × n) of a world point `p` rigidly attached to `frame`, given
    /// the world frames from [`Self::frames_into`]. Columns of joints after `frame` are zero.
    pub fn point_jacobian(
        &self,
        frames: &[Isometry3<f64>],
        frame: usize,
        p: &Point3<f64>,
    ) -> nalgebra::Matrix3xX<f64> {
        let n = self.dof();
        let mut jac = nalgebra::Matrix3xX::zeros(n);
        for j in 0..frame.min(n) {
            let z = frames[j + 1].rotation * self.joints()[j].axis.into_inner();
            let o = frames[j + 1].translation.vector;
            jac.set_column(j, &z.cross(&(p.coords - o)));
        }
        jac
    }

    /// Joint-space mass matrix M(q) (kg·m²) of all links: Σ m Jvᵀ Jv + Jωᵀ R I Rᵀ Jω.
    pub fn mass_matrix(&self, q: &[f64]) -> DMatrix<f64> {
        self.mass_matrix_upto(q, self.dof())
    }

    /// Mass matrix of the sub-chain of links carried by frames `1..=frame` (the base does not move).
    pub fn mass_matrix_upto(&self, q: &[f64], frame: usize) -> DMatrix<f64> {
        let n = self.dof();
        let f = self.frames(q);
        let mut m = DMatrix::zeros(n, n);
        for l in self.links() {
            let Some(inr) = l.inertial else { continue };
            if l.frame == 0 || l.frame > frame {
                continue;
            }
            let c = f[l.frame] * inr.com;
            let jv = self.point_jacobian(&f, l.frame, &c);
            let mut jw = nalgebra::Matrix3xX::zeros(n);
            for j in 0..l.frame {
                jw.set_column(j, &(f[j + 1].rotation * self.joints()[j].axis.into_inner()));
            }
            let r = f[l.frame].rotation.to_rotation_matrix();
            let iw = r.matrix() * inr.inertia * r.matrix().transpose();
            m += inr.mass * jv.transpose() * &jv + jw.transpose() * iw * &jw;
        }
        m
    }

    /// Kinetic energy (J) of the links carried by frames `1..=k`, for every k = 0..=n, written into
    /// `out` (`out.len() == dof + 1`, `out[0] == 0`). Nominal value ½ q̇ᵀ M_k(q) q̇, computed from
    /// link twists without forming M. Allocates nothing.
    pub fn subchain_energies_into(&self, q: &[f64], dq: &[f64], out: &mut [f64]) {
        let n = self.dof();
        assert_eq!(dq.len(), n, "velocity length");
        assert_eq!(out.len(), n + 1, "energy buffer length");
        let mut frames = [Isometry3::identity(); MAX_DOF + 1];
        self.frames_into(q, &mut frames[..=n]);
        // Angular velocity and origin linear velocity of each frame.
        let mut w = [Vector3::zeros(); MAX_DOF + 1];
        let mut v = [Vector3::zeros(); MAX_DOF + 1];
        for j in 0..n {
            let z = frames[j + 1].rotation * self.joints()[j].axis.into_inner();
            let dp = frames[j + 1].translation.vector - frames[j].translation.vector;
            w[j + 1] = w[j] + z * dq[j];
            v[j + 1] = v[j] + w[j].cross(&dp);
        }
        let mut per_frame = [0.0; MAX_DOF + 1];
        for l in self.links() {
            let Some(inr) = l.inertial else { continue };
            if l.frame == 0 {
                continue;
            }
            let k = l.frame;
            let r = frames[k].rotation;
            let c_rel = r * inr.com.coords;
            let vc = v[k] + w[k].cross(&c_rel);
            let w_local = r.inverse() * w[k];
            per_frame[k] +=
                0.5 * inr.mass * vc.norm_squared() + 0.5 * w_local.dot(&(inr.inertia * w_local));
        }
        out[0] = 0.0;
        for k in 1..=n {
            out[k] = out[k - 1] + per_frame[k];
        }
    }

    /// Kinetic energy (J) of the whole moving robot at (q, q̇).
    pub fn kinetic_energy(&self, q: &[f64], dq: &[f64]) -> f64 {
        let mut e = [0.0; MAX_DOF + 1];
        self.subchain_energies_into(q, dq, &mut e[..=self.dof()]);
        e[self.dof()]
    }
}
