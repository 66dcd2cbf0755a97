# Case definitions for realsim.py. Effect values are the REAL robot's absolute values
# (damping, armature, frictionloss, stiffness) or scales / seconds / radians.
STD = dict(rec_hz=88.0, jitter=0.15, drop=0.005, q_noise=0.0005, qd_noise=0.01, bits=12)
MODELS = {
    "leg3": dict(xml="leg3.xml", joints=["hip_pitch", "knee", "ankle"], robot="leg3_stand",
                 amp=[0.35, 0.35, 0.3], t0_ctrl=0.0037, **STD),
    "arm4": dict(xml="arm4.xml", joints=["yaw", "shoulder", "elbow", "wrist_roll"], robot="arm4_pedestal",
                 amp=[0.4, 0.3, 0.35, 0.6], t0_ctrl=0.0061, **STD),
}
# ---- quad12: 12-joint quadruped lifted on a stand (torso welded, feet in the air) ----
# 200 Hz controller (ctrl_hz; the others use realsim's default 100 Hz) and a recorder at ~176 Hz
# ±15 % (the arm2 ratio 88/100 kept), otherwise the STD noise/quantisation/drops.
QUAD = [f"{l}_{j}" for l in ("FL", "FR", "RL", "RR") for j in ("hip_abd", "hip_pitch", "knee")]
MODELS["quad12"] = dict(xml="quad12.xml", joints=QUAD, robot="quad12_stand", ctrl_hz=200.0,
                        amp=[0.25, 0.35, 0.4] * 4, t0_ctrl=0.0023, **dict(STD, rec_hz=176.0))
QUAD_EP = dict(model="quad12", episodes=4, seconds=6.0, heldout=[3])
ALL3 = ["hip_pitch", "knee", "ankle"]
ALL4 = ["yaw", "shoulder", "elbow", "wrist_roll"]
CASES = {
    # ---- leg3 ----
    "L0_none": dict(model="leg3", seed=11, effects={}),
    "L1_knee_damping": dict(model="leg3", seed=12, effects={"joints": {"knee": {"damping": 0.8}}}),
    "L2_all_armature": dict(model="leg3", seed=13, effects={"joints": {j: {"armature": 0.06} for j in ALL3}}),
    "L3_gain07_delay15": dict(model="leg3", seed=14,
        effects={"delay": 0.015, "joints": {j: {"kp_scale": 0.7} for j in ALL3}}),
    "L4_knee_stiffness_14bit": dict(model="leg3", seed=15, logging=dict(bits=14),
        effects={"joints": {"knee": {"stiffness": 6.0}}}),
    # ---- arm4 ----
    "A0_none_noquant": dict(model="arm4", seed=21, logging=dict(bits=None, q_noise=0.0003), effects={}),
    "A1_shoulder_offset": dict(model="arm4", seed=22, effects={"joints": {"shoulder": {"offset": 0.04}}}),
    "A2_all_delay20": dict(model="arm4", seed=23, effects={"delay": 0.020}),
    "A3_all_friction": dict(model="arm4", seed=24,
        effects={"joints": {"yaw": {"frictionloss": 0.3}, "shoulder": {"frictionloss": 0.3},
                            "elbow": {"frictionloss": 0.3}, "wrist_roll": {"frictionloss": 0.03}}}),
    "A4_elbow_gain_plus_damping": dict(model="arm4", seed=25,
        effects={"joints": {"elbow": {"kp_scale": 1.4, "kd_scale": 1.0}, "yaw": {"damping": 0.5}}}),
}
# ---- extra, harder cases ----
CASES["L5_three_effects"] = dict(model="leg3", seed=16, effects={"joints": {
    "knee": {"frictionloss": 0.5}, "ankle": {"offset": -0.03}, "hip_pitch": {"damping": 1.2}}})
CASES["A5_wrist_armature_nosplit"] = dict(model="arm4", seed=26, episodes=4, seconds=4.0, heldout=[],
    effects={"joints": {"wrist_roll": {"armature": 0.008}}})
CASES["A6_shoulder_kd_only"] = dict(model="arm4", seed=27, effects={"joints": {"shoulder": {"kd_scale": 2.0}}})
CASES["L6_ankle_delay25"] = dict(model="leg3", seed=17, effects={"joints": {"ankle": {"delay": 0.025}}})
CASES["L7_none_10bit_noisy"] = dict(model="leg3", seed=18, logging=dict(bits=10, q_noise=0.001, qd_noise=0.03, drop=0.02), effects={})
# ---- quad12 ----
CASES["Q0_none"] = dict(QUAD_EP, seed=41, effects={})
CASES["Q1_all_damping"] = dict(QUAD_EP, seed=42, effects={"joints": {j: {"damping": 0.3} for j in QUAD}})
CASES["Q2_knees_armature"] = dict(QUAD_EP, seed=43,
    effects={"joints": {j: {"armature": 0.02} for j in QUAD if j.endswith("_knee")}})
CASES["Q3_all_delay10"] = dict(QUAD_EP, seed=44, effects={"delay": 0.010})
CASES["Q4_FL_hip_offset"] = dict(QUAD_EP, seed=45, effects={"joints": {"FL_hip_pitch": {"offset": 0.03}}})
# ---- legs12h: humanoid legs (12 joints, kp 40–250, ±50–200 N·m) on a stand ----
# 50 Hz policy-rate controller (a common humanoid deployment) logged at ~200 Hz ±15 %; the fit's
# bounds must reach humanoid-sized damping and friction (beyond the 5 N·m(·s/rad) of a small
# arm) and report a left/right pair as one group.
H12 = [f"{s}_{j}" for s in ("left", "right")
       for j in ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll")]
MODELS["legs12h"] = dict(xml="legs12h.xml", joints=H12, robot="legs12h_stand", ctrl_hz=50.0,
                         amp=[0.25, 0.2, 0.4, 0.6, 0.3, 0.2] * 2, t0_ctrl=0.0071,
                         **dict(STD, rec_hz=200.0))
H12_EP = dict(model="legs12h", episodes=4, seconds=6.0, heldout=[3])
CASES["H0_none"] = dict(H12_EP, seed=51, effects={})
CASES["H1_knees_damping8"] = dict(H12_EP, seed=52,
    effects={"joints": {j: {"damping": 8.0} for j in H12 if j.endswith("_knee")}})
CASES["H2_hip_pitch_friction4"] = dict(H12_EP, seed=53,
    effects={"joints": {j: {"frictionloss": 4.0} for j in H12 if j.endswith("_hip_pitch")}})
CASES["H3_all_delay15"] = dict(H12_EP, seed=54, effects={"delay": 0.015})
CASES["H4_left_knee_kp08"] = dict(H12_EP, seed=55, effects={"joints": {"left_knee": {"kp_scale": 0.8}}})
CASES["H5_knees_armature02"] = dict(H12_EP, seed=56,
    effects={"joints": {j: {"armature": 0.2} for j in H12 if j.endswith("_knee")}})
CASES["H6_knees_friction10"] = dict(H12_EP, seed=57,
    effects={"joints": {j: {"frictionloss": 10.0} for j in H12 if j.endswith("_knee")}})
# ---- recordings that start mid-motion (rec_start: the log begins 1 s into the motion, its
# first row off the control ticks and the physics steps, as a real logger's would be) ----
CASES["L8_knee_damping_midmotion"] = dict(model="leg3", seed=12, logging=dict(rec_start=1.0),
    effects={"joints": {"knee": {"damping": 0.8}}})
CASES["H7_none_midmotion"] = dict(H12_EP, seed=51, logging=dict(rec_start=1.0), effects={})
CASES["H8_knees_damping8_midmotion"] = dict(H12_EP, seed=52, logging=dict(rec_start=1.0),
    effects={"joints": {j: {"damping": 8.0} for j in H12 if j.endswith("_knee")}})
# ---- logs that do not declare control_t0_s (most real ones), starting mid-motion: the
# ticks' phase must come from the rows (ticks at 0.0071 + k/50, first row ~1 s in) ----
CASES["H9_none_no_t0"] = dict(H12_EP, seed=51, logging=dict(rec_start=1.0, declare_t0=False),
    effects={})
CASES["H10_knees_damping8_no_t0"] = dict(H12_EP, seed=52,
    logging=dict(rec_start=1.0, declare_t0=False),
    effects={"joints": {j: {"damping": 8.0} for j in H12 if j.endswith("_knee")}})
# The same with the arm2-style recorder (88 Hz, slower than the 100 Hz controller): most ticks
# hold one row or none, so the command changes alone leave several phases open.
CASES["L9_knee_damping_no_t0"] = dict(model="leg3", seed=12,
    logging=dict(rec_start=1.0, declare_t0=False), effects={"joints": {"knee": {"damping": 0.8}}})
# ---- a controller 300 ppm off its nominal rate on the recorder's clock (49.985 Hz, the header
# says 50; no control_t0_s, from 1 s into the motion): rows near the tick edges land in the
# wrong tick unless the rate is fitted from the rows ----
CASES["H11_none_rate_off"] = dict(H12_EP, seed=51,
    logging=dict(rec_start=1.0, declare_t0=False, ctrl_hz=49.985, declared_hz=50.0), effects={})
CASES["H12_knees_damping8_rate_off"] = dict(H12_EP, seed=52,
    logging=dict(rec_start=1.0, declare_t0=False, ctrl_hz=49.985, declared_hz=50.0),
    effects={"joints": {j: {"damping": 8.0} for j in H12 if j.endswith("_knee")}})
# ---- the robot moves in (nearly) continuous time: it integrates at an eighth of the model's
# timestep, as hardware does against a model stepped at 2 ms (humanoid) or 1 ms; the model's own
# discretisation is then part of the gap, and must not come out as physics ----
CASES["H13_none_fine"] = dict(H12_EP, seed=51, logging=dict(physics_div=8), effects={})
CASES["H14_knees_damping8_fine"] = dict(H12_EP, seed=52, logging=dict(physics_div=8),
    effects={"joints": {j: {"damping": 8.0} for j in H12 if j.endswith("_knee")}})
CASES["L10_none_fine"] = dict(model="leg3", seed=11, logging=dict(physics_div=8), effects={})
CASES["L11_knee_damping_fine"] = dict(model="leg3", seed=12, logging=dict(physics_div=8),
    effects={"joints": {"knee": {"damping": 0.8}}})
CASES["Q5_none_fine"] = dict(QUAD_EP, seed=41, logging=dict(physics_div=8), effects={})
# The controller off its rate (as H11/H12) on a robot in near-continuous time: H11's
# simulator splits its 2 ms steps at ticks that drift across them, a discretisation no
# fixed-step replay has; hardware has none.
CASES["H15_none_rate_off_fine"] = dict(H12_EP, seed=51, effects={},
    logging=dict(rec_start=1.0, declare_t0=False, ctrl_hz=49.985, declared_hz=50.0, physics_div=8))
CASES["H16_knees_damping8_rate_off_fine"] = dict(H12_EP, seed=52,
    logging=dict(rec_start=1.0, declare_t0=False, ctrl_hz=49.985, declared_hz=50.0, physics_div=8),
    effects={"joints": {j: {"damping": 8.0} for j in H12 if j.endswith("_knee")}})
# ---- body effects (issue 48): the link's mass properties differ from the model's. Built with
# MjSpec before compiling (realsim.real_model): a payload is a child body holding a sphere of its
# mass, a centre-of-mass shift moves every geom of the body. ----
CASES["L12_shank_payload"] = dict(model="leg3", seed=19,
    effects={"bodies": {"shank": {"payload": {"mass": 0.6, "pos": [0.0, 0.0, -0.25]}}}})
CASES["L13_shank_com_shift"] = dict(model="leg3", seed=20,
    effects={"bodies": {"shank": {"com_shift": [0.03, 0.0, -0.04]}}})
CASES["L14_thigh_payload"] = dict(model="leg3", seed=30,
    effects={"bodies": {"thigh": {"payload": {"mass": 1.0, "pos": [0.0, 0.0, -0.12]}}}})
# Reduced versions for `make test` (tests/independent_body.rs; recordings committed in
# fixtures/independent_py/): 4 episodes × 4 s, the last held out.
CASES["R1_shank_payload"] = dict(model="leg3", seed=61, episodes=4, seconds=4.0, heldout=[3],
    effects={"bodies": {"shank": {"payload": {"mass": 0.6, "pos": [0.0, 0.0, -0.25]}}}})
CASES["R0_none"] = dict(model="leg3", seed=60, episodes=4, seconds=4.0, heldout=[3], effects={})
# The shank's inertia about its principal x and y axes (y: the knee's axis) doubled, mass and
# centre of mass kept; the fit is given a short list of effects (fit_args). K11/KR11 (chainsim)
# are the blind inertia cases.
CASES["L15_shank_inertia"] = dict(model="leg3", seed=31,
    effects={"bodies": {"shank": {"inertia_scale": [2.0, 2.0, 1.0]}}},
    fit_args=["--effects", "link_inertia,armature,link_mass,com_offset,viscous_damping,gain_error"])
# Humanoid legs: the same 1.5 kg payload on both shanks (a mirror pair of bodies; kp 250 knees).
CASES["H17_shanks_payload"] = dict(H12_EP, seed=58, effects={"bodies": {
    s + "_shank": {"payload": {"mass": 1.5, "pos": [0.0, 0.0, -0.3]}} for s in ("left", "right")}})
# ---- chainsim.py (`sim: chain`): the robot is the numpy planar-chain simulator with its own
# physics, not MuJoCo (its header says what it models). The hard classes of issues 46 and 48:
# backlash (a motor behind a gear play), Stribeck against Coulomb friction on a light servo,
# armature on every joint, a payload and a centre-of-mass shift, and controls of several seeds.
MODELS["leg3_chain"] = dict(MODELS["leg3"], chain="leg3", key=[-0.4, 0.8, -0.4])
MODELS["pendulum_chain"] = dict(xml="../../../fixtures/synth/pendulum_servo.xml", chain="pendulum",
                                joints=["servo"], robot="pendulum_servo", key=[0.0], amp=[0.4],
                                t0_ctrl=0.0043, **STD)
CHAIN_P = dict(sim="chain", model="pendulum_chain")
CHAIN_L = dict(sim="chain", model="leg3_chain")
STRIBECK = {"static": 0.06, "dynamic": 0.03, "v_stribeck": 0.2}
CASES.update({
    "K0_pend_none": dict(CHAIN_P, seed=71, effects={}),
    "K1_pend_none": dict(CHAIN_P, seed=72, effects={}),
    # the same commands (seed) with Stribeck friction and with Coulomb friction at its sliding level
    "K2_pend_stribeck": dict(CHAIN_P, seed=73, effects={"joints": {"servo": {"stribeck": STRIBECK}}}),
    "K3_pend_coulomb": dict(CHAIN_P, seed=73, effects={"joints": {"servo": {"frictionloss": 0.03}}}),
    "K4_leg_none": dict(CHAIN_L, seed=75, effects={}),
    "K5_leg_none": dict(CHAIN_L, seed=76, effects={}),
    "K6_knee_backlash": dict(CHAIN_L, seed=77, effects={"joints": {"knee": {"backlash": 0.04}}}),
    "K7_all_backlash": dict(CHAIN_L, seed=78, effects={"joints": {j: {"backlash": 0.03} for j in ALL3}}),
    "K8_all_armature": dict(CHAIN_L, seed=79, effects={"joints": {j: {"armature": 0.06} for j in ALL3}}),
    "K9_shank_payload": dict(CHAIN_L, seed=80, effects={"bodies": {"shank": {
        "joint": "knee", "payload": {"mass": 0.6, "pos": [0.0, 0.0, -0.25]}}}}),
    "K10_shank_com_shift": dict(CHAIN_L, seed=81, effects={"bodies": {"shank": {
        "joint": "knee", "com_shift": [0.03, 0.0, -0.04]}}}),
})
# The shank's moment of inertia about the knee's axis through its centre of mass doubled (mass and
# centre of mass kept): a link heavier at its ends than its CAD (a battery pack split in two).
CASES["K11_shank_inertia"] = dict(CHAIN_L, seed=85, effects={"bodies": {"shank": {
    "joint": "knee", "inertia_scale": 2.0}}})
# Reduced chainsim cases for `make test` (tests/independent_chain.rs; recordings committed in
# fixtures/independent_py/): 4 episodes × 4 s, the last held out.
CHAIN_R = dict(CHAIN_L, episodes=4, seconds=4.0, heldout=[3])
CASES["KR0_leg_none"] = dict(CHAIN_R, seed=90, effects={})
CASES["KR1_shank_payload"] = dict(CHAIN_R, seed=91, effects={"bodies": {"shank": {
    "joint": "knee", "payload": {"mass": 0.6, "pos": [0.0, 0.0, -0.25]}}}})
# Backlash 0.04 (total play) on the knee: a motor behind a gear play.
CASES["KR6_knee_backlash"] = dict(CHAIN_R, seed=96, effects={"joints": {"knee": {"backlash": 0.04}}})
CASES["KR11_shank_inertia"] = dict(CHAIN_R, seed=95, effects={"bodies": {"shank": {
    "joint": "knee", "inertia_scale": 2.0}}})
# Backlash 0.03 (total play) behind every motor of the leg (K7's truth, reduced): one group on
# all three joints (issue 46's all-joint backlash). Recorded by run.sh, not committed.
CASES["KR7_all_backlash"] = dict(CHAIN_R, seed=97, effects={"joints": {j: {"backlash": 0.03} for j in ALL3}})
# Armature on every joint (one value, 0.06, where the model says 0.04 / 0.03 / 0.012): one group.
CASES["KR8_all_armature"] = dict(CHAIN_R, seed=98,
    effects={"joints": {j: {"armature": 0.06} for j in ALL3}})
# Stribeck friction on the light pendulum servo (K2's curve), reduced, and Coulomb friction at its
# sliding level on the same commands (seed): the first must come out blind as Stribeck friction
# (v_s within 10 %), the second as Coulomb friction.
CHAIN_PR = dict(CHAIN_P, episodes=4, seconds=4.0, heldout=[3])
CASES["KR2_pend_stribeck"] = dict(CHAIN_PR, seed=99, effects={"joints": {"servo": {"stribeck": STRIBECK}}})
CASES["KR3_pend_coulomb"] = dict(CHAIN_PR, seed=99, effects={"joints": {"servo": {"frictionloss": 0.03}}})
# ---- the trunk's centre of mass (issue 48): observable only where the legs carry the trunk.
# On a test stand (the trunk welded to the world: leg3's `stand` body) a battery moving the
# trunk's centre of mass acts on no recorded joint — the fit must report nothing. Standing on a
# pinned foot (chainsim, models/stance3.xml: the chain rooted at the foot, the trunk the hip's
# child body, an inverted chain held up by its servos) it loads every joint and must come out
# as a body effect on the hip's child body, the trunk.
CASES["L16_stand_trunk_battery"] = dict(model="leg3", seed=32, effects={"bodies": {"stand": {
    "payload": {"mass": 1.0, "pos": [-0.06, 0.0, 0.03]}, "com_shift": [0.03, 0.0, 0.0]}}})
CASES["RS1_stand_trunk_battery"] = dict(CASES["L16_stand_trunk_battery"], seed=62, episodes=4,
                                        seconds=4.0, heldout=[3])
MODELS["stance3_chain"] = dict(xml="stance3.xml", chain="stance3", joints=["ankle", "knee", "hip_pitch"],
                               robot="stance3_pinned_foot", key=[0.15, -0.4, 0.3], amp=[0.1, 0.15, 0.15],
                               t0_ctrl=0.0053, **STD)
CHAIN_S = dict(sim="chain", model="stance3_chain")
CASES["KS0_stance_none"] = dict(CHAIN_S, seed=82, effects={})
CASES["KS1_trunk_com_shift"] = dict(CHAIN_S, seed=83, effects={"bodies": {"trunk": {
    "joint": "hip_pitch", "com_shift": [0.04, 0.0, -0.03]}}})
# KS2's battery sits off the trunk's axis (8 cm behind it and 12 cm above its centre): one point
# mass placed in the joint's plane (link_mass: mass, along, across).
CASES["KS2_trunk_battery"] = dict(CHAIN_S, seed=84, effects={"bodies": {"trunk": {
    "joint": "hip_pitch", "payload": {"mass": 1.5, "pos": [-0.08, 0.0, 0.32]}}}})
# Reduced for `make test` (tests/independent_chain.rs): 4 episodes × 4 s, the last held out.
CHAIN_SR = dict(CHAIN_S, episodes=4, seconds=4.0, heldout=[3])
CASES["KSR0_stance_none"] = dict(CHAIN_SR, seed=92, effects={})
CASES["KSR1_trunk_com_shift"] = dict(CHAIN_SR, seed=93, effects={"bodies": {"trunk": {
    "joint": "hip_pitch", "com_shift": [0.04, 0.0, -0.03]}}})
CASES["KSR2_trunk_battery"] = dict(CHAIN_SR, seed=94, effects={"bodies": {"trunk": {
    "joint": "hip_pitch", "payload": {"mass": 1.5, "pos": [-0.08, 0.0, 0.32]}}}})
# ---- every leg (issue 48): the same 0.25 kg sensor at the foot end of all four shanks of the
# quadruped on its stand; one body effect on the four knees' child bodies, one group.
QUAD_PAYLOAD = {"payload": {"mass": 0.25, "pos": [0.0, 0.0, -0.2]}}
CASES["Q6_shanks_payload"] = dict(QUAD_EP, seed=46, effects={"bodies": {
    f"{l}_shank": QUAD_PAYLOAD for l in ("FL", "FR", "RL", "RR")}})
CASES["QR6_shanks_payload"] = dict(CASES["Q6_shanks_payload"], seed=66, episodes=3, seconds=4.0,
                                   heldout=[2])
# ---- a floating-base robot recorded on a stand: the simulated quadruped's torso is welded to
# the world (quad12.xml); `fit`/`gap` get its robot file with a free joint (quad12_float.xml),
# whose base the replay must hold with the stand's inertia, the legs loaded by gravity.
MODELS["quad12f"] = dict(MODELS["quad12"], nominal="quad12_float.xml")
CASES["QR0f_stand_float_none"] = dict(QUAD_EP, model="quad12f", seed=67, episodes=3,
                                      seconds=4.0, heldout=[2], effects={})
CASES["QR7f_stand_float_knee_damping"] = dict(CASES["QR0f_stand_float_none"], seed=68,
    effects={"joints": {f"{l}_knee": {"damping": 0.3} for l in ("FL", "FR", "RL", "RR")}})
# ---- a free base (issue 48; floatsim.py, `sim: float`): the trunk on slide x / slide z / hinge
# y joints standing on two legs (models/biped2.xml), both legs commanded alike; the ground is
# floatsim's own penalty contact (spring-damper + regularised Coulomb friction), not MuJoCo's:
# the contact models differ, as they do between any simulator and a floor. The trunk's three
# base joints are recorded as positions only (passive). `amp`: the squat's, the hip swing's and
# the trunk pitch's command signals (floatsim.run_episode); the key leans the trunk 0.05 rad
# forward, over the middle of the soles.
B2 = ["root_x", "root_z", "root_pitch"] + [f"{s}_{j}" for s in ("left", "right") for j in ALL3]
MODELS["biped2_float"] = dict(xml="biped2.xml", chain="biped2", joints=B2, robot="biped2_floor",
                              key=[-0.4, 0.8, -0.45], amp=[0.15, 0.02, 0.015], t0_ctrl=0.0047, **STD)
CHAIN_F = dict(sim="float", model="biped2_float")
CASES["KF0_biped_none"] = dict(CHAIN_F, seed=86, effects={})
CASES["KF1_trunk_battery"] = dict(CHAIN_F, seed=87, effects={"bodies": {"trunk": {
    "joint": "root_pitch", "com_shift": [0.04, 0.0, -0.03]}}})
CHAIN_FR = dict(CHAIN_F, episodes=4, seconds=4.0, heldout=[3])
CASES["KFR0_biped_none"] = dict(CHAIN_FR, seed=96, effects={})
CASES["KFR1_trunk_battery"] = dict(CHAIN_FR, seed=97, effects={"bodies": {"trunk": {
    "joint": "root_pitch", "com_shift": [0.04, 0.0, -0.03]}}})
# Real body effects other than a moved centre on the same floor (the stand-in test of
# docs/fitting.md, "A free base standing on a floor"): a 0.6 kg sensor at the foot end of both
# shanks (one body effect on the two knees' child bodies), and KS2's 1.5 kg battery off the
# trunk's axis (8 cm behind it, 12 cm above its centre); both committed in
# fixtures/independent_py, tests/independent_free.rs.
CASES["KFR2_shanks_payload"] = dict(CHAIN_FR, seed=98, effects={"bodies": {
    f"{s}_shank": {"joint": f"{s}_knee", "payload": {"mass": 0.6, "pos": [0.0, 0.0, -0.25]}}
    for s in ("left", "right")}})
CASES["KFR3_trunk_battery_off_axis"] = dict(CHAIN_FR, seed=99, effects={"bodies": {"trunk": {
    "joint": "root_pitch", "payload": {"mass": 1.5, "pos": [-0.08, 0.0, 0.32]}}}})
# The clean control over other floors (`ground`: floatsim's k, c): ten times stiffer and five
# times softer than KFR0's, the same commands (seed) for two episodes: how much of KFR0's gap is
# the floor, and whether MuJoCo's contact settings (solref, solimp) can be either floor.
CASES["KFR0s_biped_stiff_floor"] = dict(CHAIN_FR, seed=96, episodes=2, heldout=[1], effects={},
                                        ground=dict(k=1e6, c=3000.0))
# KFR1's battery over KFR0s's stiff floor (the same commands, seed 97): whether the shift along
# the trunk is hidden by the floor or by the excitation (docs/fitting.md). Recorded by run.sh.
CASES["KFR1s_trunk_battery_stiff_floor"] = dict(CASES["KFR1_trunk_battery"], ground=dict(k=1e6, c=3000.0))
CASES["KFR0w_biped_soft_floor"] = dict(CHAIN_FR, seed=96, episodes=2, heldout=[1], effects={},
                                       ground=dict(k=2e4, c=450.0))
# ---- arm4y: a humanoid's arm whose upper arm hangs along its shoulder yaw's axis (the new-user
# tryout's 4-joint arm). Its centre of mass moved 4 cm forward, perpendicular to that axis: the
# shoulder pitch carrying it sees the shift through gravity, the yaw's own plane holds no "along".
# 4 × 4 s, the last held out (tests/independent_body.rs; committed in fixtures/independent_py/).
MODELS["arm4y"] = dict(xml="arm4y.xml", joints=["shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow"],
                       robot="arm4y_torso", amp=[0.5, 0.35, 0.5, 0.5], t0_ctrl=0.0043, **STD)
CASES["RY0_arm_none"] = dict(model="arm4y", seed=63, episodes=4, seconds=4.0, heldout=[3], effects={})
CASES["RY1_upper_arm_com_forward"] = dict(model="arm4y", seed=64, episodes=4, seconds=4.0, heldout=[3],
    effects={"bodies": {"upper_arm": {"com_shift": [0.04, 0.0, 0.0]}}})
