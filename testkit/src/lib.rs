//! # pacs-testkit
//!
//! Fixtures shared by the tests, benches and harnesses of several crates, so that each exists
//! once. Keypoints are in the order of the default human model (`lShldr`, `lForeArm`, `lHand`,
//! `rShldr`, `rForeArm`, `rHand`, `neck`, `hip`, `head`); units m and rad. Robot configurations
//! such as `pacs_models::fr3::Q_READY` live with the model.

/// The default human standing at (x, y) with the right hand at `hand` (the forearm keypoint
/// halfway between the right shoulder and the hand).
pub fn human_reaching(x: f64, y: f64, hand: [f64; 3]) -> Vec<[f64; 3]> {
    vec![
        [x, y + 0.2, 1.4],
        [x, y + 0.25, 1.15],
        [x, y + 0.25, 0.9],
        [x, y - 0.2, 1.4],
        [
            0.5 * (x + hand[0]),
            0.5 * (y - 0.2 + hand[1]),
            0.5 * (1.4 + hand[2]),
        ],
        hand,
        [x, y, 1.5],
        [x, y, 1.0],
        [x, y, 1.65],
    ]
}

/// Nine keypoints in a row at `x` (m from the base), 1 m high, 0.1 m apart along y: a person
/// far from or near the robot depending on `x`, for log and CLI tests.
pub fn keypoints_in_a_row(x: f64) -> Vec<[f64; 3]> {
    (0..9).map(|i| [x, 0.1 * i as f64 - 0.4, 1.0]).collect()
}

/// The default human standing `x` m in front of the base, both arms reaching 0.1–0.2 m
/// towards it (forearms and hands nearer than the shoulders): the audit's bench and series
/// tests.
pub fn standing_arms_forward(x: f64) -> Vec<[f64; 3]> {
    vec![
        [x, 0.2, 1.4],
        [x - 0.1, 0.25, 1.15],
        [x - 0.2, 0.25, 0.95],
        [x, -0.2, 1.4],
        [x - 0.1, -0.25, 1.15],
        [x - 0.2, -0.25, 0.95],
        [x, 0.0, 1.45],
        [x, 0.0, 0.95],
        [x, 0.0, 1.65],
    ]
}

/// A 7-joint motion with every joint on its own sinusoid about `q0` (rad): joint `j` at
/// `q0_j + 0.3·sin(w_j t)` with `w_j = w0 + dw·j` (rad/s), and its velocity (rad/s) at `t` (s).
pub fn sinusoidal_joints(q0: [f64; 7], w0: f64, dw: f64, t: f64) -> ([f64; 7], [f64; 7]) {
    let (mut q, mut dq) = (q0, [0.0; 7]);
    for j in 0..7 {
        let w = w0 + dw * j as f64;
        q[j] += 0.3 * (w * t).sin();
        dq[j] = 0.3 * w * (w * t).cos();
    }
    (q, dq)
}

/// Least distance (m) between the robot's moving capsules at `q` (rad) and the body parts at the
/// keypoints `kp` (m): the separation the tests score the shield and the baselines against.
pub fn true_separation(
    robot: &pacs_models::RobotModel,
    human: &pacs_models::HumanModel,
    q: &[f64],
    kp: &[[f64; 3]],
) -> f64 {
    use nalgebra::Point3;
    let caps = robot.capsules_world(q);
    let mut d = f64::INFINITY;
    for bp in human.body_parts() {
        let a = Point3::from(kp[bp.from]);
        let b = Point3::from(kp[bp.to]);
        for (li, c) in &caps {
            if robot.links()[*li].frame == 0 {
                continue;
            }
            let s = pacs_reach::geometry::segment_distance_lower_bound(&a, &b, &c.p1(), &c.p2())
                - c.radius()
                - bp.thickness / 2.0;
            d = d.min(s);
        }
    }
    d
}

/// A directory for one test's files, unique to the process and `name`, emptied when created and
/// removed (with its contents) when dropped, so that test runs leave nothing behind in the
/// system's temporary directory. Dereferences to its path.
#[derive(Debug)]
pub struct ScratchDir(std::path::PathBuf);

impl ScratchDir {
    /// `TMPDIR/pacs-PREFIX-PID-NAME`, created empty.
    ///
    /// # Panics
    /// If the directory cannot be created (a test fixture: the test cannot run).
    pub fn new(prefix: &str, name: &str) -> ScratchDir {
        let d = std::env::temp_dir().join(format!("pacs-{prefix}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d)
            .unwrap_or_else(|e| panic!("cannot create {}: {e}", d.display()));
        ScratchDir(d)
    }
}

impl std::ops::Deref for ScratchDir {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::path::Path> for ScratchDir {
    fn as_ref(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A reproducible stream of pseudo-random `u64`s (xorshift64) from a non-zero `seed`, for tests
/// that draw many random cases without a proptest strategy.
pub fn xorshift(seed: u64) -> impl FnMut() -> u64 {
    let mut s = seed.max(1);
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    }
}

/// SQL that turns a copy of the db3 fixture `clean.db3` (`python/tests/fixtures/db3`) into a
/// bag whose rows are stored too far out of time order to be read in the table's own order:
/// 1,000 copies of its first keypoints message at 0.9 s (1 µs apart), then one at 0.1 s, stored
/// after them; the metadata's counts are raised to match (1,114 rows, 1,012 keypoints).
pub const DB3_ROW_STORED_LATE: &str = "WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 999) \
     INSERT INTO messages (topic_id, timestamp, data) \
     SELECT m.topic_id, 1700000000900000000 + n.i * 1000, m.data FROM n, \
     (SELECT topic_id, data FROM messages WHERE topic_id = \
      (SELECT id FROM topics WHERE name = '/human/keypoints') ORDER BY id LIMIT 1) AS m; \
     INSERT INTO messages (topic_id, timestamp, data) \
     SELECT topic_id, 1700000000100000000, data FROM messages WHERE id = 114; \
     UPDATE metadata SET metadata = replace(replace(metadata, 'message_count: 113', \
     'message_count: 1114'), 'message_count: 11\n', 'message_count: 1012\n');";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixtures_have_the_default_humans_nine_keypoints() {
        assert_eq!(human_reaching(1.0, 0.0, [0.5, 0.0, 1.0]).len(), 9);
        let row = keypoints_in_a_row(2.0);
        assert_eq!(row.len(), 9);
        assert_eq!(row[0], [2.0, -0.4, 1.0]);
        assert!((row[8][1] - 0.4).abs() < 1e-15);
    }
}
