"""Derive H1's nominal standing pose (the `stand` keyframe and robot.yaml's `nominal`).

Run from the repository root: `.venv/bin/python robots/h1/nominal_pose.py [HEIGHT]`. It
prints the joint angles in degrees (for robot.yaml) and the keyframe qpos in radians (for
h1.xml); paste both by hand when the model changes.

Conditions solved for (the same as HECTOR's, robots/hector/nominal_pose.py):
- pelvis upright at height H = 0.98 m above the ground, both soles flat on z = 0;
- legs in their hip-pitch planes (hip yaw = hip roll = 0), ankle = -(hip_pitch + knee);
- torso yaw 0; arms at their zero angles: upper arm hanging, elbow at 90 deg with the
  forearm pointing forward (hands 0.30 m in front of the pelvis, at chest-box height);
- total CoM 0.0525 m in front of the ankles, mid-way between heel (-0.035) and toe
  (+0.14): H1's line foot reaches much further forward than back.
The two leg unknowns (hip pitch, knee) come from the two scalar conditions sole z = 0 and
CoM x - ankle x = 0.0525, solved with the arms already placed.

H = 0.98 m: the straight-leg height is 1.044 m; 0.98 m puts the knee near 45 deg, away
from the straight-knee singularity and with room to squat, as HECTOR's nominal stance does.
"""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco
import numpy as np
from scipy.optimize import fsolve

HEIGHT = 0.98  # pelvis origin above the soles, m
TOE, HEEL = 0.14, 0.035  # m ahead of / behind the sole site
COM_AHEAD_OF_ANKLE = 0.5 * (TOE - HEEL)

MJCF = Path(__file__).with_name("h1.xml")


def main() -> None:
    height = float(sys.argv[1]) if len(sys.argv) > 1 else HEIGHT
    model = mujoco.MjModel.from_xml_path(str(MJCF))
    data = mujoco.MjData(model)
    qadr = {model.joint(j).name: int(model.jnt_qposadr[j]) for j in range(model.njnt)}

    def configure(hip_pitch: float, knee: float) -> np.ndarray:
        q = np.zeros(model.nq)
        q[2], q[3] = height, 1.0
        for s in "LR":
            q[qadr[f"{s}_hip_pitch"]] = hip_pitch
            q[qadr[f"{s}_knee"]] = knee
            q[qadr[f"{s}_ankle"]] = -(hip_pitch + knee)
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        return q

    def residual(x: np.ndarray) -> list[float]:
        configure(float(x[0]), float(x[1]))
        com_x = data.subtree_com[model.body("pelvis").id][0]
        return [
            float(data.site("L_sole").xpos[2]),
            float(com_x - data.body("L_foot").xpos[0] - COM_AHEAD_OF_ANKLE),
        ]

    hp, kn = fsolve(residual, [-0.4, 0.8], xtol=1e-13)
    # Round to 1e-6 deg (< 1e-8 m at the sole) and keep the foot exactly flat in degrees.
    hp_deg, kn_deg = round(float(np.degrees(hp)), 6), round(float(np.degrees(kn)), 6)
    an_deg = round(-(hp_deg + kn_deg), 6)
    q = configure(np.radians(hp_deg), np.radians(kn_deg))
    com = data.subtree_com[model.body("pelvis").id]
    p_pelvis = data.body("pelvis").xpos
    print(f"hip_pitch {hp_deg:.6f}  knee {kn_deg:.6f}  ankle {an_deg:.6f} deg")
    print(f"CoM x - ankle x = {com[0] - data.body('L_foot').xpos[0]:.6f} m, CoM z {com[2]:.4f}")
    print(f"sole z = {data.site('L_sole').xpos[2]:.2e}, {data.site('R_sole').xpos[2]:.2e}")
    for s in ("L_hand", "R_hand"):
        print(f"{s} in pelvis frame: {np.round(data.site(s).xpos - p_pelvis, 5)}")
    print("keyframe qpos:", " ".join(f"{v:.12g}" for v in q))


if __name__ == "__main__":
    main()
