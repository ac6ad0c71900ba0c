//! The audit core: sound SSM and PFL checks of every span between consecutive robot samples.
//!
//! For a span `[t_i, t_{i+1}]` the robot's joint positions lie in a box derived from the two
//! samples and the velocity limits, its velocities in a box derived from the acceleration limits;
//! the human lies in the reachable occupancy of the latest measurement logged before `t_i`. A
//! violation is *possible* if the enclosures admit one, *certain* if it holds at a recorded sample
//! with the measured keypoints taken at face value. See `docs/audit.md` for the exact semantics.

// Per-joint loops index several parallel arrays; ranges read better than zipped iterators.
#![allow(clippy::needless_range_loop)]

use super::log::LogModels;
use super::verdict::{
    ConstraintKind, InconclusiveSpan, Metrics, ModelNames, RunResult, SeriesPoint, Verdict,
    Violation,
};
use nalgebra::{Isometry3, Point3};
use pacs_models::robot::MAX_DOF;
use pacs_models::{Capsule, Constraint, HumanModel, RobotModel};
use pacs_reach::geometry::{capsule_distance_lower_bound, segment_distance_upper_bound};
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::robot::{ReachScratch, RobotReach};
use pacs_reach::rounding::{add_up, dist3_up, mul_up, sub_down, sub_up};
use serde::{Deserialize, Serialize};

/// Audit settings (`--config task.toml`); every field has a documented default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuditConfig {
    /// A span between robot samples longer than this (s) is inconclusive. Default 0.1 s.
    pub max_gap: f64,
    /// A span is inconclusive once the human measurement in use is older than this (s) at its
    /// end. Default 1.0 s.
    pub max_human_age: f64,
    /// The robot is at rest on a span if every joint speed is provably ≤ this (rad/s). Default
    /// 0.02 rad/s.
    pub rest_speed: f64,
    /// Human reachability model: `combined` (default), `vel`, `pos` (`acc` needs velocities,
    /// which logs do not carry).
    pub human_model: HumanReachModel,
    /// Extra radius (m) added to every robot capsule (tracking/calibration error). Default 0.
    pub tracking_error: f64,
    /// Count two *adjacent* links (carrying frames differ by 1) touching one body part as
    /// clamping. Default false (only non-adjacent links clamp).
    pub clamp_adjacent_links: bool,
    /// Relative slack on `|q_{i+1} − q_i| ≤ v_max·Δt` before samples count as exceeding the
    /// velocity limits. Default 1e-9.
    pub limit_slack: f64,
    /// Override the header's robot.
    pub robot: Option<super::log::ModelRef<pacs_models::RobotSpec>>,
    /// Override the header's human model.
    pub human: Option<super::log::ModelRef<pacs_models::HumanSpec>>,
    /// Override the header's constraints.
    pub constraints: Option<super::log::ModelRef<pacs_models::ConstraintSpec>>,
    /// MCAP reading settings (topics, reorder window): the `[mcap]` table.
    pub mcap: super::mcap::McapConfig,
}

impl Default for AuditConfig {
    fn default() -> Self {
        Self {
            max_gap: 0.1,
            max_human_age: 1.0,
            rest_speed: 0.02,
            human_model: HumanReachModel::Combined,
            tracking_error: 0.0,
            clamp_adjacent_links: false,
            limit_slack: 1e-9,
            robot: None,
            human: None,
            constraints: None,
            mcap: Default::default(),
        }
    }
}

impl AuditConfig {
    /// Check every value; the error names the field and value.
    pub fn validate(&self) -> Result<(), String> {
        for (f, v) in [
            ("max_gap", self.max_gap),
            ("max_human_age", self.max_human_age),
            ("rest_speed", self.rest_speed),
            ("tracking_error", self.tracking_error),
            ("limit_slack", self.limit_slack),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{f}: value {v} must be finite and >= 0"));
            }
        }
        if self.human_model == HumanReachModel::Acc {
            return Err(
                "human_model: `acc` needs measured velocities, which logs do not carry".into(),
            );
        }
        self.mcap.validate()
    }
}

/// Maximum number of robot capsules supported (bit masks).
pub const MAX_CAPSULES: usize = 128;
/// Spans checked together by the block fast path (see `Auditor::check_block`).
pub const BLOCK_SPANS: usize = 32;
/// Maximum number of plot buckets per log.
pub const SERIES_BUCKETS: usize = 1024;

#[derive(Clone, Copy)]
struct Sample {
    t: f64,
    q: [f64; MAX_DOF],
    dq: [f64; MAX_DOF],
    has_dq: bool,
}

#[derive(Clone, Copy)]
struct Hit {
    part: usize,
    link: usize,
    kind: ConstraintKind,
    energy: f64,
    threshold: f64,
    constrained: bool,
    certain: bool,
    separation: f64,
}

#[derive(Clone, Copy)]
struct Open {
    v_start: f64,
    v_end: f64,
    kind: ConstraintKind,
    min_sep: f64,
    energy: f64,
    threshold: f64,
    constrained: bool,
    certain: bool,
    spans: u64,
    last_span: u64,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Reason {
    Gap,
    NoHuman,
    StaleHuman,
    ExceedsLimits,
    HumanReach,
}

impl Reason {
    fn name(self) -> &'static str {
        match self {
            Reason::Gap => "gap",
            Reason::NoHuman => "no_human",
            Reason::StaleHuman => "stale_human",
            Reason::ExceedsLimits => "exceeds_limits",
            Reason::HumanReach => "human_reach_error",
        }
    }
}

struct Series {
    t0: f64,
    width: f64,
    buckets: Vec<SeriesPoint>,
}

fn empty_point(t: f64, t_end: f64) -> SeriesPoint {
    SeriesPoint {
        t,
        t_end,
        min_separation: None,
        energy_nominal: None,
        energy_bound: None,
        threshold: None,
        violation: false,
        inconclusive: false,
    }
}

fn min_opt(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}
fn max_opt(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.max(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

impl Series {
    /// The bucket for time `t`, merging pairs (doubling the width) when full. Returns the index
    /// and whether the bucket is new.
    fn bucket(&mut self, t: f64) -> (usize, bool) {
        loop {
            let idx = ((t - self.t0) / self.width).floor().max(0.0) as usize;
            if idx < SERIES_BUCKETS {
                let mut new = false;
                while self.buckets.len() <= idx {
                    let k = self.buckets.len() as f64;
                    self.buckets.push(empty_point(
                        self.t0 + k * self.width,
                        self.t0 + (k + 1.0) * self.width,
                    ));
                    new = true;
                }
                return (idx, new);
            }
            // Merge pairs.
            let n = self.buckets.len();
            for i in 0..n.div_ceil(2) {
                let a = self.buckets[2 * i];
                let merged = if 2 * i + 1 < n {
                    let b = self.buckets[2 * i + 1];
                    SeriesPoint {
                        t: a.t,
                        t_end: b.t_end,
                        min_separation: min_opt(a.min_separation, b.min_separation),
                        energy_nominal: a.energy_nominal.or(b.energy_nominal),
                        energy_bound: max_opt(a.energy_bound, b.energy_bound),
                        threshold: min_opt(a.threshold, b.threshold),
                        violation: a.violation || b.violation,
                        inconclusive: a.inconclusive || b.inconclusive,
                    }
                } else {
                    SeriesPoint {
                        t_end: a.t + 2.0 * self.width,
                        ..a
                    }
                };
                self.buckets[i] = merged;
            }
            self.buckets.truncate(n.div_ceil(2));
            self.width *= 2.0;
        }
    }
}

/// Streaming auditor of one log: feed records in time order, then [`Auditor::finish`].
/// After warm-up, robot samples allocate nothing.
pub struct Auditor {
    cfg: AuditConfig,
    robot: RobotModel,
    human: HumanModel,
    constraints: Vec<Constraint>,
    environment: Vec<Capsule>,
    names: ModelNames,
    rreach: RobotReach,
    hreach: HumanReach,
    n: usize,
    parts: usize,
    links: usize,
    cap_link: Vec<usize>,
    cap_frame: Vec<usize>,
    cap_local: Vec<Capsule>,
    /// Sphere containing the robot for every configuration.
    global_sphere: Capsule,
    // Buffers.
    rcaps: Vec<Capsule>,
    hcaps: Vec<Capsule>,
    energies: Vec<f64>,
    /// Robot-occupancy scratch (the energy bound of the same box reuses its frames).
    scratch: Box<ReachScratch>,
    frames: Vec<Isometry3<f64>>,
    nom_caps: Vec<Capsule>,
    nom_energies: Vec<f64>,
    contact: Vec<u128>,
    hits: Vec<Hit>,
    // State.
    prev: Option<Sample>,
    /// Buffered samples whose spans all use the human measurement `block_human`.
    block: Vec<Sample>,
    block_human: Option<usize>,
    humans: [Option<HumanMeasurement>; 2],
    latest_human: Option<usize>,
    span_human: Option<usize>,
    span_index: u64,
    open: Vec<Option<Open>>,
    violations: Vec<Violation>,
    inconclusive: Vec<(InconclusiveSpan, Reason, u64)>,
    samples: u64,
    human_records: u64,
    /// Measurement time of a human record that arrived after the last robot sample (not yet
    /// covered by any span).
    unused_human_t_meas: Option<f64>,
    t_first: f64,
    t_last: f64,
    violating_samples: u64,
    certain_samples: u64,
    last_span_violated: bool,
    last_span_certain: bool,
    inconclusive_duration: f64,
    min_separation: Option<f64>,
    success: Option<bool>,
    series: Series,
}

fn bounding_sphere(caps: &[Capsule]) -> Capsule {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in caps {
        for p in [c.p1(), c.p2()] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let centre = [
        0.5 * lo[0] + 0.5 * hi[0],
        0.5 * lo[1] + 0.5 * hi[1],
        0.5 * lo[2] + 0.5 * hi[2],
    ];
    let mut r: f64 = 0.0;
    for c in caps {
        let d1 = dist3_up(&centre, &c.p1().coords.into());
        let d2 = dist3_up(&centre, &c.p2().coords.into());
        r = r.max(add_up(d1.max(d2), c.radius()));
    }
    Capsule::new_unchecked(Point3::from(centre), Point3::from(centre), r)
}

/// A ball around the base origin containing every link capsule for every configuration: a point
/// of a capsule carried by frame k is within Σ_{j≤k} |t_j| + |p| + r of the base origin (rotations
/// preserve lengths), rounded up and padded for the rounding of the model's fixed transforms.
fn reach_sphere(robot: &RobotModel, tracking_error: f64) -> Capsule {
    use pacs_reach::rounding::norm3_up;
    let mut cum = [0.0; MAX_DOF + 1];
    for (j, joint) in robot.joints().iter().enumerate() {
        let t = joint.origin.translation.vector;
        cum[j + 1] = add_up(cum[j], norm3_up(t.x, t.y, t.z));
    }
    let mut r: f64 = 0.0;
    for l in robot.links() {
        for c in &l.capsules {
            let (a, b) = (c.p1(), c.p2());
            let p = norm3_up(a.x, a.y, a.z).max(norm3_up(b.x, b.y, b.z));
            r = r.max(add_up(add_up(cum[l.frame], p), c.radius()));
        }
    }
    let r = add_up(mul_up(r, 1.0 + 1e-12), add_up(tracking_error, 1e-9));
    let base = Point3::from(robot.base().translation.vector);
    Capsule::new_unchecked(base, base, r)
}

/// Signed separation lower bound (m) of two capsules: negative values bound the overlap depth.
fn signed_separation(a: &Capsule, b: &Capsule) -> f64 {
    let d = pacs_reach::geometry::segment_distance_lower_bound(&a.p1(), &a.p2(), &b.p1(), &b.p2());
    sub_down(d, add_up(a.radius(), b.radius()))
}

/// True only if the two capsules certainly overlap or touch (exact axis distance ≤ sum of radii).
fn certainly_touch(a: &Capsule, b: &Capsule) -> bool {
    segment_distance_upper_bound(&a.p1(), &a.p2(), &b.p1(), &b.p2())
        <= sub_down(a.radius() + b.radius(), (a.radius() + b.radius()) * 1e-15)
}

impl Auditor {
    /// Prepare an auditor for the models; fails if the constraints do not resolve against the
    /// human model, the config is invalid, or the robot has more than [`MAX_CAPSULES`] capsules.
    pub fn new(models: LogModels, cfg: AuditConfig) -> Result<Self, String> {
        cfg.validate()?;
        let tc = models
            .constraints
            .resolve(&models.human)
            .map_err(|e| format!("constraints: {e}"))?;
        let rreach = RobotReach::try_new(&models.robot, cfg.tracking_error)
            .map_err(|e| format!("tracking_error: {e}"))?;
        let ncaps = rreach.capsule_count();
        if ncaps > MAX_CAPSULES {
            return Err(format!(
                "robot `{}` has {ncaps} capsules; the audit supports at most {MAX_CAPSULES}",
                models.robot.name()
            ));
        }
        if models.robot.links().len() > MAX_CAPSULES {
            return Err(format!(
                "robot `{}` has more than {MAX_CAPSULES} links",
                models.robot.name()
            ));
        }
        if ncaps == 0 {
            return Err(format!("robot `{}` has no capsules", models.robot.name()));
        }
        let mut cap_link = vec![0; ncaps];
        for (l, &(s, e)) in rreach.link_ranges().iter().enumerate() {
            for c in &mut cap_link[s..e] {
                *c = l;
            }
        }
        let cap_frame: Vec<usize> = (0..ncaps).map(|i| rreach.capsule_frame(i)).collect();
        let cap_local: Vec<Capsule> = models
            .robot
            .links()
            .iter()
            .flat_map(|l| l.capsules.iter().copied())
            .collect();
        let zero = Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        let rcaps = vec![zero; ncaps];
        let global_sphere = reach_sphere(&models.robot, cfg.tracking_error);
        let n = models.robot.dof();
        let parts = models.human.body_parts().len();
        let names = ModelNames {
            robot: models.robot.name().to_string(),
            human: models.human.spec().name.clone(),
            constraints: tc.name.clone(),
            robot_v_max: models.robot.limits().v_max().to_vec(),
            robot_a_max: models.robot.limits().a_max().to_vec(),
            human_v_max: models.human.v_max().to_vec(),
            human_measurement_error_pos: models.human.measurement_error_pos(),
            human_delay: models.human.delay(),
            environment_shapes: models.environment.len(),
        };
        let links = models.robot.links().len();
        Ok(Self {
            hreach: HumanReach::new(models.human.clone(), cfg.human_model),
            rreach,
            cfg,
            n,
            parts,
            links,
            cap_link,
            cap_frame,
            cap_local,
            global_sphere,
            rcaps,
            hcaps: vec![zero; parts],
            energies: vec![0.0; n + 1],
            scratch: Box::default(),
            frames: vec![Isometry3::identity(); n + 1],
            nom_caps: vec![zero; ncaps],
            nom_energies: vec![0.0; n + 1],
            contact: vec![0; parts],
            hits: Vec::with_capacity(parts * links),
            prev: None,
            block: Vec::with_capacity(BLOCK_SPANS + 1),
            block_human: None,
            humans: [None, None],
            latest_human: None,
            span_human: None,
            span_index: 0,
            open: vec![None; parts * links],
            violations: Vec::new(),
            inconclusive: Vec::new(),
            samples: 0,
            human_records: 0,
            unused_human_t_meas: None,
            t_first: f64::NAN,
            t_last: f64::NAN,
            violating_samples: 0,
            certain_samples: 0,
            last_span_violated: false,
            last_span_certain: false,
            inconclusive_duration: 0.0,
            min_separation: None,
            success: None,
            series: Series {
                t0: 0.0,
                width: 1e-3,
                buckets: Vec::with_capacity(SERIES_BUCKETS + 1),
            },
            constraints: tc.per_part,
            environment: models.environment,
            robot: models.robot,
            human: models.human,
            names,
        })
    }

    /// Robot degrees of freedom.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// A human measurement logged at `t`, taken at `t_meas` (s). Errors name the field and value.
    pub fn push_human(
        &mut self,
        t: f64,
        t_meas: f64,
        positions: &[[f64; 3]],
    ) -> Result<(), String> {
        if !t_meas.is_finite() {
            return Err(format!("t_meas: value {t_meas} is not finite"));
        }
        if t_meas > t {
            return Err(format!(
                "t_meas: {t_meas} s is after the record's t = {t} s (measurements cannot come from the future)"
            ));
        }
        let m = HumanMeasurement::new(&self.human, t_meas, positions, None)
            .map_err(|e| e.to_string())?;
        // Check the pending spans first: afterwards only `span_human`'s slot is still needed.
        self.flush_block();
        self.block_human = self.span_human;
        let slot = match self.span_human {
            Some(s) => 1 - s,
            None => 0,
        };
        self.humans[slot] = Some(m);
        self.latest_human = Some(slot);
        self.human_records += 1;
        self.unused_human_t_meas = Some(t_meas);
        Ok(())
    }

    /// An event; `success` and `failure` set the task outcome (the last one counts).
    pub fn push_event(&mut self, name: &str) {
        match name {
            "success" => self.success = Some(true),
            "failure" => self.success = Some(false),
            _ => {}
        }
    }

    /// A robot sample at `t` (s): positions (rad), optional velocities (rad/s). Checks the span
    /// from the previous sample. Errors (wrong length, non-finite value) name the field.
    pub fn push_robot(&mut self, t: f64, q: &[f64], dq: Option<&[f64]>) -> Result<(), String> {
        let n = self.n;
        self.unused_human_t_meas = None;
        if q.len() != n {
            return Err(format!(
                "q: expected {n} joint positions for robot `{}`, found {}",
                self.names.robot,
                q.len()
            ));
        }
        if let Some((i, x)) = q.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(format!("q[{i}]: value {x} is not finite"));
        }
        let mut s = Sample {
            t,
            q: [0.0; MAX_DOF],
            dq: [0.0; MAX_DOF],
            has_dq: false,
        };
        s.q[..n].copy_from_slice(q);
        if let Some(dq) = dq {
            if dq.len() != n {
                return Err(format!(
                    "dq: expected {n} joint velocities for robot `{}`, found {}",
                    self.names.robot,
                    dq.len()
                ));
            }
            if let Some((i, x)) = dq.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(format!("dq[{i}]: value {x} is not finite"));
            }
            s.dq[..n].copy_from_slice(dq);
            s.has_dq = true;
        }
        if self.prev.is_none() {
            self.t_first = t;
            self.series.t0 = t;
        }
        if self.block.is_empty() {
            self.block_human = self.span_human;
        } else if self.span_human != self.block_human {
            // The new span uses another human measurement: close the block.
            self.flush_block();
            self.block_human = self.span_human;
        }
        self.block.push(s);
        if self.block.len() > BLOCK_SPANS {
            self.flush_block();
            self.block_human = self.latest_human;
        }
        self.prev = Some(s);
        self.span_human = self.latest_human;
        self.samples += 1;
        self.t_last = t;
        Ok(())
    }

    fn mark_inconclusive(&mut self, t0: f64, t1: f64, reason: Reason) {
        let idx = self.span_index;
        if let Some((last, r, last_idx)) = self.inconclusive.last_mut()
            && *r == reason
            && *last_idx + 1 == idx
        {
            last.t_end = t1;
            last.spans += 1;
            *last_idx = idx;
        } else {
            self.inconclusive.push((
                InconclusiveSpan {
                    t_start: t0,
                    t_end: t1,
                    reason: reason.name().to_string(),
                    spans: 1,
                },
                reason,
                idx,
            ));
        }
    }

    /// Joint position and velocity boxes over the span (outward-rounded). Returns false if the
    /// samples contradict the velocity or acceleration limits (the boxes are then widened to
    /// contain the samples, but the span is inconclusive).
    #[allow(clippy::too_many_arguments)]
    fn boxes(
        &self,
        s0: &Sample,
        s1: &Sample,
        q_lo: &mut [f64; MAX_DOF],
        q_hi: &mut [f64; MAX_DOF],
        dq_lo: &mut [f64; MAX_DOF],
        dq_hi: &mut [f64; MAX_DOF],
    ) -> bool {
        let lim = self.robot.limits();
        let dt = s1.t - s0.t;
        let dt_up = sub_up(s1.t, s0.t);
        let dt_down = sub_down(s1.t, s0.t).max(0.0);
        let slack = 1.0 + self.cfg.limit_slack;
        let mut ok = true;
        for j in 0..self.n {
            let (a, b) = (s0.q[j], s1.q[j]);
            let v = lim.v_max()[j];
            let acc = lim.a_max()[j];
            let reach = mul_up(v, dt_up);
            // Position: q(t) ∈ [(a+b−vΔ)/2, (a+b+vΔ)/2]; outward-rounded, 1 ulp for decimal parsing.
            let lo = 0.5 * sub_down(pacs_reach::rounding::add_down(a, b), reach);
            let hi = 0.5 * add_up(add_up(a, b), reach);
            q_lo[j] = lo.min(a).min(b).next_down();
            q_hi[j] = hi.max(a).max(b).next_up();
            if (b - a).abs() > v * dt * slack + f64::MIN_POSITIVE {
                ok = false;
            }
            // Velocity.
            let acc_dt = mul_up(acc, dt_up);
            let (mut vlo, mut vhi);
            if s0.has_dq && s1.has_dq {
                let (c, d) = (s0.dq[j], s1.dq[j]);
                vlo = 0.5 * sub_down(pacs_reach::rounding::add_down(c, d), acc_dt);
                vhi = 0.5 * add_up(add_up(c, d), acc_dt);
                if (d - c).abs() > acc * dt * slack + f64::MIN_POSITIVE
                    || c.abs() > v * slack
                    || d.abs() > v * slack
                {
                    ok = false;
                }
                vlo = vlo.min(c).min(d);
                vhi = vhi.max(c).max(d);
            } else if dt_down > 0.0 {
                // The mean velocity (b−a)/Δ is attained somewhere in the span.
                let m_lo = pacs_reach::rounding::div_down(sub_down(b, a), dt_up.max(dt_down));
                let m_lo = m_lo.min(pacs_reach::rounding::div_down(sub_down(b, a), dt_down));
                let m_hi = pacs_reach::rounding::div_up(sub_up(b, a), dt_down)
                    .max(pacs_reach::rounding::div_up(sub_up(b, a), dt_up));
                vlo = sub_down(m_lo, acc_dt);
                vhi = add_up(m_hi, acc_dt);
            } else {
                vlo = -v;
                vhi = v;
            }
            // Clip to the velocity limits (if consistent), keeping a non-empty box.
            let clo = vlo.max(-v);
            let chi = vhi.min(v);
            if clo <= chi {
                vlo = clo;
                vhi = chi;
            } else {
                ok = false;
            }
            dq_lo[j] = vlo.next_down();
            dq_hi[j] = vhi.next_up();
        }
        ok
    }

    /// Check the buffered spans (all using the human measurement `block_human`), keeping the
    /// last sample as the start of the next block.
    fn flush_block(&mut self) {
        let m = self.block.len();
        if m >= 2 {
            let slot = self.block_human;
            if !self.check_block(slot) {
                for i in 0..m - 1 {
                    let (a, b) = (self.block[i], self.block[i + 1]);
                    self.check_span(&a, &b, slot);
                }
            }
            let last = self.block[m - 1];
            self.block.clear();
            self.block.push(last);
        }
    }

    /// Which robot capsules (bit mask per body part, in `self.contact`) may touch each body part,
    /// from the occupancies in `self.rcaps` and `self.hcaps`: a bounding-sphere test first, then
    /// capsule by capsule. Lowers `sep` to the separation lower bound (0 on possible contact);
    /// returns whether any contact is possible.
    fn contact_masks(&mut self, sep: &mut f64) -> bool {
        let sphere = bounding_sphere(&self.rcaps);
        let mut any_contact = false;
        for p in 0..self.parts {
            let h = &self.hcaps[p];
            let d = capsule_distance_lower_bound(&sphere, h);
            if d > 0.0 {
                *sep = sep.min(d);
                self.contact[p] = 0;
                continue;
            }
            let mut mask = 0u128;
            for (c, rc) in self.rcaps.iter().enumerate() {
                let dc = capsule_distance_lower_bound(rc, h);
                if dc > 0.0 {
                    *sep = sep.min(dc);
                } else {
                    mask |= 1u128 << c;
                    *sep = 0.0;
                }
            }
            self.contact[p] = mask;
            any_contact |= mask != 0;
        }
        any_contact
    }

    /// Fast path: one check over the union of the block's span boxes and the human occupancy
    /// over the whole block (both supersets of every span's enclosures, so "no violation
    /// possible" holds for every span). Returns false, having recorded nothing, if the block is
    /// not provably clean; the caller then checks span by span.
    fn check_block(&mut self, slot: Option<usize>) -> bool {
        let m = self.block.len();
        let n = self.n;
        if m < 3 {
            return false;
        }
        let Some(slot) = slot else { return false };
        let Some(meas) = self.humans[slot].as_ref() else {
            return false;
        };
        let (t0, t1) = (self.block[0].t, self.block[m - 1].t);
        if t1 - meas.time() > self.cfg.max_human_age {
            return false;
        }
        if self
            .hreach
            .occupancy_into(meas, t0, t1, &mut self.hcaps)
            .is_err()
        {
            return false;
        }
        let mut u_qlo = [f64::INFINITY; MAX_DOF];
        let mut u_qhi = [f64::NEG_INFINITY; MAX_DOF];
        let mut u_dlo = [f64::INFINITY; MAX_DOF];
        let mut u_dhi = [f64::NEG_INFINITY; MAX_DOF];
        for i in 0..m - 1 {
            let (a, b) = (&self.block[i], &self.block[i + 1]);
            if b.t - a.t > self.cfg.max_gap {
                return false;
            }
            let (mut ql, mut qh, mut dl, mut dh) = (
                [0.0; MAX_DOF],
                [0.0; MAX_DOF],
                [0.0; MAX_DOF],
                [0.0; MAX_DOF],
            );
            if !self.boxes(a, b, &mut ql, &mut qh, &mut dl, &mut dh) {
                return false;
            }
            for j in 0..n {
                u_qlo[j] = u_qlo[j].min(ql[j]);
                u_qhi[j] = u_qhi[j].max(qh[j]);
                u_dlo[j] = u_dlo[j].min(dl[j]);
                u_dhi[j] = u_dhi[j].max(dh[j]);
            }
        }
        let mut sep = f64::INFINITY;
        let mut clear = true;
        for h in &self.hcaps {
            let d = capsule_distance_lower_bound(&self.global_sphere, h);
            if d > 0.0 {
                sep = sep.min(d);
            } else {
                clear = false;
                break;
            }
        }
        let mut pfl_seen: Option<(f64, f64)> = None;
        if !clear {
            sep = f64::INFINITY;
            if self
                .rreach
                .occupancy_with(&mut self.scratch, &u_qlo[..n], &u_qhi[..n], &mut self.rcaps)
                .is_err()
            {
                return false;
            }
            let any_contact = self.contact_masks(&mut sep);
            if any_contact {
                let at_rest = (0..n)
                    .all(|j| u_dlo[j] >= -self.cfg.rest_speed && u_dhi[j] <= self.cfg.rest_speed);
                let mut energies_done = false;
                for p in 0..self.parts {
                    let mask = self.contact[p];
                    if mask == 0 {
                        continue;
                    }
                    let constraint = self.constraints[p];
                    if matches!(constraint, Constraint::Ssm) {
                        if !at_rest {
                            return false;
                        }
                        continue;
                    }
                    if !energies_done {
                        if self
                            .rreach
                            .subchain_energy_bounds_with(
                                &mut self.scratch,
                                &u_qlo[..n],
                                &u_qhi[..n],
                                &u_dlo[..n],
                                &u_dhi[..n],
                                &mut self.energies,
                            )
                            .is_err()
                        {
                            return false;
                        }
                        energies_done = true;
                    }
                    let part_clamp = self.part_may_clamp(p);
                    for c in 0..self.rcaps.len() {
                        if mask & (1u128 << c) == 0 {
                            continue;
                        }
                        let e = self.energies[self.cap_frame[c]];
                        let thr = constraint.threshold(part_clamp || self.links_may_clamp(mask, c));
                        if e > thr {
                            return false;
                        }
                        pfl_seen = Some(match pfl_seen {
                            Some((a, b)) => (a.max(e), b.min(thr)),
                            None => (e, thr),
                        });
                    }
                }
            }
        }
        // Every span of the block is clean: per-span bookkeeping only.
        for i in 0..m - 1 {
            let (a, b) = (self.block[i], self.block[i + 1]);
            self.span_index += 1;
            let (bidx, new_bucket) = self.series.bucket(a.t);
            if new_bucket {
                self.series.buckets[bidx].energy_nominal = Some(self.nominal_energy(&a, &b));
            }
            if let Some((e, thr)) = pfl_seen {
                let bk = &mut self.series.buckets[bidx];
                bk.energy_bound = max_opt(bk.energy_bound, Some(e));
                bk.threshold = min_opt(bk.threshold, Some(thr));
            }
            self.record_separation(bidx, sep);
        }
        self.last_span_violated = false;
        self.last_span_certain = false;
        true
    }

    /// Nominal whole-robot kinetic energy (J) at `a` (velocity logged, else the span's mean).
    fn nominal_energy(&self, a: &Sample, b: &Sample) -> f64 {
        let n = self.n;
        let dt = b.t - a.t;
        let mut dq = [0.0; MAX_DOF];
        for j in 0..n {
            dq[j] = if a.has_dq {
                a.dq[j]
            } else if dt > 0.0 {
                (b.q[j] - a.q[j]) / dt
            } else {
                0.0
            };
        }
        self.robot.kinetic_energy(&a.q[..n], &dq[..n])
    }

    fn check_span(&mut self, s0: &Sample, s1: &Sample, span_human: Option<usize>) {
        self.span_index += 1;
        let (t0, t1) = (s0.t, s1.t);
        let dt = t1 - t0;
        let (bidx, new_bucket) = self.series.bucket(t0);
        let mut certain = false;
        let finish_span = |this: &mut Self, violated: bool, certain: bool| {
            if violated {
                this.violating_samples += 1;
            }
            if certain {
                this.certain_samples += 1;
            }
            this.last_span_violated = violated;
            this.last_span_certain = certain;
            this.series.buckets[bidx].violation |= violated;
        };
        if dt > self.cfg.max_gap {
            self.mark_inconclusive(t0, t1, Reason::Gap);
            self.inconclusive_duration += dt;
            self.series.buckets[bidx].inconclusive = true;
            finish_span(self, false, false);
            return;
        }
        let Some(slot) = span_human else {
            self.mark_inconclusive(t0, t1, Reason::NoHuman);
            self.inconclusive_duration += dt;
            self.series.buckets[bidx].inconclusive = true;
            finish_span(self, false, false);
            return;
        };
        let Some(m) = self.humans[slot].as_ref() else {
            // Unreachable by construction; never let an unchecked span pass.
            self.mark_inconclusive(t0, t1, Reason::NoHuman);
            self.inconclusive_duration += dt;
            finish_span(self, false, false);
            return;
        };
        if t1 - m.time() > self.cfg.max_human_age {
            self.mark_inconclusive(t0, t1, Reason::StaleHuman);
            self.inconclusive_duration += dt;
            self.series.buckets[bidx].inconclusive = true;
            finish_span(self, false, false);
            return;
        }
        if let Err(_e) = self.hreach.occupancy_into(m, t0, t1, &mut self.hcaps) {
            self.mark_inconclusive(t0, t1, Reason::HumanReach);
            self.inconclusive_duration += dt;
            self.series.buckets[bidx].inconclusive = true;
            finish_span(self, false, false);
            return;
        }
        let mut q_lo = [0.0; MAX_DOF];
        let mut q_hi = [0.0; MAX_DOF];
        let mut dq_lo = [0.0; MAX_DOF];
        let mut dq_hi = [0.0; MAX_DOF];
        let n = self.n;
        let consistent = self.boxes(s0, s1, &mut q_lo, &mut q_hi, &mut dq_lo, &mut dq_hi);
        if !consistent {
            self.mark_inconclusive(t0, t1, Reason::ExceedsLimits);
            self.inconclusive_duration += dt;
            self.series.buckets[bidx].inconclusive = true;
        }
        if new_bucket {
            self.series.buckets[bidx].energy_nominal = Some(self.nominal_energy(s0, s1));
        }
        // Broad phase 1: the sphere around every configuration within the joint limits.
        let lim = self.robot.limits();
        let within_limits = (0..n).all(|j| q_lo[j] >= lim.q_min()[j] && q_hi[j] <= lim.q_max()[j]);
        let mut sep = f64::INFINITY;
        if within_limits {
            let mut all_clear = true;
            for h in &self.hcaps {
                let d = capsule_distance_lower_bound(&self.global_sphere, h);
                if d > 0.0 {
                    sep = sep.min(d);
                } else {
                    all_clear = false;
                    break;
                }
            }
            if all_clear {
                self.record_separation(bidx, sep);
                finish_span(self, false, false);
                return;
            }
            sep = f64::INFINITY;
        }
        // Robot occupancy over the span.
        if self
            .rreach
            .occupancy_with(&mut self.scratch, &q_lo[..n], &q_hi[..n], &mut self.rcaps)
            .is_err()
        {
            // Boxes are finite and ordered by construction; treat a failure as unchecked.
            self.mark_inconclusive(t0, t1, Reason::ExceedsLimits);
            self.inconclusive_duration += dt;
            finish_span(self, false, false);
            return;
        }
        let any_contact = self.contact_masks(&mut sep);
        self.record_separation(bidx, sep);
        if !any_contact {
            finish_span(self, false, false);
            return;
        }
        // Narrow phase: constraints of the parts that may be touched.
        let at_rest =
            (0..n).all(|j| dq_lo[j] >= -self.cfg.rest_speed && dq_hi[j] <= self.cfg.rest_speed);
        if self
            .rreach
            .subchain_energy_bounds_with(
                &mut self.scratch,
                &q_lo[..n],
                &q_hi[..n],
                &dq_lo[..n],
                &dq_hi[..n],
                &mut self.energies,
            )
            .is_err()
        {
            self.energies.iter_mut().for_each(|e| *e = f64::INFINITY);
        }
        self.hits.clear();
        for p in 0..self.parts {
            let mask = self.contact[p];
            if mask == 0 {
                continue;
            }
            let constraint = self.constraints[p];
            let part_clamp = self.part_may_clamp(p);
            let mut link_done = 0u128;
            for c in 0..self.rcaps.len() {
                if mask & (1u128 << c) == 0 {
                    continue;
                }
                let l = self.cap_link[c];
                if link_done & (1u128 << l.min(127)) != 0 {
                    continue;
                }
                link_done |= 1u128 << l.min(127);
                let e = self.energies[self.cap_frame[c]];
                let (kind, thr, constrained, bad) = match constraint {
                    Constraint::Ssm => (ConstraintKind::Ssm, 0.0, false, !at_rest),
                    Constraint::Pfl { .. } => {
                        let clamp = part_clamp || self.links_may_clamp(mask, c);
                        let thr = constraint.threshold(clamp);
                        let b = &mut self.series.buckets[bidx];
                        b.energy_bound = max_opt(b.energy_bound, Some(e));
                        b.threshold = min_opt(b.threshold, Some(thr));
                        (ConstraintKind::Pfl, thr, clamp, e > thr)
                    }
                };
                if bad {
                    self.hits.push(Hit {
                        part: p,
                        link: l,
                        kind,
                        energy: e,
                        threshold: thr,
                        constrained,
                        certain: false,
                        separation: f64::INFINITY,
                    });
                }
            }
        }
        if self.hits.is_empty() {
            finish_span(self, false, false);
            return;
        }
        let violated = true;
        // Certain check at both recorded samples, with the measured keypoints.
        for s in [s0, s1] {
            certain |= self.certain_at(s, s0, s1, slot);
        }
        let idx = self.span_index;
        for k in 0..self.hits.len() {
            let h = self.hits[k];
            let key = h.part * self.links + h.link;
            let extend =
                matches!(&self.open[key], Some(o) if o.last_span + 1 == idx && o.kind == h.kind);
            if extend {
                let Some(o) = self.open[key].as_mut() else {
                    continue;
                };
                o.v_end = t1;
                o.min_sep = o.min_sep.min(h.separation);
                o.energy = o.energy.max(h.energy);
                o.threshold = o.threshold.min(h.threshold);
                o.constrained |= h.constrained;
                o.certain |= h.certain;
                o.spans += 1;
                o.last_span = idx;
            } else {
                if let Some(o) = self.open[key].take() {
                    self.close(key, o);
                }
                self.open[key] = Some(Open {
                    v_start: t0,
                    v_end: t1,
                    kind: h.kind,
                    min_sep: h.separation,
                    energy: h.energy,
                    threshold: h.threshold,
                    constrained: h.constrained,
                    certain: h.certain,
                    spans: 1,
                    last_span: idx,
                });
            }
        }
        finish_span(self, violated, certain);
    }

    fn record_separation(&mut self, bidx: usize, sep: f64) {
        if sep.is_finite() {
            self.min_separation = min_opt(self.min_separation, Some(sep));
            let b = &mut self.series.buckets[bidx];
            b.min_separation = min_opt(b.min_separation, Some(sep));
        }
    }

    /// Body part `p`'s occupancy may touch an environment shape or a body part it can be clamped
    /// against.
    fn part_may_clamp(&self, p: usize) -> bool {
        let h = &self.hcaps[p];
        self.environment
            .iter()
            .any(|e| capsule_distance_lower_bound(e, h) <= 0.0)
            || (0..self.parts).any(|o| {
                o != p
                    && self.human.clampable(p, o)
                    && capsule_distance_lower_bound(&self.hcaps[o], h) <= 0.0
            })
    }

    /// Another link that may touch the same body part (mask) can clamp it against capsule `c`'s link.
    fn links_may_clamp(&self, mask: u128, c: usize) -> bool {
        let (l, f) = (self.cap_link[c], self.cap_frame[c]);
        (0..self.rcaps.len()).any(|o| {
            mask & (1u128 << o) != 0
                && self.cap_link[o] != l
                && (self.cfg.clamp_adjacent_links || self.cap_frame[o].abs_diff(f) > 1)
        })
    }

    /// Evaluate the span's hits at the recorded sample `s` with the measured keypoints; updates
    /// each hit's `certain` and `separation`. Returns whether any hit is certain there.
    fn certain_at(&mut self, s: &Sample, s0: &Sample, s1: &Sample, slot: usize) -> bool {
        let n = self.n;
        let Some(m) = self.humans[slot].as_ref() else {
            return false;
        };
        let dt = s1.t - s0.t;
        let mut dq = [0.0; MAX_DOF];
        let known_dq = s.has_dq || dt > 0.0;
        for j in 0..n {
            dq[j] = if s.has_dq {
                s.dq[j]
            } else if dt > 0.0 {
                (s1.q[j] - s0.q[j]) / dt
            } else {
                0.0
            };
        }
        self.robot.frames_into(&s.q[..n], &mut self.frames);
        for (c, local) in self.cap_local.iter().enumerate() {
            self.nom_caps[c] = local.transformed(&self.frames[self.cap_frame[c]]);
        }
        self.robot
            .subchain_energies_into(&s.q[..n], &dq[..n], &mut self.nom_energies);
        let moving = known_dq && dq[..n].iter().any(|v| v.abs() > self.cfg.rest_speed);
        let pos = m.positions();
        let part_cap = |p: usize| {
            let bp = &self.human.body_parts()[p];
            Capsule::new_unchecked(pos[bp.from], pos[bp.to], bp.thickness * 0.5)
        };
        let mut any = false;
        for k in 0..self.hits.len() {
            let h = self.hits[k];
            let pc = part_cap(h.part);
            let (s_, e_) = self.robot_link_range(h.link);
            let mut touch = false;
            let mut sep = f64::INFINITY;
            let mut frame = 0;
            for c in s_..e_ {
                sep = sep.min(signed_separation(&self.nom_caps[c], &pc));
                touch |= certainly_touch(&self.nom_caps[c], &pc);
                frame = self.cap_frame[c];
            }
            let certain = touch
                && match h.kind {
                    ConstraintKind::Ssm => moving,
                    ConstraintKind::Pfl => {
                        let clamp = self.environment.iter().any(|e| certainly_touch(e, &pc))
                            || (0..self.parts).any(|o| {
                                o != h.part
                                    && self.human.clampable(h.part, o)
                                    && certainly_touch(&part_cap(o), &pc)
                            })
                            || (0..self.nom_caps.len()).any(|o| {
                                self.cap_link[o] != h.link
                                    && (self.cfg.clamp_adjacent_links
                                        || self.cap_frame[o].abs_diff(frame) > 1)
                                    && certainly_touch(&self.nom_caps[o], &pc)
                            });
                        let thr = self.constraints[h.part].threshold(clamp);
                        known_dq && self.nom_energies[frame] > thr
                    }
                };
            let hit = &mut self.hits[k];
            hit.separation = hit.separation.min(sep);
            hit.certain |= certain;
            any |= certain;
        }
        any
    }

    fn robot_link_range(&self, link: usize) -> (usize, usize) {
        self.rreach.link_ranges()[link]
    }

    /// Close the audit: the verdict, intervals and metrics.
    pub fn finish(
        mut self,
        log: &str,
        meta: serde_json::Map<String, serde_json::Value>,
    ) -> RunResult {
        self.flush_block();
        for key in 0..self.open.len() {
            if let Some(o) = self.open[key].take() {
                self.close(key, o);
            }
        }
        self.violations.sort_by(|a, b| {
            a.t_start
                .total_cmp(&b.t_start)
                .then(a.body_part.cmp(&b.body_part))
        });
        if self.samples >= 2 && self.last_span_violated {
            self.violating_samples += 1;
        }
        if self.samples >= 2 && self.last_span_certain {
            self.certain_samples += 1;
        }
        let mut inconclusive: Vec<InconclusiveSpan> =
            self.inconclusive.into_iter().map(|(s, _, _)| s).collect();
        // A human record after the last robot sample that describes a state within the logged
        // robot time is covered by no span: it was not checked, so the log cannot pass.
        if let Some(tm) = self.unused_human_t_meas
            && self.samples >= 1
            && tm - self.human.delay() <= self.t_last
        {
            inconclusive.push(InconclusiveSpan {
                t_start: self.t_last,
                t_end: self.t_last,
                reason: "human_record_after_last_robot_sample".into(),
                spans: 0,
            });
        }
        if self.samples < 2 {
            inconclusive.push(InconclusiveSpan {
                t_start: if self.samples == 1 { self.t_first } else { 0.0 },
                t_end: if self.samples == 1 { self.t_last } else { 0.0 },
                reason: "fewer_than_two_robot_samples".into(),
                spans: 0,
            });
        }
        let verdict = if !self.violations.is_empty() {
            Verdict::Fail
        } else if !inconclusive.is_empty() {
            Verdict::Inconclusive
        } else {
            Verdict::Pass
        };
        let samples = self.samples;
        let metrics = Metrics {
            samples,
            human_records: self.human_records,
            duration: if samples > 0 {
                self.t_last - self.t_first
            } else {
                0.0
            },
            violation_fraction: if samples > 0 {
                self.violating_samples as f64 / samples as f64
            } else {
                0.0
            },
            violating_samples: self.violating_samples,
            certain_violating_samples: self.certain_samples,
            inconclusive_duration: self.inconclusive_duration,
            min_separation: self.min_separation,
            success: self.success,
            safe_success: self.success.map(|s| s && verdict == Verdict::Pass),
        };
        RunResult {
            log: log.to_string(),
            verdict,
            violations: self.violations,
            inconclusive,
            metrics,
            meta,
            models: self.names,
            series: self.series.buckets,
        }
    }

    fn close(&mut self, key: usize, o: Open) {
        let part = key / self.links;
        let link = key % self.links;
        self.violations.push(Violation {
            t_start: o.v_start,
            t_end: o.v_end,
            constraint: o.kind,
            body_part: self.human.body_parts()[part].name.clone(),
            link: self.robot.links()[link].name.clone(),
            min_separation: o.min_sep,
            energy: o.energy,
            threshold: o.threshold,
            constrained: o.constrained,
            certain: o.certain,
            spans: o.spans,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reach_sphere_contains_the_robot_in_every_sampled_configuration() {
        let robot = RobotModel::builtin("fr3").unwrap();
        let s = reach_sphere(&robot, 0.0);
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            // Any configuration, not only within the limits.
            let q: Vec<f64> = (0..7)
                .map(|_| (next() - 0.5) * 4.0 * std::f64::consts::PI)
                .collect();
            for (_, c) in robot.capsules_world(&q) {
                for p in [c.p1(), c.p2()] {
                    assert!((p - s.p1()).norm() + c.radius() <= s.radius());
                }
            }
        }
        // Not absurdly loose: FR3 reaches about 1.2 m including the gripper.
        assert!(s.radius() < 2.0, "{}", s.radius());
    }
}
