//! Prints occupancy radii and endpoints of deterministic FR3 boxes (tightness comparisons).
use pacs_models::fr3;
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
            let caps = reach.occupancy(&lo, &hi).unwrap();
            let r: Vec<String> = caps.iter().map(|c| format!("{:.9e}", c.radius())).collect();
            println!("{w} {}", r.join(" "));
        }
    }
}
