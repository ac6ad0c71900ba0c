//! The largest uniform speed-up k of each task's demonstrations (sampled at Δt = 33 ms) that stays
//! within the shield's planning limits (0.8·a_max, min(j_max, 400), v_max): velocities scale by
//! k, accelerations by k², jerks by k³.
#![allow(clippy::needless_range_loop)]
use pacs_sim::task::{TaskKind, scenario};
fn main() {
    for task in TaskKind::ALL {
        let sc = scenario(task, 1, false);
        let l = sc.robot.limits();
        let n = sc.robot.dof();
        let dt = 0.033;
        let mut kmin = f64::INFINITY;
        let (mut vm, mut am, mut jm) = (0.0f64, 0.0f64, 0.0f64);
        for d in sc.policy.demos() {
            for k in 0..d.len() - 3 {
                for i in 0..n {
                    let v = (d[k + 1][i] - d[k][i]) / dt;
                    let a = (d[k + 2][i] - 2.0 * d[k + 1][i] + d[k][i]) / (dt * dt);
                    let j = (d[k + 3][i] - 3.0 * d[k + 2][i] + 3.0 * d[k + 1][i] - d[k][i])
                        / (dt * dt * dt);
                    let (va, aa, ja) = (l.v_max()[i], 0.8 * l.a_max()[i], l.j_max()[i].min(400.0));
                    vm = vm.max(v.abs() / va);
                    am = am.max(a.abs() / aa);
                    jm = jm.max(j.abs() / ja);
                    let kk = (va / v.abs())
                        .min((aa / a.abs()).sqrt())
                        .min((ja / j.abs()).cbrt());
                    kmin = kmin.min(kk);
                }
            }
        }
        println!(
            "{:?}: demo length {} samples ({:.2} s); max ratios v {vm:.2} a {am:.2} j {jm:.2}; max uniform speed-up {kmin:.2}",
            task,
            sc.policy.demos()[0].len(),
            sc.policy.demos()[0].len() as f64 * dt
        );
    }
}
