//! A chunk policy *learned* from the demonstrations: kernel regression (Nadaraya–Watson) from
//! the last two observations to the action chunk, with its one hyper-parameter chosen by
//! cross-validation on the demonstrations alone.
//!
//! The nearest-neighbour stand-in ([`super::DemoSet`]) is written by hand: near the data it
//! replays the nearest demonstration, beyond a fixed radius it drifts at random, and it sees
//! only the joint angles. A learned policy differs in the two ways that matter for H3:
//! - it observes the last two timesteps (the paper's diffusion policies do), so the robot's
//!   recent motion is part of what it reacts to, and
//! - its behaviour away from the data is whatever the fitted function does there, not a
//!   designed failure: outputs blend the demonstrated chunks of whatever training states are
//!   nearest in the whole observation, also when those are far away or from another phase.
//!
//! Nothing here is tuned to the evaluation: the features are standardised with the training
//! data's own spread (z-scores), and the kernel width is the one that best predicts each
//! demonstration's chunks from the other demonstrations (leave-one-demonstration-out). The
//! replay paces of the augmented variant (`crate::task::REPLAY_PACES`) were chosen once
//! (1/2 and 1/4) and not varied.

use super::dist;
use pacs_motion::chunk::{ActionKind, Chunk};

/// Candidate kernel widths (in standard deviations of the standardised observation).
const BANDWIDTHS: [f64; 14] = [
    0.025, 0.035, 0.05, 0.07, 0.1, 0.14, 0.2, 0.28, 0.4, 0.56, 0.8, 1.1, 1.6, 2.2,
];

/// What a chunk policy observes when it is queried.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    /// Joint angles now (rad).
    pub q: &'a [f64],
    /// Joint angles one policy step Δt earlier (rad; equal to `q` at the start).
    pub q_before: &'a [f64],
    /// How many of the task's sub-goals have been reached (the gripper's state: empty before
    /// the pick, holding after it), as a real policy sees it in its observations.
    pub stage: usize,
}

/// The training data of one demonstration.
#[derive(Debug, Clone)]
pub struct Recording {
    /// Joint configurations, one per policy step Δt (rad).
    pub path: Vec<Vec<f64>>,
    /// Sub-goals reached at each configuration (non-decreasing).
    pub stages: Vec<usize>,
}

/// Kernel-regression chunk policy (see the module documentation).
#[derive(Debug, Clone)]
pub struct KernelPolicy {
    n: usize,
    /// Standardised observations, `2n` per sample: q, then q − q(t − Δt).
    inputs: Vec<f64>,
    /// Per sample the next H demonstrated configurations relative to the sample's own (rad),
    /// `H·n` per sample.
    outputs: Vec<f64>,
    stages: Vec<usize>,
    /// Which demonstration each sample comes from.
    demo_of: Vec<usize>,
    mean: Vec<f64>,
    scale: Vec<f64>,
    bandwidth: f64,
    /// Leave-one-demonstration-out mean squared chunk error (rad²) at each of [`BANDWIDTHS`].
    cv_errors: Vec<f64>,
    demos: Vec<Vec<Vec<f64>>>,
    /// Chunk length H.
    pub horizon: usize,
    /// Executed actions h.
    pub execute: usize,
    /// Distance (rad) from every demonstrated configuration beyond which a chunk is counted as
    /// out of distribution (a measure only: it does not change what the policy does).
    pub ood_radius: f64,
    ood_chunks: usize,
    weights: Vec<f64>,
}

/// Why a policy cannot be learned from the given demonstrations.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrainError {
    /// Cross-validation needs at least two demonstrations.
    #[error("{0} demonstration(s): leave-one-out cross-validation needs at least 2")]
    TooFewDemonstrations(usize),
    /// A demonstration is shorter than 2 samples, has a configuration of another size, or its
    /// stages do not match its samples.
    #[error("demonstration {0}: needs ≥ 2 samples of the same size and one stage per sample")]
    Malformed(usize),
    /// A configuration is not finite.
    #[error("demonstration {0}: a joint angle is not finite")]
    NotFinite(usize),
    /// The chunk needs 1 ≤ executed ≤ horizon actions.
    #[error("chunk of {horizon} actions with {execute} executed: needs 1 ≤ executed ≤ horizon")]
    Chunk {
        /// Actions per chunk (H).
        horizon: usize,
        /// Executed actions (h).
        execute: usize,
    },
    /// A replay pace is not a positive number.
    #[error("replay pace {0}: must be a positive finite fraction of the recorded pace")]
    Pace(f64),
}

/// `r` replayed at `pace` times its recorded pace: configurations linearly interpolated at
/// sample positions 0, pace, 2·pace, … (up to the last sample, which is kept); each keeps the
/// stage of the nearest recorded sample.
fn replay(r: &Recording, pace: f64) -> Recording {
    let last = r.path.len() - 1;
    let steps = (last as f64 / pace).ceil() as usize;
    let (mut path, mut stages) = (Vec::with_capacity(steps + 1), Vec::with_capacity(steps + 1));
    for j in 0..=steps {
        let u = (j as f64 * pace).min(last as f64);
        let i = (u.floor() as usize).min(last - 1);
        let w = u - i as f64;
        path.push(
            r.path[i]
                .iter()
                .zip(&r.path[i + 1])
                .map(|(a, b)| a + w * (b - a))
                .collect(),
        );
        stages.push(r.stages[u.round() as usize]);
    }
    Recording { path, stages }
}

impl KernelPolicy {
    /// Learn a policy with chunks of `horizon` actions (`execute` executed) from `recordings`.
    ///
    /// With `paces` (each > 0, e.g. 0.5), the learner also sees every demonstration replayed
    /// at those fractions of its recorded pace (the same configurations, linearly interpolated
    /// at `pace` samples per step): data augmentation for the slow passages a human
    /// demonstrator's recordings contain and machine-made ones do not. A replay belongs to its
    /// demonstration in the cross-validation (held out with it).
    pub fn train(
        recordings: &[Recording],
        horizon: usize,
        execute: usize,
        paces: &[f64],
    ) -> Result<Self, TrainError> {
        if recordings.len() < 2 {
            return Err(TrainError::TooFewDemonstrations(recordings.len()));
        }
        if horizon == 0 || execute == 0 || execute > horizon {
            return Err(TrainError::Chunk { horizon, execute });
        }
        let n = recordings[0].path.first().map_or(0, Vec::len);
        for (i, r) in recordings.iter().enumerate() {
            if n == 0
                || r.path.len() < 2
                || r.stages.len() != r.path.len()
                || r.path.iter().any(|q| q.len() != n)
            {
                return Err(TrainError::Malformed(i));
            }
            if r.path.iter().flatten().any(|x| !x.is_finite()) {
                return Err(TrainError::NotFinite(i));
            }
            if r.stages.windows(2).any(|w| w[1] < w[0]) {
                return Err(TrainError::Malformed(i));
            }
        }
        if let Some(&p) = paces.iter().find(|p| !(p.is_finite() && **p > 0.0)) {
            return Err(TrainError::Pace(p));
        }
        let mut data: Vec<(usize, std::borrow::Cow<Recording>)> = Vec::new();
        for (d, r) in recordings.iter().enumerate() {
            data.push((d, std::borrow::Cow::Borrowed(r)));
            for &pace in paces {
                data.push((d, std::borrow::Cow::Owned(replay(r, pace))));
            }
        }
        let (mut raw, mut outputs, mut stages, mut demo_of) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (d, r) in data.iter().map(|(d, r)| (*d, r.as_ref())) {
            let len = r.path.len();
            for k in 0..len {
                let here = &r.path[k];
                let before = &r.path[k.saturating_sub(1)];
                raw.extend_from_slice(here);
                raw.extend(here.iter().zip(before).map(|(a, b)| a - b));
                for s in 1..=horizon {
                    let next = &r.path[(k + s).min(len - 1)];
                    outputs.extend(next.iter().zip(here).map(|(a, b)| a - b));
                }
                stages.push(r.stages[k]);
                demo_of.push(d);
            }
        }
        let samples = stages.len();
        let dims = 2 * n;
        let mut mean = vec![0.0; dims];
        for x in raw.chunks_exact(dims) {
            mean.iter_mut()
                .zip(x)
                .for_each(|(m, v)| *m += v / samples as f64);
        }
        let mut scale = vec![0.0; dims];
        for x in raw.chunks_exact(dims) {
            scale
                .iter_mut()
                .zip(x.iter().zip(&mean))
                .for_each(|(s, (v, m))| *s += (v - m) * (v - m) / samples as f64);
        }
        // A feature that never varies in the data carries no information: unit scale.
        scale
            .iter_mut()
            .for_each(|s| *s = if *s > 1e-18 { s.sqrt() } else { 1.0 });
        let inputs: Vec<f64> = raw
            .chunks_exact(dims)
            .flat_map(|x| {
                x.iter()
                    .zip(mean.iter().zip(&scale))
                    .map(|(v, (m, s))| (v - m) / s)
            })
            .collect();
        let demos = recordings.iter().map(|r| r.path.clone()).collect();
        let mut p = Self {
            n,
            inputs,
            outputs,
            stages,
            demo_of,
            mean,
            scale,
            bandwidth: BANDWIDTHS[0],
            cv_errors: Vec::new(),
            demos,
            horizon,
            execute,
            ood_radius: 0.12,
            ood_chunks: 0,
            weights: vec![0.0; samples],
        };
        p.cv_errors = BANDWIDTHS
            .iter()
            .map(|&b| p.cross_validation_error(b))
            .collect();
        let best = p
            .cv_errors
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
        p.bandwidth = BANDWIDTHS[best];
        Ok(p)
    }

    /// The kernel width chosen by cross-validation (standard deviations).
    pub fn bandwidth(&self) -> f64 {
        self.bandwidth
    }

    /// The candidate widths and their leave-one-demonstration-out errors (rad², mean squared
    /// error per predicted joint offset).
    pub fn cross_validation(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        BANDWIDTHS
            .iter()
            .copied()
            .zip(self.cv_errors.iter().copied())
    }

    /// Mean squared error of predicting every sample's chunk from the other demonstrations.
    fn cross_validation_error(&mut self, bandwidth: f64) -> f64 {
        let dims = 2 * self.n;
        let out = self.horizon * self.n;
        let mut prediction = vec![0.0; out];
        let (mut sum, mut count) = (0.0, 0usize);
        for i in 0..self.stages.len() {
            let x: Vec<f64> = self.inputs[i * dims..(i + 1) * dims].to_vec();
            let held_out = self.demo_of[i];
            if !self.predict_standardised(
                &x,
                self.stages[i],
                bandwidth,
                Some(held_out),
                &mut prediction,
            ) {
                continue;
            }
            let truth = &self.outputs[i * out..(i + 1) * out];
            sum += prediction
                .iter()
                .zip(truth)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>();
            count += out;
        }
        if count == 0 {
            f64::INFINITY
        } else {
            sum / count as f64
        }
    }

    /// Kernel-weighted mean of the training chunks for the standardised observation `x` at
    /// `stage` (samples of that stage; of every stage if none has it), leaving out
    /// demonstration `skip`. False if no sample takes part.
    fn predict_standardised(
        &mut self,
        x: &[f64],
        stage: usize,
        bandwidth: f64,
        skip: Option<usize>,
        prediction: &mut [f64],
    ) -> bool {
        let dims = 2 * self.n;
        let out = self.horizon * self.n;
        let any_of_stage = self
            .stages
            .iter()
            .zip(&self.demo_of)
            .any(|(&s, &d)| s == stage && Some(d) != skip);
        let mut nearest = f64::INFINITY;
        for i in 0..self.stages.len() {
            let takes_part =
                (!any_of_stage || self.stages[i] == stage) && Some(self.demo_of[i]) != skip;
            self.weights[i] = if takes_part {
                let r2: f64 = self.inputs[i * dims..(i + 1) * dims]
                    .iter()
                    .zip(x)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum();
                nearest = nearest.min(r2);
                r2
            } else {
                f64::NAN
            };
        }
        if !nearest.is_finite() {
            return false;
        }
        // Weights relative to the nearest sample (exp(0) = 1 there): no underflow to 0/0 far
        // from the data, where the mean tends to the nearest samples' chunks.
        let mut total = 0.0;
        prediction.iter_mut().for_each(|p| *p = 0.0);
        for i in 0..self.stages.len() {
            let r2 = self.weights[i];
            if r2.is_nan() {
                continue;
            }
            let w = (-(r2 - nearest) / (2.0 * bandwidth * bandwidth)).exp();
            if w < 1e-12 {
                continue;
            }
            total += w;
            prediction
                .iter_mut()
                .zip(&self.outputs[i * out..(i + 1) * out])
                .for_each(|(p, y)| *p += w * y);
        }
        prediction.iter_mut().for_each(|p| *p /= total);
        true
    }

    /// The chunk for `obs`: the predicted offsets of the next H configurations, as deltas from
    /// the current joint angles.
    pub fn act(&mut self, obs: &Observation) -> Chunk {
        debug_assert!(obs.q.len() == self.n && obs.q_before.len() == self.n);
        if self.deviation(obs.q) > self.ood_radius {
            self.ood_chunks += 1;
        }
        let x: Vec<f64> = obs
            .q
            .iter()
            .copied()
            .chain(obs.q.iter().zip(obs.q_before).map(|(a, b)| a - b))
            .zip(self.mean.iter().zip(&self.scale))
            .map(|(v, (m, s))| (v - m) / s)
            .collect();
        let mut offsets = vec![0.0; self.horizon * self.n];
        let b = self.bandwidth;
        self.predict_standardised(&x, obs.stage, b, None, &mut offsets);
        let mut prev = vec![0.0; self.n];
        let actions = offsets
            .chunks_exact(self.n)
            .map(|o| {
                let a: Vec<f64> = o.iter().zip(&prev).map(|(x, p)| x - p).collect();
                prev.copy_from_slice(o);
                a
            })
            .collect();
        Chunk {
            kind: ActionKind::Delta,
            actions,
            execute: self.execute,
            gripper: None,
        }
    }

    /// Distance (rad) from `q` to the nearest demonstrated configuration.
    pub fn deviation(&self, q: &[f64]) -> f64 {
        self.demos
            .iter()
            .flatten()
            .map(|p| dist(p, q))
            .fold(f64::INFINITY, f64::min)
    }

    /// Chunks produced while the robot was further than `ood_radius` from every demonstrated
    /// configuration.
    pub fn ood_chunks(&self) -> usize {
        self.ood_chunks
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-joint recording through `path` at `stage` throughout.
    fn rec(path: &[f64], stage: usize) -> Recording {
        Recording {
            path: path.iter().map(|&x| vec![x]).collect(),
            stages: vec![stage; path.len()],
        }
    }

    /// The chunk's cumulative offsets from the current joint angle (one joint).
    fn offsets(c: &Chunk) -> Vec<f64> {
        c.actions
            .iter()
            .scan(0.0, |s, a| {
                *s += a[0];
                Some(*s)
            })
            .collect()
    }

    fn obs(q: &[f64], before: &[f64], stage: usize) -> (Vec<f64>, Vec<f64>, usize) {
        (q.to_vec(), before.to_vec(), stage)
    }

    fn act(p: &mut KernelPolicy, (q, b, stage): (Vec<f64>, Vec<f64>, usize)) -> Chunk {
        p.act(&Observation {
            q: &q,
            q_before: &b,
            stage,
        })
    }

    #[test]
    fn reproduces_its_training_chunks_exactly() {
        // Two identical demonstrations: every held-out one is predicted without error, so
        // cross-validation keeps the narrowest width, where the neighbouring samples (0.71
        // standard deviations away) weigh exp(-100).
        let path = [0.0, 1.0, 2.0, 3.0, 4.0];
        let mut p = KernelPolicy::train(&[rec(&path, 0), rec(&path, 0)], 3, 2, &[]).unwrap();
        assert_eq!(p.bandwidth(), BANDWIDTHS[0]);
        assert!(p.cross_validation().next().unwrap().1 < 1e-24);
        // At sample 1 (q = 1, one Δt after q = 0): the next three samples 2, 3, 4.
        let c = act(&mut p, obs(&[1.0], &[0.0], 0));
        assert_eq!(c.execute, 2);
        let o = offsets(&c);
        for (got, want) in o.iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{o:?}");
        }
        // At the last sample the demonstration holds: offsets 0 (the path's end repeats).
        let o = offsets(&act(&mut p, obs(&[4.0], &[3.0], 0)));
        assert!(o.iter().all(|x| x.abs() < 1e-12), "{o:?}");
        // From another place with the same observation of motion, the same offsets: the
        // policy outputs deltas from where the robot is.
        let mut q = p.clone();
        let o2 = offsets(&act(&mut q, obs(&[4.0], &[3.0], 0)));
        assert_eq!(o, o2);
    }

    #[test]
    fn the_observed_motion_selects_the_direction() {
        // Two demonstrations through the same configurations in opposite directions: only the
        // last two observations tell them apart.
        let mut p = KernelPolicy::train(
            &[
                rec(&[0.0, 1.0, 2.0, 3.0, 4.0], 0),
                rec(&[4.0, 3.0, 2.0, 1.0, 0.0], 0),
            ],
            2,
            1,
            &[],
        )
        .unwrap();
        let up = offsets(&act(&mut p, obs(&[2.0], &[1.0], 0)));
        let down = offsets(&act(&mut p, obs(&[2.0], &[3.0], 0)));
        assert!(up[0] > 0.5 && up[1] > up[0], "{up:?}");
        assert!(down[0] < -0.5 && down[1] < down[0], "{down:?}");
    }

    #[test]
    fn samples_of_another_stage_never_take_part() {
        // Stage 0 moves up here; stage 1 moves down through the same place, at another pace.
        // At stage 1 the policy follows stage 1's data although stage 0's matches the
        // observation exactly.
        let mut p = KernelPolicy::train(
            &[
                rec(&[0.0, 1.0, 2.0, 3.0, 4.0], 0),
                rec(&[0.0, 1.0, 2.0, 3.0, 4.0], 0),
                rec(&[2.5, 2.0, 1.5, 1.0, 0.5], 1),
                rec(&[2.5, 2.0, 1.5, 1.0, 0.5], 1),
            ],
            2,
            1,
            &[],
        )
        .unwrap();
        let at = |p: &mut KernelPolicy, stage| offsets(&act(p, obs(&[2.0], &[1.0], stage)));
        assert!(at(&mut p, 0)[0] > 0.99, "{:?}", at(&mut p, 0));
        let s1 = at(&mut p, 1);
        assert!(s1[0] < -0.1 && s1[1] < s1[0], "{s1:?}");
        // A stage no demonstration has: every sample takes part (here the exact match).
        assert!(at(&mut p, 7)[0] > 0.99);
    }

    #[test]
    fn far_from_the_data_the_chunk_stays_finite_and_within_the_demonstrated_offsets() {
        // Nadaraya–Watson is a weighted mean: every predicted offset lies between the smallest
        // and the largest demonstrated one, also where every kernel weight would underflow.
        let demos = [
            rec(&[0.0, 0.1, 0.3, 0.6, 1.0, 1.3, 1.5, 1.6], 0),
            rec(&[0.05, 0.2, 0.35, 0.7, 1.05, 1.3, 1.55, 1.6], 0),
            rec(&[-0.02, 0.1, 0.25, 0.55, 0.9, 1.25, 1.5, 1.62], 0),
        ];
        let mut p = KernelPolicy::train(&demos, 4, 2, &[]).unwrap();
        let (lo, hi) = p
            .outputs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                (l.min(x), h.max(x))
            });
        let mut rng = crate::humans::Rng::new(7);
        for i in 0..2000i32 {
            // Up to 10⁴ rad away and 10³ rad per step: kernel weights exp(-10¹⁴) without the
            // shift to the nearest sample.
            let scale = 10f64.powi(i % 5);
            let q = scale * (rng.uniform() - 0.5) * 20.0;
            let b = q - scale * (rng.uniform() - 0.5) * 2.0;
            let o = offsets(&act(&mut p, obs(&[q], &[b], 0)));
            for x in &o {
                assert!(x.is_finite(), "case {i}: q = {q}, before = {b}: {o:?}");
                assert!(
                    *x >= lo - 1e-9 && *x <= hi + 1e-9,
                    "case {i}: q = {q}: offset {x} outside [{lo}, {hi}]"
                );
            }
        }
        assert!(p.ood_chunks() > 1000, "{}", p.ood_chunks());
    }

    #[test]
    fn replays_interpolate_the_recording_at_the_given_pace() {
        let r = Recording {
            path: vec![vec![0.0], vec![1.0], vec![3.0]],
            stages: vec![0, 1, 1],
        };
        let half = replay(&r, 0.5);
        assert_eq!(
            half.path,
            [0.0, 0.5, 1.0, 2.0, 3.0].map(|x| vec![x]).to_vec()
        );
        // Sample positions 0, 0.5, 1, 1.5, 2 round to recorded samples 0, 1, 1, 2, 2.
        assert_eq!(half.stages, [0, 1, 1, 1, 1]);
        // A pace that does not divide the recording ends on its last sample.
        let p = replay(&r, 0.75);
        assert_eq!(p.path.last(), Some(&vec![3.0]));
        assert_eq!(p.path.len(), 4);
        // Replays belong to their demonstration: held out with it in the cross-validation.
        let pol = KernelPolicy::train(&[r.clone(), r], 2, 1, &[0.5, 0.25]).unwrap();
        assert_eq!(pol.demo_of.iter().filter(|&&d| d == 0).count(), 3 + 5 + 9);
        assert_eq!(pol.demo_of.len(), 2 * 17);
        assert_eq!(
            pol.demos.len(),
            2,
            "deviation is measured from the recordings"
        );
    }

    #[test]
    fn refuses_what_it_cannot_learn_from() {
        let one = [rec(&[0.0, 1.0], 0)];
        assert_eq!(
            KernelPolicy::train(&one, 2, 1, &[]).unwrap_err(),
            TrainError::TooFewDemonstrations(1)
        );
        let mut bad = rec(&[0.0, 1.0], 0);
        bad.stages.pop();
        assert_eq!(
            KernelPolicy::train(&[rec(&[0.0, 1.0], 0), bad], 2, 1, &[]).unwrap_err(),
            TrainError::Malformed(1)
        );
        assert_eq!(
            KernelPolicy::train(&[rec(&[0.0, f64::NAN], 0), rec(&[0.0, 1.0], 0)], 2, 1, &[])
                .unwrap_err(),
            TrainError::NotFinite(0)
        );
        assert_eq!(
            KernelPolicy::train(&[rec(&[0.0], 0), rec(&[0.0, 1.0], 0)], 2, 1, &[]).unwrap_err(),
            TrainError::Malformed(0)
        );
        let going_back = Recording {
            path: vec![vec![0.0], vec![1.0]],
            stages: vec![1, 0],
        };
        assert_eq!(
            KernelPolicy::train(&[rec(&[0.0, 1.0], 0), going_back], 2, 1, &[]).unwrap_err(),
            TrainError::Malformed(1)
        );
        let two = [rec(&[0.0, 1.0], 0), rec(&[0.0, 1.0], 0)];
        for (h, e) in [(0, 0), (2, 0), (2, 3)] {
            assert_eq!(
                KernelPolicy::train(&two, h, e, &[]).unwrap_err(),
                TrainError::Chunk {
                    horizon: h,
                    execute: e
                }
            );
        }
        for pace in [0.0, -0.5, f64::NAN, f64::INFINITY] {
            assert!(matches!(
                KernelPolicy::train(&two, 2, 1, &[pace]),
                Err(TrainError::Pace(_))
            ));
        }
    }
}
