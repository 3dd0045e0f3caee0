"""Robot description layer: one MJCF file builds both the MuJoCo plant and pinocchio model.

- `description`: `RobotDescription`, `load_robot_description(name_or_path)` from
  `robots/<name>/robot.yaml` (+ the MJCF it names), cross-checked against the MJCF.
- `conventions`: MuJoCo <-> pinocchio free-flyer states, Jacobians, M and bias forces.
- `mujoco_model`: MjSpec / MjModel loading, nominal keyframe, joint index maps.
- `pinocchio_model`: `PinocchioRobot`, the dynamics a whole-body controller needs per tick.

Sign conventions of the default robot `hector` (trunk frame x forward, y left, z up):
hip yaw about +z, hip roll about +x, hip pitch, knee and ankle about +y. Positive hip pitch
swings the leg backward, knee flexion is positive (15..160 deg) and a flat foot needs
ankle = -(hip_pitch + knee). Shoulder roll about +x on both arms (positive moves the hand to
+y: left arm outward, range [-30, 90] deg; right arm inward, range [-90, 30] deg). Shoulder
pitch about +y (negative lifts the arm forward). Elbow about -y, so flexion is positive
(0..150 deg) and moves the hand forward and up when the upper arm hangs down.

Free-flyer conventions: MuJoCo qpos quaternion (w, x, y, z), qvel = [v_world, omega_base,
qdot]; pinocchio q quaternion (x, y, z, w), v = [v_base, omega_base, qdot]. Controllers
work in pinocchio's convention; see `conventions` for the exact maps.

Importing this package does not import mujoco or pinocchio; import the submodules.
"""
