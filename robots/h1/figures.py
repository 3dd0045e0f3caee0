"""Convert H1's published inertial figures into the frames of robots/h1/h1.xml.

Run from the repository root: `.venv/bin/python robots/h1/figures.py`. It prints, per body,
the `<inertial>` attributes (pos, mass, fullinertia in the body's own axes) and the frame
data of the shoulder bodies, ready to paste into h1.xml when a figure changes.

Source of the figures (see robots/h1/README.md): MuJoCo Menagerie `unitree_h1/h1.xml`,
commit 83e4e86b8f75a92a81487d383e24adcafceed55f (BSD-3-Clause, derived by the Menagerie
from Unitree's H1 URDF). The Menagerie states each inertia as principal moments plus the
quaternion (w, x, y, z) of the principal axes in the body frame; h1.xml states the full
tensor in the body frame instead (the URDF's form), I = R diag(I_p) R^T.

One change of frame: in the published tree the shoulder-pitch body is rotated by +-25 deg
(0.43633 rad) about x (so that its hinge is its local y axis) and the shoulder-roll body
rotates back.
h1.xml keeps every body frame parallel to the pelvis at q = 0 and tilts the shoulder-pitch
hinge axis instead: axis = R_x(+-25 deg) (0, 1, 0). The shoulder-pitch link's centre of
mass and inertia are rotated into the torso-parallel frame (c' = R c, I' = R I R^T) and the
roll joint's position becomes p_pitch + R p_roll. Kinematics and dynamics are unchanged.
"""

from __future__ import annotations

import numpy as np

# name: (mass kg, com in body frame, principal-axes quat (w, x, y, z), principal moments)
# Left side and centre; the right side mirrors y (checked against the source's right side).
PUBLISHED = {
    "pelvis": (
        5.39,
        (-0.0002, 4e-05, -0.04522),
        (0.498303, 0.499454, -0.500496, 0.501741),
        (0.0490211, 0.0445821, 0.00824619),
    ),
    "hip_yaw": (
        2.244,
        (-0.04923, 0.0001, 0.0072),
        (0.69699, 0.219193, 0.233287, 0.641667),
        (0.00304494, 0.00296885, 0.00189201),
    ),
    "hip_roll": (
        2.232,
        (-0.0058, -0.00319, -9e-05),
        (0.0438242, 0.70721, -0.0729075, 0.701867),
        (0.00243264, 0.00225325, 0.00205492),
    ),
    "thigh": (
        4.152,
        (0.00746, -0.02346, -0.08193),
        (0.979828, 0.0513522, -0.0169854, -0.192382),
        (0.0829503, 0.0821457, 0.00510909),
    ),
    "calf": (
        1.721,
        (-0.00136, -0.00512, -0.1384),
        (0.626132, -0.034227, -0.0416277, 0.777852),
        (0.0125237, 0.0123104, 0.0019428),
    ),
    "foot": (
        0.446,
        (0.06722, 0.00015, -0.04497),
        (0.489101, 0.503197, 0.565782, 0.432972),
        (0.00220848, 0.00218961, 0.000214202),
    ),
    "torso": (
        17.789,
        (0.000489, 0.002797, 0.20484),
        (0.999989, -0.00130808, -0.00282289, -0.00349105),
        (0.487315, 0.409628, 0.127837),
    ),
    "shoulder_pitch": (
        1.033,
        (0.005045, 0.053657, -0.015715),
        (0.814858, 0.579236, -0.0201072, -0.00936488),
        (0.00129936, 0.000987113, 0.000858198),
    ),
    "shoulder_roll": (
        0.793,
        (0.000679, 0.00115, -0.094076),
        (0.732491, 0.00917179, 0.0766656, 0.676384),
        (0.00170388, 0.00158256, 0.00100336),
    ),
    "upper_arm": (
        0.839,
        (0.01365, 0.002767, -0.16266),
        (0.703042, -0.0331229, -0.0473362, 0.708798),
        (0.00408038, 0.00370367, 0.000622687),
    ),
    "forearm": (
        0.669,
        (0.15908, -0.000144, -0.015776),
        (0.0765232, 0.720327, 0.0853116, 0.684102),
        (0.00601829, 0.00600579, 0.000408305),
    ),
}
SHOULDER_PITCH_POS = np.array([0.0055, 0.15535, 0.42999])  # in the torso frame (left)
SHOULDER_TILT = 0.43633  # rad (25 deg): the URDF rpy; the Menagerie quat (0.976296, 0.216438, 0, 0)
SHOULDER_ROLL_POS = np.array([-0.0055, 0.0565, -0.0165])  # in the tilted pitch frame
MIRROR = np.diag([1.0, -1.0, 1.0])


def quat_to_matrix(q: tuple[float, float, float, float]) -> np.ndarray:
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def body_frame_inertia(name: str, side: float) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass, com, full inertia tensor) in h1.xml's frame of the body; side +1 left, -1 right."""
    mass, com, quat, moments = PUBLISHED[name]
    R = quat_to_matrix(quat)
    inertia = R @ np.diag(moments) @ R.T
    c = np.array(com)
    if name == "shoulder_pitch":
        Rt = rot_x(SHOULDER_TILT)
        c, inertia = Rt @ c, Rt @ inertia @ Rt.T
    if side < 0:
        c, inertia = MIRROR @ c, MIRROR @ inertia @ MIRROR
    return mass, c, inertia


def fmt(values: np.ndarray, digits: int = 9) -> str:
    return " ".join(f"{v:.{digits}g}" for v in values)


def main() -> None:
    total = 0.0
    for name in PUBLISHED:
        sides = (1.0,) if name in ("pelvis", "torso") else (1.0, -1.0)
        for side in sides:
            mass, c, inertia = body_frame_inertia(name, side)
            total += mass
            full = [inertia[0, 0], inertia[1, 1], inertia[2, 2]]
            full += [inertia[0, 1], inertia[0, 2], inertia[1, 2]]
            label = name if len(sides) == 1 else f"{'L' if side > 0 else 'R'}_{name}"
            print(f'{label:18s} pos="{fmt(c)}" mass="{mass}" fullinertia="{fmt(full)}"')
    for side, label in ((1.0, "L"), (-1.0, "R")):
        Rt = rot_x(side * SHOULDER_TILT)
        axis = Rt @ np.array([0.0, 1.0, 0.0])
        roll_pos = Rt @ (MIRROR @ SHOULDER_ROLL_POS if side < 0 else SHOULDER_ROLL_POS)
        print(f"{label}_shoulder_pitch axis {fmt(axis, 12)}  roll joint offset {fmt(roll_pos, 9)}")
    print(f"total mass {total:.3f} kg")


if __name__ == "__main__":
    main()
