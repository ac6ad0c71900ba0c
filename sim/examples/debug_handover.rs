use pacs_models::{ConstraintSpec, default_human, fr3};
use pacs_sim::humans::{Camera, Handover, HumanScript};
use pacs_sim::policy::{ChunkPolicy, Demonstration};
use pacs_verify::shield::{Shield, ShieldConfig};
fn main() {
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.03).unwrap();
    let q_goal = [0.25, 0.15, 0.0, -1.95, 0.0, 2.1, 0.785];
    let mut demo = Demonstration::linear(&fr3::Q_READY, &q_goal, 40, 16, 8);
    let f = robot.frames(&q_goal);
    let p = (f[7] * fr3::tcp_in_joint7()).translation.vector;
    let script = Handover { offer: [p.x + 0.08, p.y, p.z + 0.02], t_offer: 0.0 };
    let spec = ConstraintSpec::builtin("handover").unwrap();
    let mut sh = Shield::new(robot.clone(), Some((human.clone(), &spec)), vec![], ShieldConfig::default()).unwrap();
    sh.start(0.0, &fr3::Q_READY).unwrap();
    let mut cam = Camera::new(0.01, 1);
    let mut q = fr3::Q_READY.to_vec();
    for k in 0..4000 {
        let t = k as f64 * 0.001;
        if k % 264 == 0 { let _ = sh.set_chunk(&demo.chunk(&q)); }
        let m = cam.measure(&human, &script, t);
        let c = sh.step(t, m.as_ref());
        q.copy_from_slice(&c.state.q[..7]);
        if k % 200 == 0 { eprintln!("t={t:.2} sd={:.3} ver={} {:?} sep={:.3} E={:.4}/{:.4}", c.diag.path_speed, c.diag.verified, c.diag.binding, c.diag.min_separation, c.diag.contact_energy, c.diag.contact_threshold); }
    }
    let _ = script.name();
}
