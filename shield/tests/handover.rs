//! Chunks planned off the control loop (`Shield::handover` → `ChunkPlanner::prepare` →
//! `Shield::offer`): taken over exactly as `set_chunk` at the handover would be, dropped when the
//! commands went elsewhere, never a jump in the commands.

mod common;

use common::{Lcg, assert_continuous, human, random_chunk, same, shield};

use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_shield::ChunkMotion;
use pacs_shield::shield::{Command, OfferState, Shield, ShieldError};

/// A chunk planned `lead` steps ahead and offered is, once its handover comes, the same as the
/// chunk handed to `set_chunk` right before that step: the two shields give bitwise the same
/// commands (unless a step in between was not verified: then the offer is dropped).
#[test]
fn an_offered_chunk_is_set_chunk_at_its_handover() {
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let h = human();
    let mut rng = Lcg(7);
    let (mut taken, mut cases) = (0, 0);
    for motion in [ChunkMotion::Continuous, ChunkMotion::Stop] {
        let mut sync = shield(motion);
        let mut offered = shield(motion);
        let dt = sync.config().safety_step;
        let mut planner = offered.chunk_planner();
        let mut k = 0usize;
        while k < 3000 {
            let lead = rng.below(13);
            let gap = 20 + rng.below(200);
            let chunk = random_chunk(&mut rng);
            let t_r = k as f64 * dt;
            let ho = offered.handover(lead).expect("started, admissible");
            assert!((ho.t - (t_r + lead as f64 * dt)).abs() < 1e-9);
            let prepared = planner.prepare(&ho, &chunk);
            let offer_ok = prepared.is_ok_and(|p| offered.offer(p).is_ok());
            // An offer from the state the robot stands in is taken over at once.
            let at_once = matches!(offered.offer_state(), OfferState::Taken(_));
            let mut unverified = false;
            for j in 0..gap {
                let t = (k + j) as f64 * dt;
                if offer_ok && ((at_once && j == 0) || (!at_once && j == lead)) {
                    // set_chunk plans from the state before this step, as the offer was.
                    sync.set_chunk(&chunk).unwrap();
                }
                let m = HumanMeasurement::new(&h, t, &far, None).unwrap();
                let a = sync.step(t, Some(&m)).unwrap();
                let b = offered.step(t, Some(&m)).unwrap();
                if j < lead {
                    unverified |= !b.diag.verified;
                }
                if offered.offer_state() == OfferState::Stale {
                    break;
                }
                assert!(
                    same(&a, &b),
                    "{motion:?}, lead {lead}: commands differ at t = {t}: {:?} vs {:?}",
                    a.q().to_vec(),
                    b.q().to_vec()
                );
            }
            if !offer_ok {
                k += gap;
                continue;
            }
            cases += 1;
            match offered.offer_state() {
                OfferState::Followed(n) => {
                    taken += 1;
                    assert_eq!(
                        offered.chunk_progress().unwrap().accepted,
                        n,
                        "the serial is the accepted count"
                    );
                }
                // Taken over, but its first monitored step was not verified (as `set_chunk`'s
                // chunk in `sync`).
                OfferState::Dropped(n) => {
                    assert_eq!(offered.chunk_progress().unwrap().accepted, n);
                    assert_ne!(offered.chunk_progress().unwrap().chunk, n);
                }
                OfferState::Stale => {
                    assert!(unverified, "dropped although every step was verified");
                    // Re-align the two shields for the next case.
                    sync = offered.clone();
                }
                s => panic!("offer left {s:?} after its handover"),
            }
            k += gap;
        }
    }
    eprintln!("{taken} of {cases} offers taken over");
    assert!(cases >= 30, "{cases} cases");
    assert!(
        taken * 10 >= cases * 9,
        "only {taken} of {cases} offers were taken over (the comparison is too weak)"
    );
}

/// A plan from a state the commands never reach is dropped at its handover and the commands
/// stay continuous (a shield that took it over would jump to its start).
#[test]
fn an_offer_from_another_state_is_dropped() {
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let h = human();
    let mut rng = Lcg(11);
    for lead in [0usize, 1, 5] {
        let mut sh = shield(ChunkMotion::Continuous);
        let dt = sh.config().safety_step;
        let mut planner = sh.chunk_planner();
        sh.set_chunk(&random_chunk(&mut rng)).unwrap();
        let mut prev: Option<Command> = None;
        for k in 0..400 {
            let t = k as f64 * dt;
            if k == 200 {
                let mut ho = sh.handover(lead).unwrap();
                ho.start.q[0] += 0.05; // a plan from somewhere else
                let p = planner.prepare(&ho, &random_chunk(&mut rng)).unwrap();
                sh.offer(p).unwrap();
                assert_eq!(sh.offer_state(), OfferState::Waiting);
            }
            let m = HumanMeasurement::new(&h, t, &far, None).unwrap();
            let cmd = sh.step(t, Some(&m)).unwrap();
            if let Some(p) = &prev {
                assert_continuous(p, &cmd);
            }
            prev = Some(cmd);
        }
        assert_eq!(sh.offer_state(), OfferState::Stale, "lead {lead}");
        assert_eq!(sh.chunk_progress().unwrap().accepted, 1, "lead {lead}");
    }
}

/// An offer that comes back after its handover step ran is refused with `Stale`; the shield
/// keeps its motion.
#[test]
fn an_offer_past_its_handover_is_refused() {
    let mut sh = shield(ChunkMotion::Continuous);
    let dt = sh.config().safety_step;
    let mut rng = Lcg(3);
    sh.set_chunk(&random_chunk(&mut rng)).unwrap();
    let mut planner = sh.chunk_planner();
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let h = human();
    let step = |sh: &mut Shield, k: usize| {
        let t = k as f64 * dt;
        let m = HumanMeasurement::new(&h, t, &far, None).unwrap();
        assert!(sh.step(t, Some(&m)).unwrap().diag.verified);
    };
    for k in 0..50 {
        step(&mut sh, k);
    }
    let ho = sh.handover(2).unwrap();
    let p = planner.prepare(&ho, &random_chunk(&mut rng)).unwrap();
    for k in 50..60 {
        step(&mut sh, k);
    }
    let r = sh.offer(p);
    assert!(
        matches!(r, Err(ShieldError::Stale { .. })),
        "{r:?} at {:?}",
        sh.state().dq[..7].to_vec()
    );
    assert_eq!(sh.offer_state(), OfferState::Stale);
    assert_eq!(sh.chunk_progress().unwrap().accepted, 1);
    // A waiting offer that is withdrawn is never taken over.
    let ho = sh.handover(3).unwrap();
    sh.offer(planner.prepare(&ho, &random_chunk(&mut rng)).unwrap())
        .unwrap();
    assert_eq!(sh.offer_state(), OfferState::Waiting);
    assert!(sh.withdraw_offer());
    for k in 60..70 {
        step(&mut sh, k);
    }
    assert_eq!(sh.chunk_progress().unwrap().accepted, 1);
    assert!(!sh.withdraw_offer());
}

/// With a person walking up to the robot and away, offers with random leads are taken over or
/// dropped; every command lies on an accepted chunk's trajectory and follows the previous one
/// within the robot's limits. The shield's record of each chunk's fate is what its commands did:
/// `Followed(n)` after the step that verified chunk n's first monitored step (the commands are
/// on chunk n), `Dropped(n)` after the step that did not (they are not).
#[test]
fn offers_keep_the_commands_on_the_path_with_a_person_walking_in() {
    let h = human();
    let mut rng = Lcg(5);
    let mut sh = shield(ChunkMotion::Continuous);
    let dt = sh.config().safety_step;
    let mut planner = sh.chunk_planner();
    let (mut taken, mut stale, mut followed, mut dropped) = (0, 0, 0, 0);
    let mut prev: Option<Command> = None;
    let mut next_offer = 0;
    let mut last_state = OfferState::None;
    for k in 0..6000 {
        let t = k as f64 * dt;
        if k == next_offer {
            let ho = sh.handover(rng.below(20)).unwrap();
            if let Ok(p) = planner.prepare(&ho, &random_chunk(&mut rng)) {
                sh.offer(p).unwrap();
            }
            next_offer += 30 + rng.below(150);
        }
        let d = 0.45 + 0.6 * (1.5 * t).cos().abs();
        let kp = pacs_testkit::human_reaching(d + 0.3, 0.0, [d, 0.0, 0.6]);
        let m = HumanMeasurement::new(&h, t, &kp, None).unwrap();
        let cmd = sh.step(t, Some(&m)).unwrap();
        let verified = cmd.diag.verified;
        let (traj, p) = sh.path();
        let on = p.joint_state(traj);
        assert_eq!(&on.q[..7], cmd.q(), "command off the path at {t}");
        if let Some(p) = &prev {
            assert_continuous(p, &cmd);
        }
        prev = Some(cmd);
        let s = sh.offer_state();
        let on = sh.chunk_progress().unwrap().chunk;
        if s != last_state {
            match s {
                OfferState::Taken(_) => taken += 1,
                OfferState::Followed(n) => {
                    // Taken over at this step's start (or at the offer) and tried by it.
                    assert!(verified, "followed without a verified step at {t}");
                    assert_eq!(on, n, "followed, but the commands are on chunk {on} at {t}");
                    followed += 1;
                }
                OfferState::Dropped(n) => {
                    assert!(!verified, "dropped after a verified step at {t}");
                    assert_ne!(on, n, "dropped, but the commands follow it at {t}");
                    dropped += 1;
                }
                OfferState::Stale => stale += 1,
                _ => {}
            }
            last_state = s;
        }
    }
    eprintln!("taken at once {taken}, followed {followed}, dropped {dropped}, stale {stale}");
    assert!(
        followed >= 5 && dropped >= 1 && stale >= 1,
        "followed {followed}, dropped {dropped}, stale {stale}"
    );
}

/// Chunks handed over while the robot brakes for a person or speeds up again after one are
/// planned. The failsafe brakes with up to the robot's acceleration, beyond the intended limits
/// (0.8 of it): such starts (the walking scenario's states with the fastest joint decelerating
/// at 0.95 of the robot's limit) are planned within the robot's limits instead of being
/// rejected.
#[test]
fn a_chunk_from_a_braking_or_ramping_state_is_planned() {
    let h = human();
    let mut rng = Lcg(23);
    let mut sh = shield(ChunkMotion::Continuous);
    let dt = sh.config().safety_step;
    let mut planner = sh.chunk_planner();
    let (mut starts, mut planned, mut beyond) = (0, 0, 0);
    let a_int = 0.8 * 10.0;
    for k in 0..6000 {
        let t = k as f64 * dt;
        if k % 400 == 0 {
            sh.set_chunk(&random_chunk(&mut rng)).ok();
        }
        if k % 7 == 0 {
            for lead in [0, 2, 5] {
                let ho = sh.handover(lead).unwrap();
                let moving = ho.start.dq[..7].iter().any(|&v| v != 0.0);
                if !moving {
                    continue;
                }
                let mut braking = ho.start;
                let fast = (0..7)
                    .max_by(|&a, &b| braking.dq[a].abs().total_cmp(&braking.dq[b].abs()))
                    .unwrap();
                braking.ddq[fast] = -0.95 * 10.0 * braking.dq[fast].signum();
                for st in [ho.start, braking] {
                    starts += 1;
                    let amax = st.ddq[..7].iter().fold(0.0f64, |m, a| m.max(a.abs()));
                    beyond += (amax > a_int * (1.0 + 1e-6)) as usize;
                    match planner.plan(&st, &random_chunk(&mut rng)) {
                        Ok(traj) => {
                            planned += 1;
                            let s0 = traj.state_at(0.0);
                            assert_eq!(s0.q[..7], st.q[..7]);
                            assert_eq!(s0.dq[..7], st.dq[..7]);
                            assert_eq!(s0.ddq[..7], st.ddq[..7]);
                        }
                        Err(e) => eprintln!("{amax} rad/s²: {e}"),
                    }
                }
            }
        }
        let d = 0.45 + 0.6 * (1.5 * t).cos().abs();
        let kp = pacs_testkit::human_reaching(d + 0.3, 0.0, [d, 0.0, 0.6]);
        let m = HumanMeasurement::new(&h, t, &kp, None).unwrap();
        sh.step(t, Some(&m)).unwrap();
    }
    eprintln!(
        "{planned} of {starts} moving starts planned ({beyond} beyond the intended acceleration)"
    );
    assert!(
        starts >= 500 && beyond >= 10,
        "starts {starts}, beyond {beyond}"
    );
    assert_eq!(planned, starts);
}

/// Chunks recorded from the demonstration policy at a pause (deltas of 1e-8–1e-7 rad from a
/// standstill) that the planner once refused (a 2.6e-9 rad position discontinuity; a jerk 2 %
/// over the limit): they plan, and the trajectory stays within the intended limits.
#[test]
fn chunks_of_tiny_moves_from_rest_plan() {
    let cases: Vec<([f64; 7], Vec<Vec<f64>>)> = vec![
        (
            [
                -0.36042598140821835,
                0.1413894379219355,
                -0.3408115382955704,
                -2.1753607529053216,
                0.00146058855784062,
                2.2336263336015945,
                0.7853981633958272,
            ],
            vec![
                vec![
                    3.772683226932472e-08,
                    -1.3804455217814038e-08,
                    3.8427279080988086e-08,
                    -5.743360897980665e-09,
                    2.310467026468005e-09,
                    -5.0635451387393005e-09,
                    -1.1102230246251565e-16,
                ],
                vec![
                    3.206780746500826e-08,
                    -1.173378691432525e-08,
                    3.26631872105132e-08,
                    -4.881856696670184e-09,
                    1.963896972346016e-09,
                    -4.3040131458838005e-09,
                    0.0,
                ],
                vec![
                    2.7257636314725886e-08,
                    -9.973718878564242e-09,
                    2.7763709109507317e-08,
                    -4.149578014533972e-09,
                    1.6693124265700077e-09,
                    -3.6584113516369143e-09,
                    -1.1102230246251565e-16,
                ],
                vec![
                    2.316899089249702e-08,
                    -8.477661045391827e-09,
                    2.359915274308122e-08,
                    -3.527141245740495e-09,
                    1.4189155625194544e-09,
                    -3.109649870935982e-09,
                    0.0,
                ],
                vec![
                    1.9693642272500256e-08,
                    -7.206011898297504e-09,
                    2.0059279848272382e-08,
                    -2.9980702365151046e-09,
                    1.2060782281740623e-09,
                    -2.6432021016375984e-09,
                    0.0,
                ],
                vec![
                    1.6739595876114066e-08,
                    -6.1251101135528785e-09,
                    1.7050387879358198e-08,
                    -2.54835974544676e-09,
                    1.025166494013005e-09,
                    -2.2467219196187216e-09,
                    0.0,
                ],
                vec![
                    1.4228656530779205e-08,
                    -5.206343606234398e-09,
                    1.4492829658596662e-08,
                    -2.16610596126543e-09,
                    8.713915199218963e-10,
                    -1.9097137204937553e-09,
                    -1.1102230246251565e-16,
                ],
                vec![
                    1.2094358070591227e-08,
                    -4.4253920528092294e-09,
                    1.2318905284747217e-08,
                    -1.841189867235471e-09,
                    7.406827917926656e-10,
                    -1.6232561961260217e-09,
                    0.0,
                ],
                vec![
                    1.0280204354451428e-08,
                    -3.76158323933673e-09,
                    1.0471069400441735e-08,
                    -1.5650112317189269e-09,
                    6.295803732948163e-10,
                    -1.3797682996141702e-09,
                    0.0,
                ],
                vec![
                    8.738173684630368e-09,
                    -3.197345749272884e-09,
                    8.900409076417759e-09,
                    -1.3302599022324557e-09,
                    5.351433170295433e-10,
                    -1.1728027438095978e-09,
                    0.0,
                ],
                vec![
                    7.42744760140468e-09,
                    -2.717743891045288e-09,
                    7.565347626137253e-09,
                    -1.130720406194996e-09,
                    4.5487181968111023e-10,
                    -9.968825764872236e-10,
                    0.0,
                ],
                vec![
                    6.313330525031802e-09,
                    -2.3100823198785037e-09,
                    6.430545540503374e-09,
                    -9.611129669906404e-10,
                    3.866410464362091e-10,
                    -8.4735019001414e-10,
                    0.0,
                ],
                vec![
                    5.36633087966365e-09,
                    -1.963569973284507e-09,
                    5.465963681672292e-09,
                    -8.169456222617555e-10,
                    3.2864488973098627e-10,
                    -7.202474172629536e-10,
                    -1.1102230246251565e-16,
                ],
                vec![
                    4.5613812726941205e-09,
                    -1.6690344661896006e-09,
                    4.64606919603483e-09,
                    -6.944036456957292e-10,
                    2.793481561520761e-10,
                    -6.122102824690501e-10,
                    0.0,
                ],
                vec![
                    3.8771740817900024e-09,
                    -1.4186792851589303e-09,
                    3.949158722260648e-09,
                    -5.902434097038167e-10,
                    2.3744593292442107e-10,
                    -5.20378851120995e-10,
                    0.0,
                ],
                vec![
                    3.2955980167059806e-09,
                    -1.2058774256917815e-09,
                    3.3567849611060296e-09,
                    -5.017066762036393e-10,
                    2.0182904284481162e-10,
                    -4.423221788840692e-10,
                    0.0,
                ],
            ],
        ),
        (
            [
                -0.3568190162207734,
                0.13408739943917894,
                -0.33759074078074897,
                -2.1857685649104805,
                0.004050036979662451,
                2.2236346789364116,
                0.7853981633595566,
            ],
            vec![
                vec![
                    -2.0387249383135853e-07,
                    2.6309289180570516e-07,
                    -1.9258633654484214e-07,
                    3.0527427608006974e-07,
                    -1.2850658466252024e-07,
                    3.326609068210473e-07,
                    3.9968028886505635e-15,
                ],
                vec![
                    -1.732916197205725e-07,
                    2.2362895804595162e-07,
                    -1.6369838601315578e-07,
                    2.594831345348325e-07,
                    -1.0923059696327231e-07,
                    2.8276177088670806e-07,
                    3.4416913763379853e-15,
                ],
                vec![
                    -1.4729787678469108e-07,
                    1.9008461435432444e-07,
                    -1.3914362817502024e-07,
                    2.2056066484310577e-07,
                    -9.284600741878146e-08,
                    2.40347505453542e-07,
                    2.886579864025407e-15,
                ],
                vec![
                    -1.252031952558852e-07,
                    1.6157192217480798e-07,
                    -1.1827208390435828e-07,
                    1.87476564494915e-07,
                    -7.891910630639792e-08,
                    2.0429537928023933e-07,
                    2.55351295663786e-15,
                ],
                vec![
                    -1.0642271597305353e-07,
                    1.3733613388189347e-07,
                    -1.0053127130760231e-07,
                    1.593550802425625e-07,
                    -6.70812403602214e-08,
                    1.736510726324525e-07,
                    2.1094237467877974e-15,
                ],
                vec![
                    -9.045930859929996e-08,
                    1.1673571376213943e-07,
                    -8.545158064476865e-08,
                    1.3545181820617813e-07,
                    -5.7019054306231554e-08,
                    1.4760341171538016e-07,
                    1.7763568394002505e-15,
                ],
                vec![
                    -7.689041225944493e-08,
                    9.922535670892074e-08,
                    -7.263384355082891e-08,
                    1.1513404540863803e-07,
                    -4.846619615968967e-08,
                    1.2546290006909544e-07,
                    1.4432899320127035e-15,
                ],
                vec![
                    -6.535685043163042e-08,
                    8.434155321368486e-08,
                    -6.173876698767344e-08,
                    9.786393828647988e-08,
                    -4.1196266736473475e-08,
                    1.0664346472566422e-07,
                    1.3322676295501878e-15,
                ],
                vec![
                    -5.555332288631476e-08,
                    7.169032023579547e-08,
                    -5.247795198393135e-08,
                    8.318434785437034e-08,
                    -3.501682672556877e-08,
                    9.064694550531271e-08,
                    1.1102230246251565e-15,
                ],
                vec![
                    -4.722032448389868e-08,
                    6.09367721837728e-08,
                    -4.4606259130830495e-08,
                    7.070669560960141e-08,
                    -2.9764302716950297e-08,
                    7.70499033464489e-08,
                    8.881784197001252e-16,
                ],
                vec![
                    -4.0137275780782744e-08,
                    5.179625636730911e-08,
                    -3.79153203278193e-08,
                    6.010069153461473e-08,
                    -2.529965730923428e-08,
                    6.54924177112548e-08,
                    8.881784197001252e-16,
                ],
                vec![
                    -3.4116684421992005e-08,
                    4.4026817913600524e-08,
                    -3.222802225089083e-08,
                    5.1085587315924386e-08,
                    -2.1504708713412923e-08,
                    5.56685550989755e-08,
                    6.661338147750939e-16,
                ],
                vec![
                    -2.8999181722610956e-08,
                    3.742279522378489e-08,
                    -2.7393818879950516e-08,
                    4.342274939617141e-08,
                    -1.8279002405446887e-08,
                    4.731827196735594e-08,
                    5.551115123125783e-16,
                ],
                vec![
                    -2.4649304486423773e-08,
                    3.1809375938829376e-08,
                    -2.3284746075713514e-08,
                    3.690933736422153e-08,
                    -1.553715204584416e-08,
                    4.022053134988823e-08,
                    4.440892098500626e-16,
                ],
                vec![
                    -2.0951908819011322e-08,
                    2.7037969529963846e-08,
                    -1.9792034178234275e-08,
                    3.137293624888571e-08,
                    -1.320657923818691e-08,
                    3.4187451536382696e-08,
                    4.440892098500626e-16,
                ],
                vec![
                    -1.7809122510037412e-08,
                    2.29822741115715e-08,
                    -1.682322903207023e-08,
                    2.666699616682422e-08,
                    -1.1225592352372138e-08,
                    2.9059333606085147e-08,
                    3.3306690738754696e-16,
                ],
            ],
        ),
    ];
    let sh = shield(ChunkMotion::Continuous);
    let mut planner = sh.chunk_planner();
    for (i, (q, actions)) in cases.into_iter().enumerate() {
        let mut start = pacs_motion::trajectory::JointState::default();
        start.q[..7].copy_from_slice(&q);
        let chunk = Chunk {
            kind: ActionKind::Delta,
            actions,
            execute: 8,
            gripper: None,
        };
        let traj = planner.plan(&start, &chunk);
        assert!(traj.is_ok(), "case {i}: {:?}", traj.err());
    }
}
