//! Kinematics and dynamics of the built-in FR3: FK check values, Jacobians, mass matrix, energies.

mod common;

use common::{Rng, quad};
use nalgebra::{Matrix3, Point3, Vector3};
use pacs_models::fr3::{Q_READY, fr3, tcp_in_joint7};

fn flange(q: &[f64]) -> Point3<f64> {
    let r = fr3();
    r.frames(q)[7] * Point3::new(0.0, 0.0, 0.107)
}

#[test]
fn fk_check_values_from_facts_file() {
    // Facts §1b: q = 0 → flange (0.088, 0, 0.926); q_ready → flange (0.3069, 0, 0.5903),
    // hand_tcp (0.3069, 0, 0.4869) (values printed to 4 decimals).
    let p0 = flange(&[0.0; 7]);
    assert!((p0 - Point3::new(0.088, 0.0, 0.926)).norm() < 1e-12, "{p0}");
    let pr = flange(&Q_READY);
    assert!(
        (pr - Point3::new(0.3069, 0.0, 0.5903)).abs().max() < 1e-4,
        "{pr}"
    );
    let tcp = fr3().frames(&Q_READY)[7] * tcp_in_joint7();
    let t = tcp.translation.vector;
    assert!(
        (t - Vector3::new(0.3069, 0.0, 0.4869)).abs().max() < 1e-4,
        "{t}"
    );
    // At q_ready the TCP z axis points straight down.
    let z = tcp.rotation * Vector3::z();
    assert!((z - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12, "{z}");
}

#[test]
fn fk_q_zero_frames_by_hand() {
    // At q = 0 (modified DH, facts §1b) the joint-frame origins are:
    // 1: (0,0,0.333), 2: same, 3: (0,0,0.649), 4: (0.0825,0,0.649), 5: (0,0,1.033), 6: same, 7: (0.088,0,1.033)
    let f = fr3().frames(&[0.0; 7]);
    let expect = [
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.333],
        [0.0, 0.0, 0.333],
        [0.0, 0.0, 0.649],
        [0.0825, 0.0, 0.649],
        [0.0, 0.0, 1.033],
        [0.0, 0.0, 1.033],
        [0.088, 0.0, 1.033],
    ];
    for (k, e) in expect.iter().enumerate() {
        let t = f[k].translation.vector;
        assert!((t - Vector3::from(*e)).norm() < 1e-12, "frame {k}: {t}");
    }
    // Frame 7 at q = 0: z axis points down (−z world), x along world +x.
    let r7 = f[7].rotation;
    assert!((r7 * Vector3::z() + Vector3::z()).norm() < 1e-12);
    assert!((r7 * Vector3::x() - Vector3::x()).norm() < 1e-12);
}

#[test]
fn point_jacobian_matches_central_differences() {
    let r = fr3();
    let mut rng = Rng::new(7);
    let h = 1e-6;
    for _ in 0..50 {
        let q = rng.config(&r);
        let f = r.frames(&q);
        for frame in 1..=7 {
            let local = Point3::new(
                rng.range(-0.2, 0.2),
                rng.range(-0.2, 0.2),
                rng.range(-0.2, 0.2),
            );
            let p = f[frame] * local;
            let jac = r.point_jacobian(&f, frame, &p);
            for j in 0..7 {
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[j] += h;
                qm[j] -= h;
                let d = (r.frames(&qp)[frame] * local - r.frames(&qm)[frame] * local) / (2.0 * h);
                let col = jac.column(j);
                assert!(
                    (col - d).norm() < 1e-6,
                    "frame {frame} joint {j}: {col} vs {d}"
                );
                if j >= frame {
                    assert_eq!(col.norm(), 0.0, "joint {j} cannot move frame {frame}");
                }
            }
        }
    }
}

#[test]
fn mass_matrix_symmetric_positive_definite() {
    let r = fr3();
    let mut rng = Rng::new(11);
    for _ in 0..100 {
        let q = rng.config(&r);
        let m = r.mass_matrix(&q);
        assert_eq!(m.shape(), (7, 7));
        assert!((&m - m.transpose()).abs().max() < 1e-12, "asymmetric");
        let eig = m.clone().symmetric_eigenvalues();
        assert!(eig.min() > 1e-6, "not PD: {eig}");
    }
}

#[test]
fn kinetic_energy_equals_quadratic_form_of_mass_matrix() {
    let r = fr3();
    let mut rng = Rng::new(13);
    for _ in 0..100 {
        let q = rng.config(&r);
        let dq = rng.velocity(&r);
        let e = r.kinetic_energy(&q, &dq);
        let em = quad(&r.mass_matrix(&q), &dq);
        assert!((e - em).abs() <= 1e-10 * em, "{e} vs {em}");
        let mut sub = vec![0.0; 8];
        r.subchain_energies_into(&q, &dq, &mut sub);
        assert_eq!(sub[0], 0.0);
        assert_eq!(sub[7], e);
        for k in 1..=7 {
            let ek = quad(&r.mass_matrix_upto(&q, k), &dq);
            assert!(
                (sub[k] - ek).abs() <= 1e-10 * ek.max(1e-12),
                "k={k}: {} vs {ek}",
                sub[k]
            );
            assert!(sub[k] >= sub[k - 1], "energies not monotone at k={k}");
        }
    }
}

#[test]
fn single_joint_rotation_energy_by_parallel_axis_theorem() {
    // Only joint 1 moves at ω: every moving link spins rigidly about the world z axis through the
    // origin, so E = ½ ω² Σ (I_zz,world + m (c_x² + c_y²)) over links carried by frames ≥ 1.
    let r = fr3();
    let mut rng = Rng::new(17);
    for _ in 0..20 {
        let q = rng.config(&r);
        let w = rng.range(-2.0, 2.0);
        let f = r.frames(&q);
        let mut sum = 0.0;
        let mut mass = 0.0;
        for l in r.links() {
            let Some(i) = l.inertial else { continue };
            if l.frame == 0 {
                continue;
            }
            let rot: Matrix3<f64> = *f[l.frame].rotation.to_rotation_matrix().matrix();
            let iw = rot * i.inertia * rot.transpose();
            let c = f[l.frame] * i.com;
            sum += iw[(2, 2)] + i.mass * (c.x * c.x + c.y * c.y);
            mass += i.mass;
        }
        // Moving mass = links 1–7 (15.4948 kg, facts §3) + hand 0.6544 + fingers 2 × 0.0291.
        assert!((mass - (15.4948 + 0.6544 + 0.0582)).abs() < 1e-4, "{mass}");
        let mut dq = [0.0; 7];
        dq[0] = w;
        let expect = 0.5 * w * w * sum;
        let e = r.kinetic_energy(&q, &dq);
        assert!(
            (e - expect).abs() <= 1e-12 * expect.max(1e-12),
            "{e} vs {expect}"
        );
    }
}

#[test]
fn world_capsules_follow_their_frames() {
    // Link 1's capsule (0,0,−0.333)–(0,0,−0.05) in frame 1 is the world segment z ∈ [0, 0.283]
    // on the base axis for every q1.
    let r = fr3();
    let mut rng = Rng::new(19);
    let l1 = r.link_index("fr3_link1").unwrap();
    for _ in 0..10 {
        let q = rng.config(&r);
        let caps = r.capsules_world(&q);
        let (_, c) = caps.iter().find(|(li, _)| *li == l1).unwrap();
        assert!((c.p1() - Point3::new(0.0, 0.0, 0.0)).norm() < 1e-12);
        assert!((c.p2() - Point3::new(0.0, 0.0, 0.283)).norm() < 1e-12);
        assert_eq!(c.radius(), 0.09);
    }
    assert_eq!(r.capsule_count(), 12);
}

#[test]
fn pose_rpy_convention_is_urdf_fixed_axis_xyz() {
    // R = Rz(yaw)·Ry(pitch)·Rx(roll), built here from explicit matrices.
    let (r, p, y) = (0.3_f64, -0.7_f64, 1.1_f64);
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, r.cos(), -r.sin(), 0.0, r.sin(), r.cos());
    let ry = Matrix3::new(p.cos(), 0.0, p.sin(), 0.0, 1.0, 0.0, -p.sin(), 0.0, p.cos());
    let rz = Matrix3::new(y.cos(), -y.sin(), 0.0, y.sin(), y.cos(), 0.0, 0.0, 0.0, 1.0);
    let pose = pacs_models::robot::PoseSpec {
        xyz: [1.0, 2.0, 3.0],
        rpy: [r, p, y],
    }
    .to_isometry();
    let m = pose.rotation.to_rotation_matrix();
    assert!((m.matrix() - rz * ry * rx).abs().max() < 1e-15);
    assert_eq!(pose.translation.vector, Vector3::new(1.0, 2.0, 3.0));
}
