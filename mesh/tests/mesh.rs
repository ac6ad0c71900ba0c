//! Mesh reading (files the test writes) and capsule fitting: every vertex and every sampled point
//! of every face inside the capsule; exact values on hand-made meshes; URDF mesh collisions
//! resolved and fitted into a side file the model loader accepts.

use nalgebra::{Point3, Vector3};
use pacs_mesh::fit::segment_distance;
use pacs_mesh::read::{read_mesh, resolve};
use pacs_mesh::urdf::fit_urdf_meshes;
use pacs_mesh::{FittedCapsule, MeshError, fit_capsule};
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pacs-mesh-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A closed cylinder (radius r, axis z from 0 to len) as triangles.
fn cylinder(r: f64, len: f64, n: usize) -> Vec<[Point3<f64>; 3]> {
    let p = |k: usize, z: f64| {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        Point3::new(r * a.cos(), r * a.sin(), z)
    };
    let mut t = Vec::new();
    for k in 0..n {
        let (a0, a1, b0, b1) = (p(k, 0.0), p(k + 1, 0.0), p(k, len), p(k + 1, len));
        t.push([a0, a1, b1]);
        t.push([a0, b1, b0]);
        t.push([Point3::new(0.0, 0.0, 0.0), a1, a0]);
        t.push([Point3::new(0.0, 0.0, len), b0, b1]);
    }
    t
}

fn write_stl_binary(path: &Path, tris: &[[Point3<f64>; 3]]) {
    let mut b = vec![0u8; 80];
    b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend_from_slice(&[0u8; 12]);
        for v in t {
            for c in v.iter() {
                b.extend_from_slice(&(*c as f32).to_le_bytes());
            }
        }
        b.extend_from_slice(&[0u8; 2]);
    }
    std::fs::write(path, b).unwrap();
}

fn write_stl_ascii(path: &Path, tris: &[[Point3<f64>; 3]]) {
    let mut s = String::from("solid test\n");
    for t in tris {
        s += "facet normal 0 0 0\n outer loop\n";
        for v in t {
            s += &format!("  vertex {} {} {}\n", v.x, v.y, v.z);
        }
        s += " endloop\nendfacet\n";
    }
    s += "endsolid test\n";
    std::fs::write(path, s).unwrap();
}

fn write_obj(path: &Path, tris: &[[Point3<f64>; 3]]) {
    let mut s = String::from("# test\no cyl\n");
    for t in tris {
        for v in t {
            s += &format!("v {} {} {}\n", v.x, v.y, v.z);
        }
    }
    for k in 0..tris.len() {
        s += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    }
    std::fs::write(path, s).unwrap();
}

/// Every vertex, and points sampled on every face, within the radius of the segment.
fn assert_contains(c: &FittedCapsule, tris: &[[Point3<f64>; 3]]) {
    for t in tris {
        for (u, v) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.3, 0.3),
            (0.5, 0.5),
            (0.1, 0.8),
        ] {
            let p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
            let d = segment_distance(&p, &c.p1, &c.p2);
            assert!(d <= c.radius, "point {p:?} at {d} m, radius {} m", c.radius);
        }
    }
}

#[test]
fn a_cylinder_mesh_gets_its_own_capsule_from_every_format() {
    let (r, len) = (0.06, 0.3);
    let tris = cylinder(r, len, 64);
    let dir = tmp("formats");
    let files = [
        dir.join("cyl.stl"),
        dir.join("cyl_ascii.STL"),
        dir.join("cyl.obj"),
    ];
    write_stl_binary(&files[0], &tris);
    write_stl_ascii(&files[1], &tris);
    write_obj(&files[2], &tris);
    for f in &files {
        let v = read_mesh(f).unwrap();
        assert_eq!(v.len(), 3 * tris.len(), "{}", f.display());
        let c = fit_capsule(&v, "cyl").unwrap();
        assert_contains(&c, &tris);
        // Along the cylinder's axis, radius a little above the cylinder's (a slightly larger
        // radius lets the caps cover the end discs with a shorter segment: less volume).
        let axis = (c.p2 - c.p1).normalize();
        assert!(axis.z.abs() > 1.0 - 1e-6, "axis {axis:?}");
        assert!(
            c.radius >= r * (1.0 - 1e-6) && c.radius < 1.05 * r,
            "radius {}",
            c.radius
        );
        // At least as tight as the cylinder's own capsule (radius r, segment = the axis):
        // cylinder volume / capsule volume = π r² L / (π r² L + 4/3 π r³) (hull = the 64-gon prism).
        let own = (r * r * len) / (r * r * len + 4.0 / 3.0 * r * r * r);
        let polygon = 64.0 / std::f64::consts::TAU * (std::f64::consts::TAU / 64.0).sin();
        assert!(
            c.tightness() >= own * polygon - 1e-6,
            "tightness {} < {}",
            c.tightness(),
            own * polygon
        );
        assert!(c.tightness() <= 1.0);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// COLLADA: a triangle list in millimetres under a node translated, rotated and scaled; the
/// vertices come out in metres where the node puts them (hand-computed).
#[test]
fn collada_positions_follow_units_and_node_transforms() {
    let dir = tmp("dae");
    let dae = |up: &str, transforms: &str| {
        format!(
            r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="millimeter" meter="0.001"/>{up}</asset>
  <library_geometries>
    <geometry id="g" name="g"><mesh>
      <source id="g-pos"><float_array id="g-pos-array" count="9">1000 0 0  0 2000 0  0 0 3000</float_array>
        <technique_common><accessor source="#g-pos-array" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <source id="g-nrm"><float_array id="g-nrm-array" count="3">0 0 1</float_array>
        <technique_common><accessor source="#g-nrm-array" count="1" stride="3"/></technique_common></source>
      <vertices id="g-vtx"><input semantic="POSITION" source="#g-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#g-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes><visual_scene id="s">
    <node id="outer">{transforms}
      <node id="inner"><instance_geometry url="#g"/></node>
    </node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##
        )
    };
    let f = dir.join("tri.dae");
    // translate (mm units are applied last: the scene is in file units), then rotate 90° about z.
    std::fs::write(
        &f,
        dae(
            "<up_axis>Z_UP</up_axis>",
            "<translate>100 0 0</translate><rotate>0 0 1 90</rotate>",
        ),
    )
    .unwrap();
    let v = read_mesh(&f).unwrap();
    let expect = [[0.1, 1.0, 0.0], [0.1 - 2.0, 0.0, 0.0], [0.1, 0.0, 3.0]];
    assert_eq!(v.len(), 3);
    for (p, e) in v.iter().zip(expect) {
        assert!((p - Point3::from(e)).norm() < 1e-12, "{p:?} vs {e:?}");
    }
    // The same with a row-major <matrix> (translation in the last column).
    std::fs::write(
        &f,
        dae(
            "<up_axis>Z_UP</up_axis>",
            "<matrix>0 -1 0 100  1 0 0 0  0 0 1 0  0 0 0 1</matrix>",
        ),
    )
    .unwrap();
    let w = read_mesh(&f).unwrap();
    for (p, e) in w.iter().zip(expect) {
        assert!((p - Point3::from(e)).norm() < 1e-12, "{p:?} vs {e:?}");
    }
    // Y_UP and a missing up_axis are refused, not guessed.
    for up in ["<up_axis>Y_UP</up_axis>", ""] {
        std::fs::write(&f, dae(up, "")).unwrap();
        let e = read_mesh(&f).unwrap_err();
        assert!(matches!(e, MeshError::Unsupported { .. }), "{e}");
        assert!(e.to_string().contains("up_axis"), "{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_mesh_files_name_the_file_and_the_problem() {
    let dir = tmp("bad");
    let f = dir.join("broken.obj");
    std::fs::write(&f, "v 1 2\n").unwrap();
    let e = read_mesh(&f).unwrap_err().to_string();
    assert!(
        e.contains("broken.obj") && e.contains("line 1") && e.contains("has 2"),
        "{e}"
    );
    std::fs::write(&f, "v 1 2 x\n").unwrap();
    let e = read_mesh(&f).unwrap_err().to_string();
    assert!(e.contains("`x` is not a number"), "{e}");
    // Vertex colours (MeshLab's `v x y z r g b`) are not a weight; a weight divides.
    std::fs::write(&f, "v 1 2 3 0.5 0.2 0.1\nv 2 4 6 2\n").unwrap();
    let v = read_mesh(&f).unwrap();
    assert_eq!(v[0], Point3::new(1.0, 2.0, 3.0));
    assert_eq!(v[1], Point3::new(1.0, 2.0, 3.0));
    std::fs::write(&f, "v 1 2 3 4 5\n").unwrap();
    let e = read_mesh(&f).unwrap_err().to_string();
    assert!(
        e.contains("line 1") && e.contains("2 numbers after x y z"),
        "{e}"
    );
    std::fs::write(&f, "# nothing\n").unwrap();
    assert!(matches!(read_mesh(&f), Err(MeshError::Empty { .. })));
    let g = dir.join("short.stl");
    std::fs::write(&g, [0u8; 90]).unwrap();
    let e = read_mesh(&g).unwrap_err().to_string();
    assert!(e.contains("short.stl") && e.contains("STL"), "{e}");
    let h = dir.join("mesh.ply");
    std::fs::write(&h, "ply\n").unwrap();
    let e = read_mesh(&h).unwrap_err().to_string();
    assert!(e.contains(".ply") && e.contains("unsupported"), "{e}");
    let e = read_mesh(&dir.join("missing.stl")).unwrap_err().to_string();
    assert!(
        e.contains("missing.stl") && e.contains("cannot read"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Random point clouds (stretched, rotated, offset; a few to hundreds of points): every
    /// point inside, tightness in [0, 1], the radius no larger than the enclosing ball's.
    #[test]
    fn every_vertex_is_inside_the_fitted_capsule(
        pts in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0), 1..300),
        stretch in (0.01f64..3.0, 0.01f64..3.0, 0.01f64..3.0),
        rot in (-3.2f64..3.2, -3.2f64..3.2, -3.2f64..3.2),
        offset in (-5.0f64..5.0, -5.0f64..5.0, -5.0f64..5.0),
    ) {
        let r = nalgebra::Rotation3::from_euler_angles(rot.0, rot.1, rot.2);
        let o = Vector3::new(offset.0, offset.1, offset.2);
        let cloud: Vec<Point3<f64>> = pts
            .iter()
            .map(|&(x, y, z)| Point3::from(r * Vector3::new(x * stretch.0, y * stretch.1, z * stretch.2) + o))
            .collect();
        let c = fit_capsule(&cloud, "cloud").unwrap();
        for p in &cloud {
            prop_assert!(segment_distance(p, &c.p1, &c.p2) <= c.radius);
        }
        prop_assert!((0.0..=1.0).contains(&c.tightness()));
        let mean = cloud.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / cloud.len() as f64;
        let ball = cloud.iter().map(|p| (p.coords - mean).norm()).fold(0.0f64, f64::max);
        prop_assert!(c.radius <= ball * (1.0 + 1e-9) + 2e-9, "radius {} > ball {}", c.radius, ball);
    }
}

/// A URDF with a `package://` STL (scaled, placed by its collision origin), a relative OBJ and a
/// box on one link: the side file gets capsules for all three; the model loads with it (without
/// it, the mesh link is refused); the mesh vertices, in the link frame, are inside.
#[test]
fn urdf_mesh_collisions_become_reviewed_side_file_capsules() {
    let dir = tmp("urdf");
    let pkg = dir.join("share").join("toy_description");
    std::fs::create_dir_all(pkg.join("meshes")).unwrap();
    std::fs::create_dir_all(dir.join("urdf").join("meshes")).unwrap();
    let tris = cylinder(0.05, 0.2, 24);
    write_stl_binary(&pkg.join("meshes").join("link1.stl"), &tris);
    write_obj(&dir.join("urdf").join("meshes").join("link2.obj"), &tris);
    let urdf = r#"<?xml version="1.0"?>
<robot name="toy">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="link1"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><origin xyz="0 0 0.1" rpy="0 1.5707963267948966 0"/>
      <geometry><mesh filename="package://toy_description/meshes/link1.stl" scale="0.5 0.5 2"/></geometry></collision>
    <collision><geometry><box size="0.04 0.04 0.3"/></geometry></collision></link>
  <link name="link2"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><mesh filename="meshes/link2.obj"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/><axis xyz="0 0 1"/>
    <limit lower="-2" upper="2" velocity="2" effort="10"/></joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/><origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="2" effort="10"/></joint>
</robot>"#;
    let urdf_path = dir.join("urdf").join("toy.urdf");
    std::fs::write(&urdf_path, urdf).unwrap();
    let side = pacs_models::urdf::SideFile {
        a_max: Some(10.0),
        j_max: Some(5000.0),
        ..Default::default()
    };
    // Without the package path the package mesh cannot be found.
    let e = fit_urdf_meshes(&urdf_path, &side, &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("link `link1` collision[0]") && e.contains("toy_description"),
        "{e}"
    );
    let (fitted, fits) = fit_urdf_meshes(&urdf_path, &side, &[dir.join("share")]).unwrap();
    assert_eq!(fits.len(), 2);
    let caps1 = fitted.links["link1"].capsules.as_ref().unwrap();
    assert_eq!(caps1.len(), 2, "the box and the mesh");
    assert_eq!(fitted.links["link2"].capsules.as_ref().unwrap().len(), 1);
    assert!(
        !fitted.links.contains_key("base"),
        "a link without meshes keeps its URDF geometry"
    );
    // The scaled, rotated mesh vertices in the link frame are inside the mesh's capsule.
    let iso = pacs_models::robot::PoseSpec {
        xyz: [0.0, 0.0, 0.1],
        rpy: [0.0, std::f64::consts::FRAC_PI_2, 0.0],
    }
    .to_isometry();
    let c = &caps1[1];
    let (p1, p2) = (Point3::from(c.p1), Point3::from(c.p2));
    for t in &tris {
        for v in t {
            let p = iso * Point3::new(v.x * 0.5, v.y * 0.5, v.z * 2.0);
            assert!(segment_distance(&p, &p1, &p2) <= c.radius);
        }
    }
    // The mesh axis (z, scaled ×2 to 0.4 m) is turned onto x by the origin's pitch.
    let axis = p2 - p1;
    assert!(axis.norm() > 0.3 && axis.norm() <= 0.4 + 1e-9, "{axis:?}");
    assert!(axis.x.abs() > 0.999 * axis.norm(), "{axis:?}");
    let text = std::fs::read_to_string(&urdf_path).unwrap();
    assert!(matches!(
        pacs_models::urdf::load_urdf(&text, &side),
        Err(pacs_models::ModelError::MeshCollision { .. })
    ));
    pacs_models::urdf::load_urdf(&text, &fitted).expect("loads with the fitted side file");
    // Paths: relative to the URDF's directory, package:// under a path that is the package.
    let r = resolve("meshes/link2.obj", &dir.join("urdf"), &[]).unwrap();
    assert!(r.ends_with("urdf/meshes/link2.obj"));
    let r = resolve(
        "package://toy_description/meshes/link1.stl",
        Path::new("/"),
        std::slice::from_ref(&pkg),
    )
    .unwrap();
    assert!(r.ends_with("toy_description/meshes/link1.stl"));
    // A missing file in a package that is there is named as such, not as a missing
    // package; a package nowhere on the paths is a missing package.
    let e = resolve(
        "package://toy_description/meshes/link9.stl",
        Path::new("/"),
        std::slice::from_ref(&pkg),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        format!(
            "mesh `package://toy_description/meshes/link9.stl`: package `toy_description` is at {}, but it has no file `meshes/link9.stl` (no {})",
            pkg.display(),
            pkg.join("meshes/link9.stl").display()
        )
    );
    let e = resolve(
        "package://other_description/meshes/link1.stl",
        Path::new("/"),
        std::slice::from_ref(&pkg),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("mesh `package://other_description/meshes/link1.stl`: package `other_description` not found under the package paths"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
