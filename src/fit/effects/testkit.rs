//! Test models and recordings shared by the effects' unit tests.

use crate::model::Robot;
use crate::sim2real::recording::Recording;

/// A one-hinge test model (a 0.5 kg capsule 0.2 m long, no gravity, 2 ms step) with one
/// position actuator, written to `dir/name` and loaded: `option`, `joint` and `actuator` are
/// extra attributes of `<option>`, the hinge `j` and the `<position>` element.
pub(crate) fn hinge_robot(
    dir: &std::path::Path,
    name: &str,
    option: &str,
    joint: &str,
    actuator: &str,
) -> Robot {
    let xml = format!(
        r#"<mujoco><option gravity="0 0 0" timestep="0.002" {option}/>
  <worldbody><body><joint name="j" type="hinge" axis="0 1 0" {joint}/>
<geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.5"/></body></worldbody>
  <actuator><position joint="j" {actuator}/></actuator>
</mujoco>"#
    );
    let path = dir.join(name);
    std::fs::write(&path, xml).expect("write the test model");
    let mut map = crate::model::source::SourceMap::default();
    crate::model::load(&mut map, &path, None).expect("load the test model")
}

/// [`hinge_robot`]'s joint commanded to `cmd` at the sample times `t` (positions and
/// velocities recorded as 0: only the replay is looked at).
pub(crate) fn hinge_recording(t: Vec<f64>, cmd: Vec<f64>) -> Recording {
    let n = t.len();
    let mut j = crate::sim2real::recording::JointTrace::new("j", vec![0.0; n]);
    j.q_cmd = Some(cmd);
    j.qd = Some(vec![0.0; n]);
    Recording::at_100hz(t, vec![j])
}
