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
//! demonstration's chunks from the other demonstrations (leave-one-demonstration-out).
//! Demonstrations replayed at a slower pace ([`replay_path`]) may be added to the training
//! data; they are held out with their demonstration. The evaluation's replay paces
//! (`crate::task::REPLAY_PACES`) were chosen once (1/2 and 1/4) and not varied.

use super::{OOD_RADIUS, Observation, nearest_distance};
use pacs_motion::chunk::{ActionKind, Chunk};
use std::sync::Arc;

/// Candidate kernel widths (in standard deviations of the standardised observation).
const BANDWIDTHS: [f64; 14] = [
    0.025, 0.035, 0.05, 0.07, 0.1, 0.14, 0.2, 0.28, 0.4, 0.56, 0.8, 1.1, 1.6, 2.2,
];

/// Smallest spread (rad) a feature is standardised with: differences below a milliradian (the
/// order of a robot's tracking error) carry no information about the task, so a joint that
/// hardly moves in the data must not dominate the distance.
pub const MIN_FEATURE_SCALE: f64 = 1e-3;

/// Slowest replay pace accepted by [`replay_path`] (a fraction of the recorded pace).
pub const MIN_PACE: f64 = 0.01;

/// The training data of one demonstration, or of a replay of one.
#[derive(Debug, Clone)]
pub struct Recording {
    /// Joint configurations, one per policy step Δt (rad).
    pub path: Vec<Vec<f64>>,
    /// Sub-goals reached at each configuration (non-decreasing).
    pub stages: Vec<usize>,
    /// Which demonstration this is (a replay: of which); held out together in the
    /// cross-validation.
    pub demonstration: usize,
    /// Fraction of the recorded pace ([`MIN_PACE`]..=1; 1: the recording itself).
    pub pace: f64,
}

/// `path` replayed at `pace` times its recorded pace ([`MIN_PACE`] ≤ pace ≤ 1): the
/// configurations linearly interpolated at sample positions 0, pace, 2·pace, … up to the last
/// sample, which is always included. Label its stages by the same rule as the recording's.
pub fn replay_path(path: &[Vec<f64>], pace: f64) -> Result<Vec<Vec<f64>>, TrainError> {
    if !(MIN_PACE..=1.0).contains(&pace) {
        return Err(TrainError::Pace(pace));
    }
    let Some(last) = path.len().checked_sub(1).filter(|&l| l > 0) else {
        return Ok(path.to_vec());
    };
    let steps = (last as f64 / pace).ceil() as usize;
    Ok((0..=steps)
        .map(|j| {
            let u = (j as f64 * pace).min(last as f64);
            let i = (u.floor() as usize).min(last - 1);
            let w = u - i as f64;
            path[i]
                .iter()
                .zip(&path[i + 1])
                .map(|(a, b)| a + w * (b - a))
                .collect()
        })
        .collect())
}

/// What training fixed: the standardised data, the kernel width and its cross-validation.
#[derive(Debug)]
struct Model {
    n: usize,
    horizon: usize,
    execute: usize,
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
    /// The recorded configurations (not the replays), for the deviation measure.
    demos: Vec<Vec<Vec<f64>>>,
    paced: bool,
}

/// Kernel-regression chunk policy (see the module documentation). Clones share the trained
/// model.
#[derive(Debug, Clone)]
pub struct KernelPolicy {
    model: Arc<Model>,
    ood_chunks: usize,
    weights: Vec<f64>,
}

/// Why a policy cannot be learned from the given demonstrations.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrainError {
    /// Cross-validation needs at least two demonstrations.
    #[error("{0} demonstration(s): leave-one-out cross-validation needs at least 2")]
    TooFewDemonstrations(usize),
    /// A recording is shorter than 2 samples, has a configuration of another size, or its
    /// stages do not match its samples or decrease.
    #[error(
        "recording {0}: needs ≥ 2 samples of the same size and one non-decreasing stage per sample"
    )]
    Malformed(usize),
    /// A configuration is not finite.
    #[error("recording {0}: a joint angle is not finite")]
    NotFinite(usize),
    /// The chunk needs 1 ≤ executed ≤ horizon actions.
    #[error("chunk of {horizon} actions with {execute} executed: needs 1 ≤ executed ≤ horizon")]
    Chunk {
        /// Actions per chunk (H).
        horizon: usize,
        /// Executed actions (h).
        execute: usize,
    },
    /// A replay pace outside [`MIN_PACE`]..=1.
    #[error("replay pace {0}: must be a fraction of the recorded pace in [0.01, 1]")]
    Pace(f64),
}

impl KernelPolicy {
    /// Learn a policy with chunks of `horizon` actions (`execute` executed) from `recordings`
    /// (at least two distinct demonstrations; replays of them may be added, see
    /// [`replay_path`]).
    pub fn train(
        recordings: &[Recording],
        horizon: usize,
        execute: usize,
    ) -> Result<Self, TrainError> {
        let mut distinct: Vec<usize> = recordings.iter().map(|r| r.demonstration).collect();
        distinct.sort_unstable();
        distinct.dedup();
        if distinct.len() < 2 {
            return Err(TrainError::TooFewDemonstrations(distinct.len()));
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
                || r.stages.windows(2).any(|w| w[1] < w[0])
            {
                return Err(TrainError::Malformed(i));
            }
            if r.path.iter().flatten().any(|x| !x.is_finite()) {
                return Err(TrainError::NotFinite(i));
            }
            if !(MIN_PACE..=1.0).contains(&r.pace) {
                return Err(TrainError::Pace(r.pace));
            }
        }
        let (mut raw, mut outputs, mut stages, mut demo_of) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for r in recordings {
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
                demo_of.push(r.demonstration);
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
        scale
            .iter_mut()
            .for_each(|s| *s = s.sqrt().max(MIN_FEATURE_SCALE));
        let inputs: Vec<f64> = raw
            .chunks_exact(dims)
            .flat_map(|x| {
                x.iter()
                    .zip(mean.iter().zip(&scale))
                    .map(|(v, (m, s))| (v - m) / s)
            })
            .collect();
        let mut recorded: Vec<Vec<Vec<f64>>> = recordings
            .iter()
            .filter(|r| r.pace == 1.0)
            .map(|r| r.path.clone())
            .collect();
        if recorded.is_empty() {
            recorded = recordings.iter().map(|r| r.path.clone()).collect();
        }
        let mut model = Model {
            n,
            horizon,
            execute,
            inputs,
            outputs,
            stages,
            demo_of,
            mean,
            scale,
            bandwidth: BANDWIDTHS[0],
            cv_errors: Vec::new(),
            demos: recorded,
            paced: recordings.iter().any(|r| r.pace != 1.0),
        };
        let mut weights = vec![0.0; samples];
        model.cv_errors = BANDWIDTHS
            .iter()
            .map(|&b| model.cross_validation_error(b, &mut weights))
            .collect();
        let best = model
            .cv_errors
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
        model.bandwidth = BANDWIDTHS[best];
        Ok(Self {
            model: Arc::new(model),
            ood_chunks: 0,
            weights,
        })
    }

    /// The kernel width chosen by cross-validation (standard deviations).
    pub fn bandwidth(&self) -> f64 {
        self.model.bandwidth
    }

    /// The candidate widths and their leave-one-demonstration-out errors (rad², mean squared
    /// error per predicted joint offset).
    pub fn cross_validation(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        BANDWIDTHS
            .iter()
            .copied()
            .zip(self.model.cv_errors.iter().copied())
    }

    /// The spread (rad) each observed feature is standardised with: per joint the angle's,
    /// then per joint the motion's over one Δt (at least [`MIN_FEATURE_SCALE`]).
    pub fn feature_scales(&self) -> &[f64] {
        &self.model.scale
    }

    /// Chunk length H.
    pub fn horizon(&self) -> usize {
        self.model.horizon
    }

    /// Executed actions per chunk (h).
    pub fn execute(&self) -> usize {
        self.model.execute
    }

    /// Whether replays were part of the training data.
    pub fn paced(&self) -> bool {
        self.model.paced
    }

    /// The chunk for `obs`: the predicted offsets of the next H configurations, as deltas from
    /// the current joint angles.
    pub fn act(&mut self, obs: &Observation) -> Chunk {
        let m = &*self.model;
        debug_assert!(obs.q.len() == m.n && obs.q_before.len() == m.n);
        if self.deviation(obs.q) > OOD_RADIUS {
            self.ood_chunks += 1;
        }
        let x: Vec<f64> = obs
            .q
            .iter()
            .copied()
            .chain(obs.q.iter().zip(obs.q_before).map(|(a, b)| a - b))
            .zip(m.mean.iter().zip(&m.scale))
            .map(|(v, (mu, s))| (v - mu) / s)
            .collect();
        let mut offsets = vec![0.0; m.horizon * m.n];
        m.predict(
            &x,
            obs.stage,
            m.bandwidth,
            None,
            &mut self.weights,
            &mut offsets,
        );
        let mut prev = vec![0.0; m.n];
        let actions = offsets
            .chunks_exact(m.n)
            .map(|o| {
                let a: Vec<f64> = o.iter().zip(&prev).map(|(x, p)| x - p).collect();
                prev.copy_from_slice(o);
                a
            })
            .collect();
        Chunk {
            kind: ActionKind::Delta,
            actions,
            execute: m.execute,
            gripper: None,
        }
    }

    /// Distance (rad) from `q` to the nearest recorded configuration (replays not counted).
    pub fn deviation(&self, q: &[f64]) -> f64 {
        nearest_distance(self.model.demos.iter().flatten(), q)
    }

    /// Chunks produced while the robot was further than [`OOD_RADIUS`] from every recorded
    /// configuration.
    pub fn ood_chunks(&self) -> usize {
        self.ood_chunks
    }
}

impl Model {
    /// Mean squared error of predicting every sample's chunk from the other demonstrations.
    fn cross_validation_error(&self, bandwidth: f64, weights: &mut [f64]) -> f64 {
        let dims = 2 * self.n;
        let out = self.horizon * self.n;
        let mut prediction = vec![0.0; out];
        let (mut sum, mut count) = (0.0, 0usize);
        for i in 0..self.stages.len() {
            let x = &self.inputs[i * dims..(i + 1) * dims];
            let held_out = Some(self.demo_of[i]);
            if !self.predict(
                x,
                self.stages[i],
                bandwidth,
                held_out,
                weights,
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
    /// demonstration `skip`; `weights` is scratch space, one per sample. False if no sample
    /// takes part.
    fn predict(
        &self,
        x: &[f64],
        stage: usize,
        bandwidth: f64,
        skip: Option<usize>,
        weights: &mut [f64],
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
        for (i, w) in weights.iter_mut().enumerate() {
            let takes_part =
                (!any_of_stage || self.stages[i] == stage) && Some(self.demo_of[i]) != skip;
            *w = if takes_part {
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
        for (i, &r2) in weights.iter().enumerate() {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Demonstration `demonstration`: one joint through `path`, at `stage` throughout.
    fn rec(path: &[f64], stage: usize, demonstration: usize) -> Recording {
        Recording {
            path: path.iter().map(|&x| vec![x]).collect(),
            stages: vec![stage; path.len()],
            demonstration,
            pace: 1.0,
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

    fn act(p: &mut KernelPolicy, q: f64, before: f64, stage: usize) -> Vec<f64> {
        offsets(&p.act(&Observation {
            q: &[q],
            q_before: &[before],
            stage,
            t: 0.0,
            person: &[],
            person_before: &[],
        }))
    }

    #[test]
    fn reproduces_its_training_chunks_exactly() {
        // Two identical demonstrations: every held-out one is predicted without error, so
        // cross-validation keeps the narrowest width (0.025), where the neighbouring samples
        // (0.71 standard deviations away: squared 0.5) weigh exp(-0.5 / 0.00125) = exp(-400).
        let path = [0.0, 1.0, 2.0, 3.0, 4.0];
        let mut p = KernelPolicy::train(&[rec(&path, 0, 0), rec(&path, 0, 1)], 3, 2).unwrap();
        assert_eq!(p.bandwidth(), BANDWIDTHS[0]);
        assert!(p.cross_validation().next().unwrap().1 < 1e-24);
        assert_eq!((p.horizon(), p.execute(), p.paced()), (3, 2, false));
        // At sample 1 (q = 1, one Δt after q = 0): the next three samples 2, 3, 4, as deltas.
        let c = p.act(&Observation {
            q: &[1.0],
            q_before: &[0.0],
            stage: 0,
            t: 0.0,
            person: &[],
            person_before: &[],
        });
        assert_eq!(c.execute, 2);
        assert_eq!(c.kind, ActionKind::Delta);
        for (got, want) in offsets(&c).iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{c:?}");
        }
        // At the last sample the demonstration holds: offsets 0 (the path's end repeats).
        assert!(act(&mut p, 4.0, 3.0, 0).iter().all(|x| x.abs() < 1e-12));
    }

    #[test]
    fn the_observed_motion_selects_the_direction() {
        // Two demonstrations through the same configurations in opposite directions: only the
        // last two observations tell them apart.
        let mut p = KernelPolicy::train(
            &[
                rec(&[0.0, 1.0, 2.0, 3.0, 4.0], 0, 0),
                rec(&[4.0, 3.0, 2.0, 1.0, 0.0], 0, 1),
            ],
            2,
            1,
        )
        .unwrap();
        let up = act(&mut p, 2.0, 1.0, 0);
        let down = act(&mut p, 2.0, 3.0, 0);
        assert!(up[0] > 0.5 && up[1] > up[0], "{up:?}");
        assert!(down[0] < -0.5 && down[1] < down[0], "{down:?}");
    }

    #[test]
    fn samples_of_another_stage_never_take_part() {
        // Stage 0 moves up here; stage 1 moves down through the same place, at another pace.
        // At stage 1 the policy follows stage 1's data although stage 0's matches the
        // observation exactly.
        let up = [0.0, 1.0, 2.0, 3.0, 4.0];
        let down = [2.5, 2.0, 1.5, 1.0, 0.5];
        let mut p = KernelPolicy::train(
            &[
                rec(&up, 0, 0),
                rec(&up, 0, 1),
                rec(&down, 1, 2),
                rec(&down, 1, 3),
            ],
            2,
            1,
        )
        .unwrap();
        assert!(act(&mut p, 2.0, 1.0, 0)[0] > 0.99);
        let s1 = act(&mut p, 2.0, 1.0, 1);
        assert!(s1[0] < -0.1 && s1[1] < s1[0], "{s1:?}");
        // A stage no demonstration has: every sample takes part (here the exact match).
        assert!(act(&mut p, 2.0, 1.0, 7)[0] > 0.99);
    }

    #[test]
    fn far_from_the_data_the_chunk_stays_finite_and_within_the_demonstrated_offsets() {
        // Nadaraya–Watson is a weighted mean: every predicted offset lies between the smallest
        // and the largest demonstrated one, also where every kernel weight would underflow.
        let demos = [
            rec(&[0.0, 0.1, 0.3, 0.6, 1.0, 1.3, 1.5, 1.6], 0, 0),
            rec(&[0.05, 0.2, 0.35, 0.7, 1.05, 1.3, 1.55, 1.6], 0, 1),
            rec(&[-0.02, 0.1, 0.25, 0.55, 0.9, 1.25, 1.5, 1.62], 0, 2),
        ];
        let mut p = KernelPolicy::train(&demos, 4, 2).unwrap();
        let (lo, hi) = p
            .model
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
            let o = act(&mut p, q, b, 0);
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
        let path: Vec<Vec<f64>> = [0.0, 1.0, 3.0].iter().map(|&x| vec![x]).collect();
        let half = replay_path(&path, 0.5).unwrap();
        assert_eq!(half, [0.0, 0.5, 1.0, 2.0, 3.0].map(|x| vec![x]).to_vec());
        // A pace that does not divide the recording ends on its last sample.
        let p = replay_path(&path, 0.75).unwrap();
        assert_eq!(p.len(), 4);
        assert_eq!(p.last(), Some(&vec![3.0]));
        assert_eq!(replay_path(&path, 1.0).unwrap(), path);
        for pace in [0.0, 0.005, -0.5, 1.5, f64::NAN, f64::INFINITY] {
            assert!(matches!(replay_path(&path, pace), Err(TrainError::Pace(_))));
        }
    }

    #[test]
    fn a_demonstrations_copies_are_held_out_with_it() {
        // Exact copies of each demonstration, labelled as replays of it: if the copies were
        // not held out with their demonstration, each would predict it exactly and the
        // narrow widths' errors would vanish. Held out together, the other demonstration's
        // samples (and its copy's, doubling every weight alike) predict it, as without copies.
        let a = rec(&[0.0, 1.0, 2.0, 3.0, 4.0], 0, 0);
        let b = rec(&[0.0, 2.0, 4.0, 6.0, 8.0], 0, 1);
        let copy = |r: &Recording| Recording {
            pace: 0.5,
            ..r.clone()
        };
        let plain = KernelPolicy::train(&[a.clone(), b.clone()], 2, 1).unwrap();
        let with = KernelPolicy::train(&[a.clone(), copy(&a), b.clone(), copy(&b)], 2, 1).unwrap();
        assert!(with.paced() && !plain.paced());
        for ((w0, e0), (w1, e1)) in plain.cross_validation().zip(with.cross_validation()) {
            assert_eq!(w0, w1);
            assert!(e0 > 0.01, "width {w0}: {e0}");
            assert!((e0 - e1).abs() <= 1e-12 * e0, "width {w0}: {e0} vs {e1}");
        }
        // Deviation is measured from the recordings, not the replays.
        assert_eq!(with.model.demos.len(), 2);
    }

    #[test]
    fn refuses_what_it_cannot_learn_from() {
        let two = [rec(&[0.0, 1.0], 0, 0), rec(&[0.0, 1.0], 0, 1)];
        assert_eq!(
            KernelPolicy::train(&two[..1], 2, 1).unwrap_err(),
            TrainError::TooFewDemonstrations(1)
        );
        // Two recordings of one demonstration are still one demonstration.
        let same = [rec(&[0.0, 1.0], 0, 3), rec(&[0.0, 1.0], 0, 3)];
        assert_eq!(
            KernelPolicy::train(&same, 2, 1).unwrap_err(),
            TrainError::TooFewDemonstrations(1)
        );
        let mut bad = rec(&[0.0, 1.0], 0, 1);
        bad.stages.pop();
        assert_eq!(
            KernelPolicy::train(&[two[0].clone(), bad], 2, 1).unwrap_err(),
            TrainError::Malformed(1)
        );
        let mut going_back = rec(&[0.0, 1.0], 0, 1);
        going_back.stages = vec![1, 0];
        assert_eq!(
            KernelPolicy::train(&[two[0].clone(), going_back], 2, 1).unwrap_err(),
            TrainError::Malformed(1)
        );
        assert_eq!(
            KernelPolicy::train(&[rec(&[0.0], 0, 0), two[1].clone()], 2, 1).unwrap_err(),
            TrainError::Malformed(0)
        );
        assert_eq!(
            KernelPolicy::train(&[rec(&[0.0, f64::NAN], 0, 0), two[1].clone()], 2, 1).unwrap_err(),
            TrainError::NotFinite(0)
        );
        for (h, e) in [(0, 0), (2, 0), (2, 3)] {
            assert_eq!(
                KernelPolicy::train(&two, h, e).unwrap_err(),
                TrainError::Chunk {
                    horizon: h,
                    execute: e
                }
            );
        }
        for pace in [0.0, 0.005, 1.5, f64::NAN] {
            let mut r = two[1].clone();
            r.pace = pace;
            assert!(matches!(
                KernelPolicy::train(&[two[0].clone(), r], 2, 1),
                Err(TrainError::Pace(_))
            ));
        }
    }
}
