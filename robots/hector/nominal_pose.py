"""Derive HECTOR's nominal standing pose (the `stand` keyframe and robot.yaml's `nominal`).

Run from the repository root: `.venv/bin/python robots/hector/nominal_pose.py`. It prints
the joint angles in degrees (for robot.yaml) and the keyframe qpos in radians (for
hector.xml); paste both by hand when the model changes.

Conditions solved for:
- trunk upright at height H = 0.60 m above the ground, both soles flat on z = 0;
- legs in the sagittal plane (hip yaw = hip roll = 0), ankle = -(hip_pitch + knee);
- arms: shoulder roll 0, shoulder pitch and elbow from a planar two-link inverse kinematics
  putting the hands 0.275 m in front of and 0.05 m below the trunk origin, then rounded to
  whole degrees;
- total CoM 0.015 m in front of the ankles (mid-way between heel -0.06 and toe +0.09).
The two leg unknowns (hip pitch, knee) come from the two scalar conditions sole z = 0 and
CoM x - ankle x = 0.015, solved with the arms already placed.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
from scipy.optimize import fsolve

HEIGHT = 0.60  # trunk origin above the soles, m
HAND_FORWARD, HAND_BELOW = 0.275, 0.05  # hand target in the trunk frame, m
COM_AHEAD_OF_ANKLE = 0.015  # middle of [-0.06, +0.09], m
SHOULDER_Z, UPPER_ARM, FOREARM = 0.17, 0.205, 0.25  # m

MJCF = Path(__file__).with_name("hector.xml")


def arm_angles() -> tuple[float, float]:
    """Shoulder pitch and elbow (rad) placing the hand at the target, elbow flexed."""
    dx, dz = HAND_FORWARD, -HAND_BELOW - SHOULDER_Z
    a, b = UPPER_ARM, FOREARM
    dist = float(np.hypot(dx, dz))
    elbow = np.pi - np.arccos((a * a + b * b - dist * dist) / (2 * a * b))
    alpha = np.arccos((a * a + dist * dist - b * b) / (2 * a * dist))
    upper_arm_forward = np.arctan2(dx, -dz) - alpha
    return float(-upper_arm_forward), float(elbow)


def main() -> None:
    model = mujoco.MjModel.from_xml_path(str(MJCF))
    data = mujoco.MjData(model)
    qadr = {model.joint(j).name: int(model.jnt_qposadr[j]) for j in range(model.njnt)}

    sp_exact, el_exact = arm_angles()
    sp, el = np.radians(np.round(np.degrees([sp_exact, el_exact])))

    def configure(hip_pitch: float, knee: float) -> np.ndarray:
        q = np.zeros(model.nq)
        q[2], q[3] = HEIGHT, 1.0
        for s in "LR":
            q[qadr[f"{s}_hip_pitch"]] = hip_pitch
            q[qadr[f"{s}_knee"]] = knee
            q[qadr[f"{s}_ankle"]] = -(hip_pitch + knee)
            q[qadr[f"{s}_shoulder_pitch"]] = sp
            q[qadr[f"{s}_elbow"]] = el
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        return q

    def residual(x: np.ndarray) -> list[float]:
        configure(float(x[0]), float(x[1]))
        com_x = data.subtree_com[model.body("trunk").id][0]
        return [
            float(data.site("L_sole").xpos[2]),
            float(com_x - data.body("L_foot").xpos[0] - COM_AHEAD_OF_ANKLE),
        ]

    hp, kn = fsolve(residual, [-0.6, 1.2], xtol=1e-13)
    # Round to 1e-6 deg (< 1e-8 m at the sole) and keep the foot exactly flat in degrees.
    hp_deg, kn_deg = round(float(np.degrees(hp)), 6), round(float(np.degrees(kn)), 6)
    an_deg = round(-(hp_deg + kn_deg), 6)
    q = configure(np.radians(hp_deg), np.radians(kn_deg))
    com = data.subtree_com[model.body("trunk").id]
    p_trunk = data.body("trunk").xpos
    print(f"hip_pitch {hp_deg:.6f}  knee {kn_deg:.6f}  ankle {an_deg:.6f} deg")
    print(f"shoulder_pitch {np.degrees(sp):.1f}  elbow {np.degrees(el):.1f} deg")
    print(f"CoM x - ankle x = {com[0] - data.body('L_foot').xpos[0]:.6f} m, CoM z {com[2]:.4f}")
    print(f"sole z = {data.site('L_sole').xpos[2]:.2e}, {data.site('R_sole').xpos[2]:.2e}")
    for s in ("L_hand", "R_hand"):
        print(f"{s} in trunk frame: {np.round(data.site(s).xpos - p_trunk, 5)}")
    print("keyframe qpos:", " ".join(f"{v:.12g}" for v in q))


if __name__ == "__main__":
    main()
