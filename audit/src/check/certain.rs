//! The certain check of [`Auditor`]: a possible violation is *certain* if it holds at a recorded
//! sample with the measured keypoints taken at face value.

use super::*;

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
    /// Evaluate the span's hits at the recorded sample `s` with the measured keypoints and
    /// object positions; updates each hit's `certain` and `separation`. Returns whether any hit
    /// is certain there. The classification is the rule's ([`pacs_verify::iso15066`]), with
    /// "certainly touches" (exact axis distance ≤ sum of radii) in place of "may touch", and the
    /// nominal whole-robot kinetic energy ½q̇ᵀM(q)q̇ at the sample in place of its bound. An
    /// object counts as its reference point dilated by its shape's radius (the point lies in
    /// the shape's zonotope, so a touch of that ball is a touch of the object), placed at its
    /// measured position taken at face value, and is decided by
    /// [`pacs_verify::iso15066::contact_violates`].
    pub(super) fn certain_at(
        &mut self,
        s: &Sample,
        s0: &Sample,
        s1: &Sample,
        slot: Option<usize>,
    ) -> bool {
        let n = self.n;
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
        // Consecutive spans share a sample: the capsules and the energy at the same joint
        // values (bit for bit) are reused.
        let same =
            |key: &[f64], v: &[f64]| key.iter().zip(v).all(|(a, b)| a.to_bits() == b.to_bits());
        if !(self.nom_key_valid && same(&self.nom_key[..n], &s.q[..n])) {
            self.robot.frames_into(&s.q[..n], &mut self.frames);
            for (c, local) in self.cap_local.iter().enumerate() {
                self.nom_caps[c] = local.transformed(&self.frames[self.rule.capsule_frame(c)]);
            }
            self.nom_key[..n].copy_from_slice(&s.q[..n]);
            self.nom_key_valid = true;
            self.nom_energy = None;
        }
        // The energy decides PFL hits and objects only: not computed for SSM-only hits (it is
        // then never read; NaN would compare false everywhere it could be).
        let parts = self.parts;
        let needs_energy = self
            .hits
            .iter()
            .any(|h| h.part >= parts || h.kind == ConstraintKind::Pfl);
        let energy = match self.nom_energy {
            _ if !needs_energy => f64::NAN,
            Some((e, key)) if same(&key[..n], &dq[..n]) => e,
            _ => {
                let e = self.robot.kinetic_energy(&s.q[..n], &dq[..n]);
                self.nom_energy = Some((e, dq));
                e
            }
        };
        let moving = known_dq && dq[..n].iter().any(|v| v.abs() > self.cfg.rest_speed);
        let pos = slot
            .and_then(|k| self.humans[k].as_ref())
            .map(|m| m.positions());
        let part_cap = |p: usize| {
            let bp = &self.human.body_parts()[p];
            pos.map(|pos| Capsule::new_unchecked(pos[bp.from], pos[bp.to], bp.thickness * 0.5))
        };
        let rule = &self.rule;
        let mut any = false;
        for k in 0..self.hits.len() {
            let h = self.hits[k];
            let (s_, e_) = self.rreach.link_ranges()[h.link];
            if h.part >= self.parts {
                let o = &self.objects[h.part - self.parts];
                let Some(m) = o.span.as_ref() else {
                    continue;
                };
                let p = nalgebra::Point3::from(m.position);
                let ball = Capsule::new_unchecked(p, p, o.model.shape_radius());
                let mut touch = false;
                let mut sep = f64::INFINITY;
                for c in s_..e_ {
                    sep = sep.min(signed_separation(&self.nom_caps[c], &ball));
                    touch |= certainly_touch(&self.nom_caps[c], &ball);
                }
                let (bad, _) = pacs_verify::iso15066::contact_violates(o.contact, !moving, || {
                    if known_dq { energy } else { f64::NEG_INFINITY }
                });
                let certain = touch && bad;
                let hit = &mut self.hits[k];
                hit.separation = hit.separation.min(sep);
                hit.certain |= certain;
                any |= certain;
                continue;
            }
            let Some(pc) = part_cap(h.part) else {
                continue;
            };
            let mut touch = false;
            let mut sep = f64::INFINITY;
            let mut frame = 0;
            for c in s_..e_ {
                sep = sep.min(signed_separation(&self.nom_caps[c], &pc));
                if certainly_touch(&self.nom_caps[c], &pc) {
                    touch = true;
                    frame = rule.capsule_frame(c);
                }
            }
            let certain = touch
                && match h.kind {
                    ConstraintKind::Ssm => moving,
                    // Body parts are never under no-contact.
                    ConstraintKind::NoContact => true,
                    ConstraintKind::Pfl => {
                        let clamp = self.environment.iter().any(|e| certainly_touch(e, &pc))
                            || (0..self.parts).any(|o| {
                                rule.clampable(h.part, o)
                                    && part_cap(o).is_some_and(|oc| certainly_touch(&oc, &pc))
                            })
                            || (0..self.nom_caps.len()).any(|o| {
                                frames_can_pinch(rule.capsule_frame(o), frame)
                                    && certainly_touch(&self.nom_caps[o], &pc)
                            });
                        let thr = threshold(rule.constraint(h.part), clamp);
                        known_dq && energy > thr
                    }
                };
            let hit = &mut self.hits[k];
            hit.separation = hit.separation.min(sep);
            hit.certain |= certain;
            any |= certain;
        }
        any
    }
}
