//! URDF `package://` meshes: resolved with `--package NAME=DIR` or ROS_PACKAGE_PATH; an unknown
//! package or a missing mesh is exit 2 with file:line at the `filename` attribute. Hand-built
//! URDF and mesh in a temp directory; the expected lines are where this file writes them.

use std::path::PathBuf;
use std::process::Command;

const URDF: &str = r#"<?xml version="1.0"?>
<robot name="bot">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="arm">
    <inertial><mass value="0.5"/><inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://mybot/meshes/tet.obj"/></geometry></visual>
    <collision><geometry><mesh filename="package://mybot/meshes/MESH"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="arm"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="5"/>
  </joint>
</robot>
"#;

fn setup(tag: &str, mesh: &str) -> (PathBuf, PathBuf) {
    let d = std::env::temp_dir().join(format!("modellint_urdfpkg_{}_{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.join("ws/mybot/meshes")).unwrap();
    std::fs::write(
        d.join("ws/mybot/meshes/tet.obj"),
        "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let urdf = d.join("bot.urdf");
    std::fs::write(&urdf, URDF.replace("MESH", mesh)).unwrap();
    (d, urdf)
}

fn lint(urdf: &PathBuf, args: &[&str], rpp: Option<&str>) -> (Option<i32>, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_modellint"));
    c.arg(urdf).args(["--no-probe", "--color", "never"]).args(args).env_remove("ROS_PACKAGE_PATH");
    if let Some(p) = rpp {
        c.env("ROS_PACKAGE_PATH", p);
    }
    let o = c.output().unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr),
    )
}

#[test]
fn package_paths_resolve_from_the_flag_or_ros_package_path() {
    let (d, urdf) = setup("resolve", "tet.obj");
    let pkg = format!("mybot={}", d.join("ws/mybot").display());
    let (c, out) = lint(&urdf, &["--package", &pkg], None);
    assert_eq!(c, Some(0), "{out}");
    let ws = d.join("ws").display().to_string();
    let (c, out) = lint(&urdf, &[], Some(&format!("/nonexistent:{ws}")));
    assert_eq!(c, Some(0), "{out}");
    // Without either: exit 2 at the first filename attribute (line 8, column 39).
    let (c, out) = lint(&urdf, &[], None);
    assert_eq!(c, Some(2), "{out}");
    assert!(
        out.contains("bot.urdf:8:39")
            && out.contains("package `mybot` not found")
            && out.contains("--package mybot=DIR"),
        "{out}"
    );
    let (c, out) = lint(&urdf, &["--package", "broken"], None);
    assert_eq!(c, Some(2), "{out}");
    assert!(out.contains("NAME=DIR"), "{out}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn missing_package_mesh_is_an_error_at_its_line() {
    let (d, urdf) = setup("missing", "gone.obj");
    let pkg = format!("mybot={}", d.join("ws/mybot").display());
    let (c, out) = lint(&urdf, &["--package", &pkg], None);
    assert_eq!(c, Some(2), "{out}");
    assert!(
        out.contains("bot.urdf:9:42")
            && out.contains("mesh file not found")
            && out.contains("gone.obj"),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn urdf_compile_errors_carry_file_and_line() {
    let (d, urdf) = setup("compile", "tet.obj");
    std::fs::write(
        &urdf,
        URDF.replace("MESH", "tet.obj")
            .replace("<parent link=\"base\"/>", "<parent link=\"nolink\"/>"),
    )
    .unwrap();
    let pkg = format!("mybot={}", d.join("ws/mybot").display());
    let (c, out) = lint(&urdf, &["--package", &pkg], None);
    assert_eq!(c, Some(2), "{out}");
    assert!(out.contains("bot.urdf:11:"), "{out}");
    let _ = std::fs::remove_dir_all(&d);
}
