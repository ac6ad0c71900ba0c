//! Plans the 200 anchor chunks `reps` times with the default planner (instruction counting under
//! callgrind; development aid).
use pacs_models::RobotModel;
use pacs_motion::anchors::anchor_set;
use pacs_motion::{JointState, Limits, OutOfLimits, Planner, PlannerConfig};

fn main() {
    let robot = RobotModel::builtin("fr3").unwrap();
    let l = Limits::from_joint_limits(robot.limits()).with_uniform_acc_jerk(10.0, 400.0);
    let reps: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(1);
    let set: Vec<_> = anchor_set(robot.limits(), 200, 7)
        .iter()
        .map(|p| {
            let wp = p
                .chunk
                .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                .unwrap();
            (JointState::at_rest(&p.q0), wp)
        })
        .collect();
    let mut pl = Planner::new(l, PlannerConfig::default());
    let mut acc = 0.0;
    for _ in 0..reps {
        for (s, wp) in &set {
            acc += pl.plan(s, wp).unwrap().duration();
        }
    }
    println!("{acc}");
}
