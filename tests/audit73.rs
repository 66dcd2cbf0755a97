//! The class the fourteenth audit round fixed, end to end from the CLI on fixtures written from
//! the class: a URDF with elements whose namespace prefix no `xmlns` declares (unexpanded xacro
//! macros) is linted as MuJoCo reads it, not refused. Line and column are counted here from the
//! fixtures' text.

mod common;

use std::process::Command;

use common::lint::{findings, message, of};

const DIR: &str = "fixtures/rules/undeclared-xml-prefix/";

/// 1-based line and column of the first `needle` in `file`.
fn line_col(file: &str, needle: &str) -> (u64, u64) {
    let text = std::fs::read_to_string(file).unwrap();
    let at = text.find(needle).unwrap_or_else(|| panic!("{needle} not in {file}"));
    let line = text[..at].matches('\n').count() + 1;
    let col = at - text[..at].rfind('\n').map_or(0, |i| i + 1) + 1;
    (line as u64, col as u64)
}

/// Both macro elements are named, the finding sits on the first one's name, and the model's
/// own rules still run (the URDF has a joint and no actuator: `missing-actuators`).
#[test]
fn unexpanded_xacro_is_a_finding_and_the_rest_is_linted() {
    let file = format!("{DIR}invalid_urdf_unexpanded_xacro.urdf");
    let all = findings(&file);
    let m = of(&all, "undeclared-xml-prefix");
    assert_eq!(m.len(), 1, "{all:#?}");
    let msg = message(m[0]);
    assert!(msg.contains("2 elements use the prefix `xacro:`"), "{msg}");
    assert!(msg.contains("`<xacro:include>`, `<xacro:camera_unit>`"), "{msg}");
    // Column of the name, after the '<' of `  <xacro:include`.
    let (line, col) = line_col(&file, "<xacro:include");
    assert_eq!((m[0]["line"].as_u64(), m[0]["column"].as_u64()), (Some(line), Some(col + 1)));
    assert_eq!(of(&all, "missing-actuators").len(), 1, "{all:#?}");
}

/// A prefix other than xacro, on an element inside a link and on a joint's attribute: one
/// finding for the element; the joint still has its range (read through the renamed attribute).
#[test]
fn any_undeclared_prefix_is_read_as_mujoco_reads_it() {
    let file = format!("{DIR}invalid_urdf_undeclared_simulator_prefix.urdf");
    let all = findings(&file);
    let m = of(&all, "undeclared-xml-prefix");
    assert_eq!(m.len(), 1, "{all:#?}");
    assert!(message(m[0]).starts_with("1 element uses the prefix `sim:`"), "{}", message(m[0]));
    let (line, _) = line_col(&file, "<sim:plugin");
    assert_eq!(m[0]["line"].as_u64(), Some(line));
    for valid in [
        "valid_urdf_xacro_output_declared_namespace.urdf",
        "valid_urdf_declared_prefix_element.urdf",
    ] {
        let all = findings(&format!("{DIR}{valid}"));
        assert!(of(&all, "undeclared-xml-prefix").is_empty(), "{valid}: {all:#?}");
    }
}

/// `package://` meshes of such a URDF are resolved too (the resolved copy given to MuJoCo is
/// read the same way): before, the copy was skipped and MuJoCo was handed the unresolved path.
#[test]
fn package_meshes_of_a_urdf_with_undeclared_prefixes_resolve() {
    let dir = std::env::temp_dir().join(format!("modellint-audit73-{}", std::process::id()));
    let pkg = dir.join("legpkg");
    std::fs::create_dir_all(pkg.join("meshes")).unwrap();
    std::fs::copy(
        "fixtures/rules/visual-mesh-collision/meshes/foot_box.stl",
        pkg.join("meshes/foot.stl"),
    )
    .unwrap();
    let urdf = dir.join("leg.urdf");
    let text = std::fs::read_to_string(format!("{DIR}invalid_urdf_unexpanded_xacro.urdf"))
        .unwrap()
        .replace(
            "<geometry><cylinder radius=\"0.02\" length=\"0.2\"/></geometry>",
            "<geometry><mesh filename=\"package://legpkg/meshes/foot.stl\"/></geometry>",
        );
    assert!(text.contains("package://legpkg"));
    std::fs::write(&urdf, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_modellint"))
        .arg(&urdf)
        .args(["--package", &format!("legpkg={}", pkg.display())])
        .args(["--no-probe", "--format", "json", "--no-cache"])
        .output()
        .unwrap();
    let code = out.status.code();
    assert!(
        code == Some(0) || code == Some(1),
        "{code:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let all = v["findings"].as_array().cloned().unwrap_or_default();
    assert_eq!(of(&all, "undeclared-xml-prefix").len(), 1, "{all:#?}");
    std::fs::remove_dir_all(&dir).ok();
}
