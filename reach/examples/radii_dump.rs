//! Prints occupancy radii and endpoints of deterministic FR3 boxes (tightness comparisons).
use pacs_models::fr3;
use pacs_reach::JointBox;
use pacs_reach::robot::RobotReach;

fn main() {
    let robot = fr3::fr3();
    let reach = RobotReach::new(&robot, 0.0);
    let lim = robot.limits();
    let mut rng = 0x2545F4914F6CDD1Du64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for &w in &[0.0, 0.002, 0.02, 0.1, 0.3, 1.0] {
        for _ in 0..200 {
            let mut lo = [0.0; 7];
            let mut hi = [0.0; 7];
            for i in 0..7 {
                let a = lim.q_min()[i] + next() * (lim.q_max()[i] - lim.q_min()[i]);
                lo[i] = a - w * next();
                hi[i] = a + w * next();
            }
            let caps = reach.occupancy(&JointBox::new(&lo, &hi).unwrap()).unwrap();
            let mut r: Vec<String> = caps.iter().map(|c| format!("{:.9e}", c.radius())).collect();
            if std::env::var_os("ENERGY").is_some() {
                let mut vl = [0.0; 7];
                let mut vh = [0.0; 7];
                for i in 0..7 {
                    let v = lim.v_max()[i] * (2.0 * next() - 1.0);
                    let wv = [0.0, 0.01, 0.5, 2.0][(next() * 4.0) as usize % 4];
                    vl[i] = v - wv * next();
                    vh[i] = v + wv * next();
                }
                let mut e = [0.0; 8];
                reach
                    .subchain_energy_bounds_into(
                        &JointBox::new(&lo, &hi).unwrap(),
                        &JointBox::new(&vl, &vh).unwrap(),
                        &mut e,
                    )
                    .unwrap();
                r = e[1..].iter().map(|x| format!("{x:.9e}")).collect();
            }
            println!("{w} {}", r.join(" "));
        }
    }
}
