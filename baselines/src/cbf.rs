//! Control-barrier-function baseline (reactive, not path-consistent): per safety step a QP solved
//! with clarabel,
//!   minimise ‖q̇ − q̇_des‖²  s.t.  ∇h_ij(q)·q̇ ≥ −γ·h_ij  for robot-capsule/body-part pairs,
//!   |q̇| ≤ v_max, |q̇ − q̇_prev| ≤ a_max·α_s, q + α_s·q̇ within the position limits,
//! where h_ij is the distance between robot capsule i and the human occupancy of body part j over
//! the coming step (minus a margin), ∇h = nᵀ·J_p(q) with n the unit vector between the closest
//! points and J_p the point Jacobian, and q̇_des = q̇_ref + k_p·(q_ref − q) tracks the intended
//! trajectory of the current chunk. This is the paper's CBF comparison: it offers no formal
//! guarantee (the barrier ignores future human motion beyond one step) and pushes the robot off
//! the intended path. Dynamic objects enter as further obstacles: the bounding capsule of each
//! object's occupancy over the coming step ([`pacs_reach::object`]), with the same barrier for
//! every contact kind (the baseline keeps its distance from everything). Allocates per step (QP
//! setup).

// Joint-indexed loops over parallel fixed-size arrays read clearer than zipped iterators.
#![allow(clippy::needless_range_loop)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use nalgebra::Point3;
use pacs_models::object::ObjectModel;
use pacs_models::{Capsule, HumanModel, MAX_DOF, RobotModel};
use pacs_motion::chunk::Chunk;
use pacs_motion::intended::{Planner, PlannerConfig};
use pacs_motion::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_reach::geometry::{capsule_distance_lower_bound, segment_closest_points};
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::shield::{Binding, Command, Diagnostics, ShieldError};

/// CBF settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CbfConfig {
    /// Safety step α_s (s).
    pub safety_step: f64,
    /// Barrier gain γ (1/s).
    pub gamma: f64,
    /// Safety margin subtracted from the distance (m).
    pub margin: f64,
    /// Pairs farther apart than this are not constrained (m).
    pub activation: f64,
    /// Reference tracking gain k_p (1/s).
    pub kp: f64,
    /// Intended trajectory acceleration limit as a fraction of the robot's.
    pub intended_acc_fraction: f64,
    /// Intended trajectory jerk limit (rad/s³).
    pub intended_jerk: f64,
}

impl Default for CbfConfig {
    fn default() -> Self {
        Self {
            safety_step: 0.001,
            gamma: 5.0,
            margin: 0.02,
            activation: 0.4,
            kp: 10.0,
            intended_acc_fraction: 0.8,
            intended_jerk: 400.0,
        }
    }
}

/// The CBF safety filter.
pub struct CbfFilter {
    robot: RobotModel,
    hw: Limits,
    planner: Planner,
    human: Option<HumanReach>,
    config: CbfConfig,
    reference: Option<Trajectory>,
    ref_t0: f64,
    q: [f64; MAX_DOF],
    dq: [f64; MAX_DOF],
    ddq: [f64; MAX_DOF],
    meas: Option<HumanMeasurement>,
    /// Further people ([`CbfFilter::add_human`]): each one's reach and newest measurement.
    others: Vec<(HumanReach, Option<HumanMeasurement>)>,
    objects: Vec<(ObjectModel, Option<ObjectMeasurement>)>,
    started: bool,
}

impl std::fmt::Debug for CbfFilter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CbfFilter")
            .field("config", &self.config)
            .finish()
    }
}

impl CbfFilter {
    /// Build for a robot and an optional human model (combined reach model over one step).
    pub fn new(
        robot: RobotModel,
        human: Option<HumanModel>,
        config: CbfConfig,
    ) -> Result<Self, ShieldError> {
        // NaN fails every comparison, so it is refused too.
        for (field, value, ok) in [
            (
                "cbf safety_step (> 0 s)",
                config.safety_step,
                config.safety_step > 0.0,
            ),
            ("cbf gamma (> 0)", config.gamma, config.gamma > 0.0),
            ("cbf kp (>= 0)", config.kp, config.kp >= 0.0),
        ] {
            if !ok {
                return Err(ShieldError::Config { field, value });
            }
        }
        let hw = Limits::from_joint_limits(robot.limits());
        let mut plan = hw;
        for i in 0..hw.dof {
            plan.a[i] *= config.intended_acc_fraction;
            plan.j[i] = plan.j[i].min(config.intended_jerk);
        }
        Ok(Self {
            planner: Planner::new(
                plan,
                PlannerConfig {
                    end: EndCondition::AtRest,
                    ..PlannerConfig::default()
                },
            ),
            hw,
            human: human.map(|h| HumanReach::new(h, HumanReachModel::Combined)),
            robot,
            config,
            reference: None,
            ref_t0: 0.0,
            q: [0.0; MAX_DOF],
            dq: [0.0; MAX_DOF],
            ddq: [0.0; MAX_DOF],
            meas: None,
            others: Vec::new(),
            objects: Vec::new(),
            started: false,
        })
    }

    /// Add another person (its body parts become barrier obstacles like the first's); returns
    /// its index (the first person, given to [`Self::new`] and measured through
    /// [`Self::step`], is 0).
    pub fn add_human(&mut self, human: HumanModel) -> usize {
        self.others
            .push((HumanReach::new(human, HumanReachModel::Combined), None));
        self.others.len()
    }

    /// A measurement of person `id` ≥ 1 (kept if newer than its latest).
    pub fn measure_human(&mut self, id: usize, m: &HumanMeasurement) -> Result<(), ShieldError> {
        let n = self.others.len() + 1;
        let Some((_, latest)) = id.checked_sub(1).and_then(|i| self.others.get_mut(i)) else {
            return Err(ShieldError::UnknownHuman { id, count: n });
        };
        pacs_reach::stamped::keep_newest(m, latest);
        Ok(())
    }

    /// Start at rest at `q` (rad), time `t` (s).
    pub fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError> {
        let n = self.robot.dof();
        if q.len() != n {
            return Err(ShieldError::StartLength {
                given: q.len(),
                dof: n,
            });
        }
        let l = self.robot.limits();
        if let Some(index) = (0..n).find(|&i| !(l.q_min()[i]..=l.q_max()[i]).contains(&q[i])) {
            return Err(ShieldError::StartOutsideLimits {
                index,
                joint: self.robot.joints()[index].name.clone(),
                value: q[index],
                min: l.q_min()[index],
                max: l.q_max()[index],
            });
        }
        self.q = [0.0; MAX_DOF];
        self.q[..n].copy_from_slice(q);
        self.dq = [0.0; MAX_DOF];
        self.ddq = [0.0; MAX_DOF];
        self.ref_t0 = t;
        self.reference = None;
        self.started = true;
        Ok(())
    }

    /// Add a dynamic object; returns its id. The barrier keeps the robot away from every object
    /// whatever its contact constraint (a CBF has no notion of allowed contact).
    pub fn add_object(&mut self, model: ObjectModel) -> usize {
        self.objects.push((model, None));
        self.objects.len() - 1
    }

    /// Number of dynamic objects.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Record a measurement of object `id` (a newer one replaces the latest). Errors: unknown
    /// `id`, non-finite values.
    pub fn measure_object(&mut self, id: usize, m: &ObjectMeasurement) -> Result<(), ShieldError> {
        if !m.is_finite() {
            return Err(ShieldError::ObjectNotFinite(id));
        }
        let n = self.objects.len();
        let Some((_, latest)) = self.objects.get_mut(id) else {
            return Err(ShieldError::UnknownObject { id, count: n });
        };
        m.keep_newest(latest);
        Ok(())
    }

    /// Plan a new reference from the current state (time `t`, s).
    pub fn set_chunk(&mut self, t: f64, chunk: &Chunk) -> Result<(), ShieldError> {
        if !self.started {
            return Err(ShieldError::NotStarted);
        }
        let n = self.robot.dof();
        // The reference starts at the current position and velocity (clamped to the planning
        // limits); its acceleration starts at 0 — the CBF tracks it by feedback, not exactly.
        let lim = *self.planner.limits();
        let mut dq = [0.0; MAX_DOF];
        for i in 0..n {
            dq[i] = self.dq[i].clamp(-lim.v[i], lim.v[i]);
        }
        let start = JointState::new(&self.q[..n], &dq[..n], &[0.0; MAX_DOF][..n]);
        let wp = chunk.waypoints(
            &self.q[..n],
            self.robot.limits(),
            pacs_motion::chunk::OutOfLimits::Reject,
        )?;
        self.reference = Some(self.planner.plan(&start, &wp)?);
        self.ref_t0 = t;
        Ok(())
    }

    /// One control step at `t` (s) with the latest measurement; returns the command for t + α_s
    /// ([`ShieldError::NotStarted`] before [`CbfFilter::start`]).
    pub fn step(
        &mut self,
        t: f64,
        measurement: Option<&HumanMeasurement>,
    ) -> Result<Command, ShieldError> {
        if !self.started {
            return Err(ShieldError::NotStarted);
        }
        let n = self.robot.dof();
        let alpha = self.config.safety_step;
        if let Some(m) = measurement
            && m.time() <= t
            && m.supersedes(self.meas.as_ref())
        {
            self.meas = Some(m.clone());
        }
        // Desired velocity: reference velocity plus position feedback.
        let mut des = [0.0; MAX_DOF];
        if let Some(r) = &self.reference {
            let s = r.state_at(t + alpha - self.ref_t0);
            for i in 0..n {
                des[i] = s.dq[i] + self.config.kp * (s.q[i] - self.q[i]);
            }
        }
        let mut diag = Diagnostics {
            verified: true,
            on_failsafe: false,
            binding: Binding::None,
            min_separation: f64::INFINITY,
            contact_energy: 0.0,
            contact_threshold: 0.0,
            path_speed: 1.0,
            stop_time: t + alpha,
        };
        // Obstacles over the coming step: the human's body-part capsules and each object's
        // bounding capsule. An object never measured, or whose occupancy cannot be bounded,
        // leaves the step unconstrained against it and is reported as missing.
        let mut obstacles: Vec<Capsule> = Vec::new();
        if let (Some(hr), Some(m)) = (self.human.as_mut(), self.meas.as_ref()) {
            match hr.occupancy(m, t.max(m.time() - hr.model().delay()), t + alpha) {
                Ok(hcaps) => obstacles.extend(hcaps.iter().cloned()),
                Err(_) => diag.binding = Binding::NoMeasurement,
            }
        }
        for (hr, meas) in &mut self.others {
            let Some(m) = meas.as_ref() else {
                diag.binding = Binding::NoMeasurement;
                continue;
            };
            match hr.occupancy(m, t.max(m.time() - hr.model().delay()), t + alpha) {
                Ok(hcaps) => obstacles.extend(hcaps.iter().cloned()),
                Err(_) => diag.binding = Binding::NoMeasurement,
            }
        }
        for (model, meas) in &self.objects {
            let caps = meas.as_ref().and_then(|m| {
                pacs_reach::object::occupancy(model, m, t, t + alpha)
                    .ok()
                    .and_then(|o| o.bounding_capsule())
            });
            match caps {
                Some(c) => obstacles.push(c),
                None => diag.binding = Binding::NoMeasurement,
            }
        }
        // Barrier rows: -∇h·q̇ ≤ γ·h.
        let mut rows: Vec<([f64; MAX_DOF], f64)> = Vec::new();
        if !obstacles.is_empty() {
            let frames = self.robot.frames(&self.q[..n]);
            for l in self.robot.links() {
                if l.frame == 0 {
                    continue;
                }
                for c in &l.capsules {
                    let w = c.transformed(&frames[l.frame]);
                    for hc in &obstacles {
                        let d = capsule_distance_lower_bound(&w, hc);
                        diag.min_separation = diag.min_separation.min(d);
                        let h = d - self.config.margin;
                        if d > self.config.activation {
                            continue;
                        }
                        let (pr, ph) = segment_closest_points(&w.p1(), &w.p2(), &hc.p1(), &hc.p2());
                        let dir = pr - ph;
                        let len = dir.norm();
                        if len < 1e-12 {
                            continue;
                        }
                        let nrm = dir / len;
                        let jac =
                            self.robot
                                .point_jacobian(&frames, l.frame, &Point3::from(pr.coords));
                        let mut g = [0.0; MAX_DOF];
                        for (j, gj) in g.iter_mut().enumerate().take(n) {
                            *gj = nrm.dot(&jac.column(j));
                        }
                        rows.push((g, self.config.gamma * h));
                    }
                }
            }
        }
        let qd = self.solve(&des[..n], &rows).unwrap_or_else(|| {
            diag.verified = false;
            diag.on_failsafe = true;
            diag.binding = Binding::NoProfile;
            // Infeasible: decelerate as hard as allowed.
            let mut v = [0.0; MAX_DOF];
            for i in 0..n {
                let dv = self.hw.a[i] * alpha;
                v[i] = if self.dq[i] > 0.0 {
                    (self.dq[i] - dv).max(0.0)
                } else {
                    (self.dq[i] + dv).min(0.0)
                };
            }
            v
        });
        if !rows.is_empty() && diag.binding == Binding::None {
            diag.binding = Binding::Barrier { active: rows.len() };
        }
        for i in 0..n {
            self.ddq[i] = (qd[i] - self.dq[i]) / alpha;
            self.dq[i] = qd[i];
            self.q[i] += qd[i] * alpha;
        }
        let state = JointState::new(&self.q[..n], &self.dq[..n], &self.ddq[..n]);
        diag.path_speed = 0.0;
        Ok(Command {
            t: t + alpha,
            state,
            dof: n,
            diag,
        })
    }

    fn solve(&self, des: &[f64], rows: &[([f64; MAX_DOF], f64)]) -> Option<[f64; MAX_DOF]> {
        let n = des.len();
        let alpha = self.config.safety_step;
        // P = 2I, q = −2·des.
        let p =
            CscMatrix::new_from_triplets(n, n, (0..n).collect(), (0..n).collect(), vec![2.0; n]);
        let qv: Vec<f64> = des.iter().map(|d| -2.0 * d).collect();
        let (mut ri, mut ci, mut vv, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (k, (g, gh)) in rows.iter().enumerate() {
            for j in 0..n {
                if g[j] != 0.0 {
                    ri.push(k);
                    ci.push(j);
                    vv.push(-g[j]);
                }
            }
            b.push(*gh);
        }
        let m0 = rows.len();
        let lim = self.robot.limits();
        for j in 0..n {
            let dv = self.hw.a[j] * alpha;
            let hi = self.hw.v[j]
                .min(self.dq[j] + dv)
                .min((lim.q_max()[j] - self.q[j]) / alpha);
            let lo = (-self.hw.v[j])
                .max(self.dq[j] - dv)
                .max((lim.q_min()[j] - self.q[j]) / alpha);
            ri.push(m0 + 2 * j);
            ci.push(j);
            vv.push(1.0);
            b.push(hi);
            ri.push(m0 + 2 * j + 1);
            ci.push(j);
            vv.push(-1.0);
            b.push(-lo);
        }
        let m = m0 + 2 * n;
        let a = CscMatrix::new_from_triplets(m, n, ri, ci, vv);
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .build()
            .ok()?;
        let mut solver =
            DefaultSolver::new(&p, &qv, &a, &b, &[NonnegativeConeT(m)], settings).ok()?;
        solver.solve();
        if !matches!(
            solver.solution.status,
            SolverStatus::Solved | SolverStatus::AlmostSolved
        ) {
            return None;
        }
        let mut out = [0.0; MAX_DOF];
        out[..n].copy_from_slice(&solver.solution.x[..n]);
        Some(out)
    }

    /// Current joint positions (rad).
    pub fn q(&self) -> &[f64] {
        &self.q[..self.robot.dof()]
    }
}

/// Capsules of the robot at `q` (world frame), for diagnostics and tests.
pub fn robot_capsules(robot: &RobotModel, q: &[f64]) -> Vec<Capsule> {
    robot
        .capsules_world(q)
        .into_iter()
        .map(|(_, c)| c)
        .collect()
}
