//! URDF loading: the hand-made FR3 URDF + side file must reproduce the built-in FR3; a planar
//! 2-link arm is checked against hand-computed values; malformed inputs give typed errors.

mod common;

use common::{Rng, data, quad, read};
use nalgebra::{Point3, Vector3};
use pacs_models::ModelError;
use pacs_models::fr3::fr3;
use pacs_models::urdf::{SideFile, load_urdf, load_urdf_files, urdf_to_spec};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_3, FRAC_PI_6};

fn fr3_from_urdf() -> pacs_models::RobotModel {
    load_urdf_files(&data("fr3.urdf"), Some(&data("fr3_side.toml"))).expect("fr3.urdf loads")
}

#[test]
fn fr3_urdf_structure_and_limits() {
    let u = fr3_from_urdf();
    let b = fr3();
    assert_eq!(u.name(), "fr3");
    assert_eq!(u.dof(), 7);
    let names: Vec<&str> = u.joints().iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        (1..=7).map(|i| format!("fr3_joint{i}")).collect::<Vec<_>>()
    );
    assert_eq!(
        u.limits(),
        b.limits(),
        "q from URDF, v from URDF, a = 10 and j = 5000 from the side file"
    );
    // Fixed links are carried by the last chain joint; fingers are frozen (closed) onto the hand.
    for (name, frame) in [
        ("fr3_link0", 0),
        ("fr3_link7", 7),
        ("fr3_link8", 7),
        ("fr3_hand", 7),
        ("fr3_hand_tcp", 7),
        ("fr3_leftfinger", 7),
    ] {
        let l = &u.links()[u.link_index(name).unwrap_or_else(|| panic!("{name}"))];
        assert_eq!(l.frame, frame, "{name}");
    }
    assert_eq!(u.capsule_count(), b.capsule_count());
}

#[test]
fn fr3_urdf_fk_equals_builtin_for_random_configurations() {
    let u = fr3_from_urdf();
    let b = fr3();
    let mut rng = Rng::new(42);
    for _ in 0..100 {
        let q = rng.config(&b);
        let (fu, fb) = (u.frames(&q), b.frames(&q));
        for k in 0..=7 {
            assert!(
                (fu[k].to_homogeneous() - fb[k].to_homogeneous())
                    .abs()
                    .max()
                    < 1e-12,
                "frame {k}"
            );
        }
        let (cu, cb) = (u.capsules_world(&q), b.capsules_world(&q));
        let mut compared = 0;
        for (bi, bl) in b.links().iter().enumerate() {
            let Some(ui) = u.link_index(&bl.name) else {
                assert!(
                    bl.capsules.is_empty(),
                    "built-in link {} with capsules missing in URDF model",
                    bl.name
                );
                continue;
            };
            let a: Vec<_> = cu
                .iter()
                .filter(|(li, _)| *li == ui)
                .map(|(_, c)| *c)
                .collect();
            let e: Vec<_> = cb
                .iter()
                .filter(|(li, _)| *li == bi)
                .map(|(_, c)| *c)
                .collect();
            assert_eq!(a.len(), e.len(), "{}", bl.name);
            for (x, y) in a.iter().zip(&e) {
                assert!(
                    (x.p1() - y.p1()).norm() < 1e-12,
                    "{} p1 {} vs {}",
                    bl.name,
                    x.p1(),
                    y.p1()
                );
                assert!((x.p2() - y.p2()).norm() < 1e-12, "{} p2", bl.name);
                assert_eq!(x.radius(), y.radius());
                compared += 1;
            }
        }
        assert_eq!(compared, 12);
    }
}

#[test]
fn fr3_urdf_mass_properties_equal_builtin() {
    // The URDF has two separate (frozen) fingers; the built-in lumps them into one body: the mass
    // matrices and energies must still agree, which also checks the built-in lumping.
    let u = fr3_from_urdf();
    let b = fr3();
    let total = |r: &pacs_models::RobotModel| {
        r.links()
            .iter()
            .filter_map(|l| l.inertial)
            .map(|i| i.mass)
            .sum::<f64>()
    };
    assert!((total(&u) - total(&b)).abs() < 1e-12);
    assert!(
        (total(&u) - (17.8914 + 0.7126)).abs() < 1e-4,
        "facts §3 sums"
    );
    let mut rng = Rng::new(43);
    for _ in 0..100 {
        let q = rng.config(&b);
        let dq = rng.velocity(&b);
        let (mu, mb) = (u.mass_matrix(&q), b.mass_matrix(&q));
        assert!(
            (&mu - &mb).abs().max() < 1e-12,
            "{}",
            (&mu - &mb).abs().max()
        );
        let (eu, eb) = (u.kinetic_energy(&q, &dq), b.kinetic_energy(&q, &dq));
        assert!((eu - eb).abs() <= 1e-12 * eb, "{eu} vs {eb}");
        assert!((eu - quad(&mu, &dq)).abs() <= 1e-10 * eu);
    }
}

fn planar() -> pacs_models::RobotModel {
    load_urdf_files(&data("planar2.urdf"), Some(&data("planar2_side.json"))).expect("planar2 loads")
}

#[test]
fn planar_fk_hand_computed() {
    let r = planar();
    assert_eq!(r.name(), "planar2");
    assert_eq!(r.dof(), 2);
    let tool = r.link_index("tool").unwrap();
    // Tool origin = base (0,0,0.5) + (cos q1 + 0.8 cos(q1+q2), sin q1 + 0.8 sin(q1+q2), 0).
    for (q, e) in [
        ([0.0, 0.0], [1.8, 0.0, 0.5]),
        ([FRAC_PI_6, FRAC_PI_3], [0.8660254037844386, 1.3, 0.5]),
        ([FRAC_PI_2, -FRAC_PI_2], [0.8, 1.0, 0.5]),
        (
            [-FRAC_PI_2, 3.0],
            [0.8 * 3.0f64.sin(), -1.0 - 0.8 * 3.0f64.cos(), 0.5],
        ),
    ] {
        let caps = r.capsules_world(&q);
        let (_, c) = caps.iter().find(|(li, _)| *li == tool).unwrap();
        assert!(
            (c.p1() - Point3::from(e)).norm() < 1e-12,
            "q={q:?}: {}",
            c.p1()
        );
        assert_eq!(c.p1(), c.p2());
        assert_eq!(c.radius(), 0.02);
    }
}

#[test]
fn planar_limits_from_urdf_and_side_file() {
    let l = planar().limits().clone();
    assert_eq!(l.q_min(), &[-2.5, -3.0]); // URDF revolute; side file for the continuous elbow
    assert_eq!(l.q_max(), &[2.5, 3.0]);
    assert_eq!(l.v_max(), &[2.0, 3.0]); // URDF velocity
    assert_eq!(l.a_max(), &[5.0, 5.0]); // uniform side value
    assert_eq!(l.j_max(), &[100.0, 50.0]); // per-joint side value wins over uniform
}

#[test]
fn planar_collision_primitives_become_capsules() {
    let spec = urdf_to_spec(
        &read("planar2.urdf"),
        &SideFile::parse(&read("planar2_side.json")).unwrap(),
    )
    .unwrap();
    let link = |n: &str| spec.links.iter().find(|l| l.name == n).unwrap();
    // Cylinder r = 0.05, L = 1 along x from 0 to 1 (origin x 0.5, pitch π/2).
    let up = &link("upper").capsules;
    assert_eq!(up.len(), 1);
    let (a, b) = (Vector3::from(up[0].p1), Vector3::from(up[0].p2));
    let (lo, hi) = if a.x < b.x { (a, b) } else { (b, a) };
    assert!(
        (lo - Vector3::zeros()).norm() < 1e-15 && (hi - Vector3::x()).norm() < 1e-15,
        "{lo} {hi}"
    );
    assert_eq!(up[0].radius, 0.05);
    // Sphere → ball; box 0.2 × 0.1 × 0.4 → segment ±0.2 on z, radius ½·√(0.2² + 0.1²).
    let fore = &link("fore").capsules;
    assert_eq!(fore.len(), 2);
    assert_eq!(fore[0].p1, [0.8, 0.0, 0.0]);
    assert_eq!(fore[0].p2, [0.8, 0.0, 0.0]);
    assert_eq!(fore[0].radius, 0.1);
    assert_eq!(fore[1].p1, [0.3, 0.0, -0.2]);
    assert_eq!(fore[1].p2, [0.3, 0.0, 0.2]);
    assert!((fore[1].radius - 0.5 * (0.05f64).sqrt()).abs() < 1e-16);
    // Every corner of the box lies within the capsule.
    for sx in [-0.1, 0.1] {
        for sy in [-0.05, 0.05] {
            for sz in [-0.2, 0.2] {
                // Distance from the corner (box centre at x = 0.3) to the capsule's segment.
                let p = Vector3::new(0.3 + sx, sy, sz);
                let (a, b) = (Vector3::from(fore[1].p1), Vector3::from(fore[1].p2));
                let t = ((p - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                let d = (p - (a + t * (b - a))).norm();
                assert!(d <= fore[1].radius + 1e-15, "corner ({sx},{sy},{sz}): {d}");
            }
        }
    }
    // Frames: upper and fore on the two joints, tool fixed 0.8 m along fore's x.
    assert_eq!(link("upper").parent, "shoulder");
    assert_eq!(link("fore").parent, "elbow");
    assert_eq!(link("tool").parent, "elbow");
    assert_eq!(link("tool").origin.xyz, [0.8, 0.0, 0.0]);
    assert_eq!(link("ground").parent, "base");
}

#[test]
fn planar_inertial_origin_rotates_inertia() {
    let spec = urdf_to_spec(
        &read("planar2.urdf"),
        &SideFile::parse(&read("planar2_side.json")).unwrap(),
    )
    .unwrap();
    let fore = spec
        .links
        .iter()
        .find(|l| l.name == "fore")
        .unwrap()
        .inertial
        .unwrap();
    assert_eq!(fore.mass, 1.0);
    assert_eq!(fore.com, [0.4, 0.0, 0.0]);
    // rpy (0,0,π/6), I' = diag(0.04, 0.001, 0.05): I = R I' Rᵀ with R = Rz(π/6):
    // ixx = 0.04·¾ + 0.001·¼, iyy = 0.04·¼ + 0.001·¾, ixy = (0.04 − 0.001)·sin·cos = 0.039·√3/4.
    let expect = [0.03025, 0.039 * 3f64.sqrt() / 4.0, 0.0, 0.01075, 0.0, 0.05];
    for (a, e) in fore.inertia.iter().zip(expect) {
        assert!((a - e).abs() < 1e-15, "{:?}", fore.inertia);
    }
    let up = spec
        .links
        .iter()
        .find(|l| l.name == "upper")
        .unwrap()
        .inertial
        .unwrap();
    assert_eq!(up.inertia, [0.01, 0.0, 0.0, 0.1, 0.0, 0.1]);
    assert!(
        spec.links
            .iter()
            .find(|l| l.name == "tool")
            .unwrap()
            .inertial
            .is_none(),
        "no <inertial> = massless"
    );
}

#[test]
fn planar_energy_hand_computed() {
    // m1 = 2, c1 = 0.5, I1 = 0.1; m2 = 1, l1 = 1, c2 = 0.4, I2 = 0.05 (about z):
    // M11 = I1 + m1c1² + I2 + m2(l1² + c2² + 2 l1 c2 cos q2) = 1.81 + 0.8 cos q2,
    // M12 = I2 + m2(c2² + l1 c2 cos q2) = 0.21 + 0.4 cos q2, M22 = 0.21.
    let r = planar();
    let q = [0.3, FRAC_PI_3]; // cos q2 = 0.5 → M = [[2.21, 0.41], [0.41, 0.21]]
    let m = r.mass_matrix(&q);
    let expect = [[2.21, 0.41], [0.41, 0.21]];
    for i in 0..2 {
        for j in 0..2 {
            assert!(
                (m[(i, j)] - expect[i][j]).abs() < 1e-12,
                "M[{i}{j}] = {}",
                m[(i, j)]
            );
        }
    }
    // dq = (1, 2): E = ½(2.21 + 2·0.41·2 + 0.21·4) = 2.345; upper arm alone: ½·0.6·1 = 0.3.
    let mut e = [0.0; 3];
    r.subchain_energies_into(&q, &[1.0, 2.0], &mut e);
    assert!((e[1] - 0.3).abs() < 1e-12, "{e:?}");
    assert!((e[2] - 2.345).abs() < 1e-12, "{e:?}");
}

#[test]
fn leaf_and_tip_selection() {
    // FR3 URDF has three leaves (tcp and two fingers): without a tip it is ambiguous.
    let urdf = read("fr3.urdf");
    match load_urdf(
        &urdf,
        &SideFile {
            a_max: Some(10.0),
            j_max: Some(5000.0),
            ..Default::default()
        },
    ) {
        Err(ModelError::Invalid(m)) => {
            assert!(m.contains("leaf") && m.contains("fr3_hand_tcp"), "{m}")
        }
        other => panic!("{other:?}"),
    }
    // Tip = link4: 4 joints; links beyond are frozen at 0 (clamped into limits) onto joint 4.
    let mut side = SideFile::parse(&read("fr3_side.toml")).unwrap();
    side.tip = Some("fr3_link4".into());
    let r = load_urdf(&urdf, &side).unwrap();
    assert_eq!(r.dof(), 4);
    let l7 = &r.links()[r.link_index("fr3_link7").unwrap()];
    assert_eq!(l7.frame, 4);
    // Frozen joints 5..7 at clamp(0): j5 0, j6 0.5445, j7 0 → link7 pose equals full FK with those.
    let q4 = [0.1, -0.2, 0.3, -1.0];
    let full = fr3().frames(&[0.1, -0.2, 0.3, -1.0, 0.0, 0.5445, 0.0]);
    let mut spec_l7 = None;
    for l in &r.spec().links {
        if l.name == "fr3_link7" {
            spec_l7 = Some(l.origin.to_isometry());
        }
    }
    let pose = r.frames(&q4)[4] * spec_l7.unwrap();
    assert!(
        (pose.to_homogeneous() - full[7].to_homogeneous())
            .abs()
            .max()
            < 1e-12
    );
    // Unknown tip.
    let side = SideFile {
        tip: Some("nope".into()),
        ..Default::default()
    };
    match load_urdf(&urdf, &side) {
        Err(ModelError::UnknownName { name, field, .. }) => {
            assert_eq!((name.as_str(), field.as_str()), ("nope", "tip"))
        }
        other => panic!("{other:?}"),
    }
}

const TWO: &str = r#"<robot name="t">
  <link name="a"/><link name="b"/><link name="c"/>
  <joint name="j1" type="JT1"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>LIM1</joint>
  <joint name="j2" type="revolute"><parent link="b"/><child link="c"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#;

fn two(jt: &str, lim: &str) -> String {
    TWO.replace("JT1", jt).replace("LIM1", lim)
}

fn uniform() -> SideFile {
    SideFile {
        a_max: Some(1.0),
        j_max: Some(1.0),
        ..Default::default()
    }
}

#[test]
fn prismatic_on_chain_is_rejected() {
    let u = two(
        "prismatic",
        r#"<limit lower="0" upper="1" effort="1" velocity="1"/>"#,
    );
    match load_urdf(&u, &uniform()) {
        Err(ModelError::Invalid(m)) => {
            assert!(m.contains("`j1`") && m.contains("Prismatic"), "{m}")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn continuous_without_side_limits_is_rejected() {
    let u = two("continuous", r#"<limit effort="1" velocity="1"/>"#);
    match load_urdf(&u, &uniform()) {
        Err(ModelError::InvalidValue { field, .. }) => assert_eq!(field, "joint `j1` q_min"),
        other => panic!("{other:?}"),
    }
    let mut side = uniform();
    side.joints.insert(
        "j1".into(),
        pacs_models::urdf::JointOverride {
            q_min: Some(-4.0),
            q_max: Some(4.0),
            ..Default::default()
        },
    );
    let r = load_urdf(&u, &side).unwrap();
    assert_eq!(r.limits().q_min(), &[-4.0, -1.0]);
}

#[test]
fn missing_acc_jerk_and_velocity_are_rejected() {
    let u = two(
        "revolute",
        r#"<limit lower="-1" upper="1" effort="1" velocity="1"/>"#,
    );
    match load_urdf(&u, &SideFile::default()) {
        Err(ModelError::InvalidValue { field, value, .. }) => {
            assert_eq!(field, "joint `j1` a_max");
            assert!(value.is_infinite());
        }
        other => panic!("{other:?}"),
    }
    let u = two("revolute", "");
    match load_urdf(&u, &uniform()) {
        Err(ModelError::InvalidValue { field, .. }) => assert_eq!(field, "joint `j1` q_min"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn urdf_1_2_acceleration_and_jerk_are_used() {
    let u = two("revolute", r#"<limit lower="-1" upper="1" effort="1" velocity="1" acceleration="7" deceleration="6" jerk="90"/>"#)
        .replace(r#"<robot name="t">"#, r#"<robot name="t" version="1.2">"#)
        .replace(r#"velocity="1"/></joint>"#, r#"velocity="1" acceleration="3" jerk="30"/></joint>"#);
    let r = load_urdf(&u, &SideFile::default()).unwrap();
    assert_eq!(
        r.limits().a_max(),
        &[6.0, 3.0],
        "min of acceleration and deceleration"
    );
    assert_eq!(r.limits().j_max(), &[90.0, 30.0]);
    // The side file overrides URDF values.
    let r = load_urdf(
        &u,
        &SideFile {
            a_max: Some(2.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(r.limits().a_max(), &[2.0, 2.0]);
}

#[test]
fn validation_errors_name_the_urdf_joint() {
    let u = two(
        "revolute",
        r#"<limit lower="-1" upper="1" effort="1" velocity="1"/>"#,
    )
    .replace(
        r#"<axis xyz="0 0 1"/>LIM1"#.replace("LIM1", "").as_str(),
        r#"<axis xyz="0 0 0"/>"#,
    );
    match load_urdf(&u, &uniform()) {
        Err(ModelError::InvalidValue { field, value, .. }) => {
            assert_eq!(field, "joints[0]{j1}.axis");
            assert_eq!(value, 0.0);
        }
        other => panic!("{other:?}"),
    }
    let mut side = uniform();
    side.joints.insert(
        "j2".into(),
        pacs_models::urdf::JointOverride {
            v_max: Some(-1.0),
            ..Default::default()
        },
    );
    let u = two(
        "revolute",
        r#"<limit lower="-1" upper="1" effort="1" velocity="1"/>"#,
    );
    match load_urdf(&u, &side) {
        Err(ModelError::InvalidValue { field, value, .. }) => {
            assert_eq!(field, "joints[1]{j2}.limits.v_max");
            assert_eq!(value, -1.0);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn side_file_errors() {
    let u = two(
        "revolute",
        r#"<limit lower="-1" upper="1" effort="1" velocity="1"/>"#,
    );
    // Unknown fields are parse errors (TOML and JSON).
    assert!(matches!(
        SideFile::parse("amax = 3.0"),
        Err(ModelError::Parse { format: "TOML", .. })
    ));
    assert!(matches!(
        SideFile::parse(r#"{"links": {"a": {"capsule": []}}}"#),
        Err(ModelError::Parse { format: "JSON", .. })
    ));
    // Unknown joint / link names.
    let side = SideFile::parse("a_max = 1.0\nj_max = 1.0\n[joints.jx]\nv_max = 1.0\n").unwrap();
    match load_urdf(&u, &side) {
        Err(ModelError::UnknownName { name, field, .. }) => {
            assert_eq!((name.as_str(), field.as_str()), ("jx", "joints"))
        }
        other => panic!("{other:?}"),
    }
    let side = SideFile::parse("a_max = 1.0\nj_max = 1.0\n[links.zz]\ncapsules = []\n").unwrap();
    match load_urdf(&u, &side) {
        Err(ModelError::UnknownName { name, field, .. }) => {
            assert_eq!((name.as_str(), field.as_str()), ("zz", "links"))
        }
        other => panic!("{other:?}"),
    }
    // A negative side-file capsule radius is caught by validation with the link named.
    let side = SideFile::parse(
        "a_max = 1.0\nj_max = 1.0\n[links.c]\ncapsules = [{p1=[0,0,0], p2=[0,0,0], radius=-0.1}]\n",
    )
    .unwrap();
    match load_urdf(&u, &side) {
        Err(ModelError::InvalidValue { field, value, .. }) => {
            assert_eq!(field, "links[2]{c}.capsules[0].radius");
            assert_eq!(value, -0.1);
        }
        other => panic!("{other:?}"),
    }
    // Malformed URDF.
    assert!(matches!(
        load_urdf("<robot", &uniform()),
        Err(ModelError::Parse { format: "URDF", .. })
    ));
}

#[test]
fn tree_structure_errors() {
    let two_roots = r#"<robot name="t"><link name="a"/><link name="b"/></robot>"#;
    match load_urdf(two_roots, &uniform()) {
        Err(ModelError::Invalid(m)) => assert!(m.contains("root"), "{m}"),
        other => panic!("{other:?}"),
    }
    let u = two(
        "revolute",
        r#"<limit lower="-1" upper="1" effort="1" velocity="1"/>"#,
    )
    .replace(r#"<child link="c"/>"#, r#"<child link="d"/>"#);
    match load_urdf(&u, &uniform()) {
        Err(ModelError::UnknownName { name, field, .. }) => {
            assert_eq!(name, "d");
            assert_eq!(field, "joint `j2` child");
        }
        other => panic!("{other:?}"),
    }
    // Only fixed joints: no chain joint.
    let u = two("fixed", "").replace(r#"type="revolute""#, r#"type="fixed""#);
    assert!(
        matches!(load_urdf(&u, &uniform()), Err(ModelError::Invalid(m)) if m.contains("joint count 0"))
    );
}

#[test]
fn side_inertial_and_frozen_at_override() {
    // Off-chain revolute joint frozen at π/2 via the side file; side inertial replaces URDF's.
    let u = r#"<robot name="t">
      <link name="a"/><link name="b"/><link name="c"/><link name="d"/>
      <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="j2" type="fixed"><parent link="b"/><child link="c"/><origin xyz="1 0 0"/></joint>
      <joint name="j3" type="revolute"><parent link="b"/><child link="d"/><origin xyz="0 1 0"/><axis xyz="0 0 1"/>
        <limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
    </robot>"#;
    let side = SideFile::parse(
        r#"tip = "c"
        a_max = 1.0
        j_max = 1.0
        [joints.j3]
        frozen_at = 1.5707963267948966
        [links.d]
        capsules = [{ p1 = [1.0, 0.0, 0.0], p2 = [1.0, 0.0, 0.0], radius = 0.1 }]
        inertial = { mass = 2.0, com = [1.0, 0.0, 0.0], inertia = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0] }
        "#,
    )
    .unwrap();
    let r = load_urdf(u, &side).unwrap();
    assert_eq!(r.dof(), 1);
    // d's frame: (0,1,0) then rotated π/2: its local (1,0,0) is at (0,2,0) in joint-1 frame.
    let caps = r.capsules_world(&[0.0]);
    let d = r.link_index("d").unwrap();
    let (_, c) = caps.iter().find(|(li, _)| *li == d).unwrap();
    assert!(
        (c.p1() - Point3::new(0.0, 2.0, 0.0)).norm() < 1e-12,
        "{}",
        c.p1()
    );
    // Energy of the point mass 2 kg at radius 2 spinning at ω = 1: ½·2·4 = 4 J.
    assert!((r.kinetic_energy(&[0.0], &[1.0]) - 4.0).abs() < 1e-12);
    // frozen_at on a chain joint and limits on an off-chain joint are errors.
    let bad =
        SideFile::parse("tip = \"c\"\na_max = 1.0\nj_max = 1.0\n[joints.j1]\nfrozen_at = 0.0\n")
            .unwrap();
    assert!(
        matches!(load_urdf(u, &bad), Err(ModelError::Invalid(m)) if m.contains("joints.j1.frozen_at"))
    );
    let bad = SideFile::parse("tip = \"c\"\na_max = 1.0\nj_max = 1.0\n[joints.j3]\nv_max = 1.0\n")
        .unwrap();
    assert!(matches!(load_urdf(u, &bad), Err(ModelError::Invalid(m)) if m.contains("joints.j3")));
}

#[test]
fn side_file_json_and_toml_round_trip() {
    let side = SideFile::parse(&read("fr3_side.toml")).unwrap();
    // Nine links with capsules, the two fingers marked `frame = true`.
    assert_eq!(side.links.len(), 11);
    assert_eq!(side.links["fr3_leftfinger"].frame, Some(true));
    assert_eq!(side.a_max, Some(10.0));
    let json = serde_json::to_string(&side).unwrap();
    assert_eq!(SideFile::parse(&json).unwrap(), side);
    let toml = toml::to_string(&side).unwrap();
    assert_eq!(SideFile::parse(&toml).unwrap(), side);
}

#[test]
fn mimic_joint_on_chain_is_rejected() {
    let u = two(
        "revolute",
        r#"<limit lower="-1" upper="1" effort="1" velocity="1"/>"#,
    )
    .replace(
        r#"<origin xyz="1 0 0"/>"#,
        r#"<origin xyz="1 0 0"/><mimic joint="j1"/>"#,
    );
    match load_urdf(&u, &uniform()) {
        Err(ModelError::Invalid(m)) => assert!(m.contains("`j2`") && m.contains("mimic"), "{m}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn missing_files_are_errors_not_panics() {
    let missing = data("does-not-exist.urdf");
    assert!(
        matches!(load_urdf_files(&missing, None), Err(ModelError::Invalid(m)) if m.contains("does-not-exist"))
    );
    let r = load_urdf_files(&data("planar2.urdf"), Some(&data("nope.toml")));
    assert!(matches!(r, Err(ModelError::Invalid(m)) if m.contains("nope.toml")));
    // Without a side file the planar arm lacks a_max (and the elbow's position limits).
    assert!(matches!(
        load_urdf_files(&data("planar2.urdf"), None),
        Err(ModelError::InvalidValue { field, .. }) if field == "joint `shoulder` a_max"
    ));
}

/// A link whose collision geometry is (or includes) a mesh, without side-file capsules, would be
/// invisible to SSM and PFL: the model is refused, naming every such link.
#[test]
fn mesh_collision_without_capsules_is_refused_naming_the_links() {
    let urdf = read("planar2.urdf")
        .replace(
            "<box size=\"0.2 0.1 0.4\"/>",
            "<mesh filename=\"package://planar2/fore.stl\"/>",
        )
        .replace(
            "<cylinder radius=\"0.05\" length=\"1.0\"/>",
            "<mesh filename=\"package://planar2/upper.stl\"/>",
        );
    assert_ne!(urdf, read("planar2.urdf"), "premise: meshes put in");
    let side = SideFile::parse(&read("planar2_side.json")).unwrap();
    let err = urdf_to_spec(&urdf, &side).unwrap_err().to_string();
    assert!(err.contains("mesh collision geometry"), "{err}");
    assert!(err.contains("`upper`") && err.contains("`fore`"), "{err}");
}

/// A moving URDF link with mass and no collision geometry is refused, naming it and its mass;
/// `frame = true` in the side file accepts it only if its centre of mass lies in a capsule of
/// another link on its joint (and is refused on a link with collisions).
#[test]
fn moving_link_with_mass_and_no_collision_is_refused_unless_a_frame() {
    let mut side = SideFile::parse(&read("fr3_side.toml")).unwrap();
    side.links.remove("fr3_link4");
    let urdf = read("fr3.urdf");
    match load_urdf(&urdf, &side) {
        Err(e @ ModelError::UncoveredLinks { .. }) => {
            let m = e.to_string();
            assert!(
                m.starts_with(
                    "robot `fr3`: moving links with mass and no capsules: `fr3_link4` (2.6155955791 kg)"
                ),
                "{m}"
            );
            assert!(m.contains("frame = true"), "{m}");
        }
        other => panic!("{other:?}"),
    }
    side.links.insert(
        "fr3_link4".into(),
        pacs_models::urdf::LinkOverride {
            frame: Some(true),
            ..Default::default()
        },
    );
    // The mark states the link has no body outside other links' capsules: a 2.6 kg link whose
    // centre of mass lies outside every capsule of its joint cannot be marked away.
    let m = load_urdf(&urdf, &side).unwrap_err().to_string();
    assert!(
        m.contains("(`fr3_link4`): `frame: true`")
            && m.contains("centre of mass")
            && m.contains("2.6155955791 kg")
            && m.contains("outside every capsule"),
        "{m}"
    );
    // The fingers' marks (in the side file) hold: their centres of mass lie in the hand's capsules.
    let r = load_urdf(&urdf, &SideFile::parse(&read("fr3_side.toml")).unwrap()).unwrap();
    let f = &r.links()[r.link_index("fr3_leftfinger").unwrap()];
    assert!(
        f.capsules.is_empty()
            && r.spec()
                .links
                .iter()
                .any(|l| l.name == "fr3_leftfinger" && l.frame)
    );
    // Without the fingers' `frame` marks they are refused too (mass, no collision geometry).
    let mut side = SideFile::parse(&read("fr3_side.toml")).unwrap();
    side.links.remove("fr3_leftfinger");
    match load_urdf(&urdf, &side) {
        Err(ModelError::UncoveredLinks { links, .. }) => {
            assert_eq!(links, vec![("fr3_leftfinger".to_string(), 0.0291)])
        }
        other => panic!("{other:?}"),
    }
    // `frame = true` on a link with URDF collision geometry is refused.
    let planar = read("planar2.urdf");
    let mut side: SideFile = serde_json::from_str(&read("planar2_side.json")).unwrap();
    side.links.insert(
        "fore".into(),
        pacs_models::urdf::LinkOverride {
            frame: Some(true),
            ..Default::default()
        },
    );
    match load_urdf(&planar, &side) {
        Err(ModelError::Invalid(m)) => assert_eq!(
            m,
            "side file `links.fore.frame = true`, but the URDF gives the link 2 <collision> element(s); \
             a link with collision geometry is not a frame (give `capsules` instead)"
        ),
        other => panic!("{other:?}"),
    }
}

/// `side_file_gaps`: exactly the keys a side file still lacks, and none once it loads.
#[test]
fn side_file_gaps_name_the_missing_keys() {
    use pacs_models::urdf::side_file_gaps;
    let urdf = read("fr3.urdf");
    // No tip among three leaves: only `tip` (the chain, and so its joints, is unknown).
    let gaps = side_file_gaps(&urdf, &SideFile::default()).unwrap();
    assert_eq!(gaps.len(), 1);
    assert_eq!(gaps[0].key, "tip");
    assert!(
        gaps[0].why.starts_with(
            "the URDF has 3 leaf links (fr3_hand_tcp, fr3_leftfinger, fr3_rightfinger)"
        ),
        "{}",
        gaps[0].why
    );
    // Tip given, no acceleration or jerk limit (URDF < 1.2): both keys, naming the joints.
    let full = SideFile::parse(&read("fr3_side.toml")).unwrap();
    let mut side = full.clone();
    side.a_max = None;
    side.j_max = None;
    let gaps = side_file_gaps(&urdf, &side).unwrap();
    let keys: Vec<&str> = gaps.iter().map(|g| g.key.as_str()).collect();
    assert_eq!(keys, ["a_max", "j_max"]);
    assert!(
        gaps[0].why.starts_with(
            "no acceleration limit for joints fr3_joint1, fr3_joint2, fr3_joint3, fr3_joint4, \
             fr3_joint5, fr3_joint6, fr3_joint7: URDF before 1.2 has none"
        ),
        "{}",
        gaps[0].why
    );
    // A link left without capsules: its key.
    let mut side = full.clone();
    side.links.remove("fr3_hand");
    let gaps = side_file_gaps(&urdf, &side).unwrap();
    assert_eq!(gaps.len(), 1);
    assert_eq!(gaps[0].key, "links.fr3_hand.capsules");
    assert!(gaps[0].why.starts_with("moving link with mass (0.6544 kg)"));
    // Continuous joint: its position limits, per joint.
    let u = two("continuous", r#"<limit effort="1" velocity="1"/>"#);
    let keys: Vec<String> = side_file_gaps(&u, &uniform())
        .unwrap()
        .into_iter()
        .map(|g| g.key)
        .collect();
    assert_eq!(keys, ["joints.j1.q_min", "joints.j1.q_max"]);
    // Complete: no gaps.
    assert_eq!(side_file_gaps(&urdf, &full).unwrap(), vec![]);
}

/// A truncated URDF names the element left open and its line (the XML parser says
/// only `No elements found`); a mismatched closing tag names both lines.
#[test]
fn truncated_urdf_names_the_open_element_and_its_line() {
    let urdf = read("fr3.urdf");
    let cut: String = urdf.lines().take(40).collect::<Vec<_>>().join("\n");
    let side = SideFile::parse(&read("fr3_side.toml")).unwrap();
    let e = load_urdf(&cut, &side).unwrap_err().to_string();
    let robot_line = 1 + urdf.lines().position(|l| l.contains("<robot")).unwrap();
    assert!(e.starts_with("cannot parse URDF: "), "{e}");
    assert!(
        e.ends_with("is not closed where the text ends (line 40): is the file truncated?"),
        "{e}"
    );
    // The innermost open element is named with its line; `<robot>` is open too.
    assert!(e.contains("opened at line"), "{e}");
    assert!(robot_line < 40);
    let bad = "<robot name=\"r\">\n  <link name=\"a\">\n  </joint>\n</robot>\n";
    let e = load_urdf(bad, &side).unwrap_err().to_string();
    assert!(
        e.ends_with("line 3: `</joint>` closes `<link>` opened at line 2"),
        "{e}"
    );
}
