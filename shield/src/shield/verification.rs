//! Verification of a monitored trajectory: per occupancy interval, joint boxes from the path
//! ranges, robot and human occupancies, and the ISO/TS 15066 rule.

use super::{Binding, Diagnostics, FilterMode, OccupancyIntervals, Shield};
use pacs_models::MAX_DOF;
use pacs_motion::scaling::SpeedProfile;
use pacs_reach::JointBox;
use pacs_reach::human::HumanMeasurement;
use pacs_verify::iso15066::ConstraintKind;
use std::ops::ControlFlow;

impl Shield {
    /// Verify the monitored trajectory (go for α_s from t, then brake) against the human.
    pub(super) fn verify(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        diag: &mut Diagnostics,
    ) -> bool {
        let alpha = self.config.safety_step;
        let stop = alpha + brake.settle_time();
        if self.human.is_none() {
            return true;
        }
        if !self.has_meas {
            diag.binding = Binding::NoMeasurement;
            return false;
        }
        let Some(meas) = self.meas.take() else {
            diag.binding = Binding::NoMeasurement;
            return false;
        };
        // Coarse check first: the whole monitored trajectory as one interval (its occupancy
        // contains that of every sub-interval, so passing it verifies the step). Usually decides
        // when the human is far; otherwise the fine intervals below decide.
        if self.config.mode != FilterMode::Off && stop > alpha {
            let mut coarse = *diag;
            if self.check_interval(slot, go, brake, t, 0.0, stop, 0, &meas, &mut coarse) {
                *diag = coarse;
                self.meas = Some(meas);
                return true;
            }
        }
        let mut ok = true;
        let intervals = OccupancyIntervals::new(
            alpha,
            stop,
            self.config.first_interval,
            self.config.max_intervals,
        );
        for (k, ta, tb) in intervals {
            if !self.check_interval(slot, go, brake, t, ta, tb, k, &meas, diag) {
                ok = false;
                if self.config.mode != FilterMode::Off {
                    break;
                }
            }
        }
        self.meas = Some(meas);
        ok
    }

    /// Path and speed ranges of the monitored trajectory over relative time [ta, tb].
    fn path_ranges(
        go: &SpeedProfile,
        brake: &SpeedProfile,
        alpha: f64,
        ta: f64,
        tb: f64,
    ) -> (f64, f64, f64, f64) {
        let mut s_lo = f64::INFINITY;
        let mut s_hi = f64::NEG_INFINITY;
        let mut sd_lo = f64::INFINITY;
        let mut sd_hi = f64::NEG_INFINITY;
        let mut add = |r: (f64, f64, f64, f64, f64)| {
            s_lo = s_lo.min(r.0);
            s_hi = s_hi.max(r.1);
            sd_lo = sd_lo.min(r.2);
            sd_hi = sd_hi.max(r.3);
        };
        if ta < alpha {
            add(go.ranges(ta, tb.min(alpha)));
        }
        if tb > alpha {
            add(brake.ranges(ta.max(alpha) - alpha, tb - alpha));
        }
        (s_lo, s_hi, sd_lo.max(0.0), sd_hi)
    }

    #[allow(clippy::too_many_arguments)]
    fn check_interval(
        &mut self,
        slot: usize,
        go: &SpeedProfile,
        brake: &SpeedProfile,
        t: f64,
        ta: f64,
        tb: f64,
        k: usize,
        meas: &HumanMeasurement,
        diag: &mut Diagnostics,
    ) -> bool {
        let alpha = self.config.safety_step;
        let n = self.dof;
        let (s_lo, s_hi, sd_lo, sd_hi) = Self::path_ranges(go, brake, alpha, ta, tb);
        let tr = self.trajs[slot].as_ref().expect("slot holds a trajectory");
        let mut q_lo = [0.0; MAX_DOF];
        let mut q_hi = [0.0; MAX_DOF];
        let mut v_lo = [0.0; MAX_DOF];
        let mut v_hi = [0.0; MAX_DOF];
        for i in 0..n {
            let d = tr.joint_derivs(i, s_lo, s_hi);
            q_lo[i] = d.r[0].lo;
            q_hi[i] = d.r[0].hi;
            // q̇ = q′·ṡ with ṡ ∈ [sd_lo, sd_hi] ⊂ [0, ∞): interval product, rounded outward.
            let (a, b) = (d.r[1].lo, d.r[1].hi);
            let c = [a * sd_lo, a * sd_hi, b * sd_lo, b * sd_hi];
            v_lo[i] = c.iter().copied().fold(f64::INFINITY, f64::min).next_down();
            v_hi[i] = c
                .iter()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max)
                .next_up();
            if sd_hi == 0.0 {
                // Path speed exactly 0 over the interval: the commanded joints are at rest.
                (v_lo[i], v_hi[i]) = (0.0, 0.0);
            }
        }
        let Self {
            reach,
            scratch,
            robot_caps,
            human_caps,
            energies,
            human,
            config,
            ..
        } = self;
        let Some((hr, rule)) = human.as_mut() else {
            return true;
        };
        // Non-finite path ranges never verify.
        let (Ok(q_box), Ok(v_box)) = (
            JointBox::new(&q_lo[..n], &q_hi[..n]),
            JointBox::new(&v_lo[..n], &v_hi[..n]),
        ) else {
            return false;
        };
        if hr.occupancy_into(meas, t + ta, t + tb, human_caps).is_err() {
            diag.binding = Binding::NoMeasurement;
            return false;
        }
        // Broad phase, stage 1: the human is outside the robot's workspace ball.
        if let Some(sep) = rule.workspace_clear(human_caps) {
            if k == 0 {
                diag.min_separation = diag.min_separation.min(sep);
            }
            return true;
        }
        if reach.occupancy_with(scratch, &q_box, robot_caps).is_err() {
            return false;
        }
        // The robot's real velocities may differ from the commanded ones by the controller's
        // velocity tracking error (rounded outward): the energy bound uses the widened box.
        let e_track = config.velocity_tracking_error;
        let energy = || {
            let widened = JointBox::from_fn(n, |i| {
                let (lo, hi) = v_box.bounds(i);
                ((lo - e_track).next_down(), (hi + e_track).next_up())
            });
            // Same joint box as the occupancy above: the scratch's frames are reused.
            match widened.map(|w| reach.subchain_energy_bounds_with(scratch, &q_box, &w, energies))
            {
                Ok(Ok(())) => energies[n],
                _ => f64::INFINITY,
            }
        };
        let mut first = None;
        let outcome = rule.check(robot_caps, &v_box, human_caps, energy, k == 0, |h| {
            first = Some(*h);
            ControlFlow::Break(())
        });
        if k == 0 {
            diag.min_separation = diag.min_separation.min(outcome.separation);
        }
        if let Some((e, thr)) = outcome.pfl
            && e > diag.contact_energy
        {
            diag.contact_energy = e;
            diag.contact_threshold = thr;
        }
        let Some(h) = first else { return true };
        if matches!(diag.binding, Binding::None) {
            diag.binding = match h.kind {
                ConstraintKind::Ssm => Binding::Ssm {
                    link: h.link,
                    body_part: h.part,
                    interval: k,
                },
                ConstraintKind::Pfl => Binding::Pfl {
                    link: h.link,
                    body_part: h.part,
                    energy: h.energy,
                    threshold: h.threshold,
                    constrained: h.constrained,
                },
            };
        }
        false
    }
}
