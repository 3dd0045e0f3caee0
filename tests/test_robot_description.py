"""robot.yaml + MJCF loading: values, lookup rules, and the errors bad files raise."""

from __future__ import annotations

import shutil
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from ruamel.yaml import YAML

from locoplan.exceptions import RobotDescriptionError
from locoplan.robot.description import (
    ROBOTS_DIR_ENV,
    PlannerFigures,
    RobotDescription,
    load_robot_description,
    resolve_robot_yaml,
    robots_dir,
)

JOINTS = (
    "L_hip_yaw",
    "L_hip_roll",
    "L_hip_pitch",
    "L_knee",
    "L_ankle",
    "R_hip_yaw",
    "R_hip_roll",
    "R_hip_pitch",
    "R_knee",
    "R_ankle",
    "L_shoulder_roll",
    "L_shoulder_pitch",
    "L_elbow",
    "R_shoulder_roll",
    "R_shoulder_pitch",
    "R_elbow",
)
HECTOR_DIR = robots_dir() / "hector"


@pytest.fixture(scope="module")
def desc() -> RobotDescription:
    return load_robot_description()


def test_values(desc: RobotDescription) -> None:
    assert desc.name == "hector"
    assert desc.mjcf_path == (HECTOR_DIR / "hector.xml").resolve()
    assert desc.joint_names == JOINTS
    assert desc.n_joints == 16
    assert desc.foot_frames == ("L_sole", "R_sole")
    assert desc.hand_frames == ("L_hand", "R_hand")
    assert desc.base_frame == desc.trunk_body == "trunk"
    assert (desc.foot_toe, desc.foot_heel) == (0.09, 0.06)
    assert desc.fall_height == 0.35
    assert desc.base_height_nominal == 0.60
    # 1e-9 kg: a sum of decimal masses.
    assert abs(desc.total_mass - 17.0) < 1e-9
    knee = JOINTS.index("L_knee")
    assert desc.torque_limits[knee] == 67.0 and desc.velocity_limits[knee] == 10.5
    # Exact radians of the YAML's degrees (np.radians of the same decimal).
    assert desc.q_lower[knee] == np.radians(15.0) and desc.q_upper[knee] == np.radians(160.0)
    # Shoulder roll: left [-30, 90], right [-90, 30] deg (round trip through radians: 1e-12).
    assert np.allclose(np.degrees(desc.q_lower[[10, 13]]), [-30.0, -90.0], atol=1e-12, rtol=0)
    assert np.allclose(np.degrees(desc.q_upper[[10, 13]]), [90.0, 30.0], atol=1e-12, rtol=0)
    assert [list(i) for i in desc.leg_joint_indices] == [[0, 1, 2, 3, 4], [5, 6, 7, 8, 9]]
    assert [list(i) for i in desc.arm_joint_indices] == [[10, 11, 12], [13, 14, 15]]
    # Flat feet in the nominal pose: ankle = -(hip_pitch + knee), to the YAML's 1e-6 deg.
    hp, kn, an = np.degrees(desc.q_joints_nominal[2:5])
    assert abs(an + hp + kn) < 1e-9


def test_arrays_are_read_only(desc: RobotDescription) -> None:
    with pytest.raises(ValueError):
        desc.torque_limits[0] = 1.0
    with pytest.raises(ValueError):
        desc.leg_joint_indices[0][0] = 3
    with pytest.raises(AttributeError):
        desc.name = "other"  # type: ignore[misc]


def test_joint_order_agrees_everywhere(desc: RobotDescription) -> None:
    m = mujoco.MjModel.from_xml_path(str(desc.mjcf_path))
    assert tuple(m.joint(j).name for j in range(1, m.njnt)) == JOINTS
    assert tuple(m.actuator(a).name for a in range(m.nu)) == JOINTS
    assert [int(m.actuator_trnid[a, 0]) for a in range(m.nu)] == list(range(1, 17))
    pm = pin.buildModelFromMJCF(str(desc.mjcf_path))
    assert tuple(pm.names)[2:] == JOINTS
    yaml_joints = YAML(typ="safe").load((HECTOR_DIR / "robot.yaml").read_text())["joints"]
    assert tuple(j["name"] for j in yaml_joints) == JOINTS


def test_lookup_by_path_dir_and_env(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    by_file = load_robot_description(str(HECTOR_DIR / "robot.yaml"))
    by_dir = load_robot_description(str(HECTOR_DIR))
    assert by_file.mjcf_path == by_dir.mjcf_path
    robot_dir = tmp_path / "robots" / "mybot"
    robot_dir.mkdir(parents=True)
    _write(robot_dir, _raw())
    monkeypatch.setenv(ROBOTS_DIR_ENV, str(tmp_path / "robots"))
    assert load_robot_description("mybot").name == "hector"
    with pytest.raises(RobotDescriptionError, match="no robot description"):
        load_robot_description("hector")


def test_a_robot_name_is_not_a_folder_of_scripts(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`robot: h1` names the robot under robots/ even where the working directory has a folder
    `h1/` (of H1 scripts, say) without a robot.yaml; such a folder with one is a robot."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "h1").mkdir()
    (tmp_path / "h1" / "transfer.yaml").write_text("version: 1\n")
    assert resolve_robot_yaml("h1") == robots_dir() / "h1" / "robot.yaml"
    assert load_robot_description("h1").name == "h1"
    mine = tmp_path / "mybot"
    mine.mkdir()
    _write(mine, _raw())
    assert resolve_robot_yaml("mybot") == Path("mybot") / "robot.yaml"
    with pytest.raises(RobotDescriptionError, match="no robot description"):
        resolve_robot_yaml("nobot")


def test_robots_dir_installed_package_before_checkout(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import locoplan

    monkeypatch.delenv(ROBOTS_DIR_ENV, raising=False)
    package = tmp_path / "site-packages" / "locoplan"
    package.mkdir(parents=True)
    monkeypatch.setattr(locoplan, "__file__", str(package / "__init__.py"))
    # Neither layout present: the error names where an installed package keeps its robots.
    assert robots_dir() == package / "_data" / "robots"
    with pytest.raises(RobotDescriptionError, match="_data/robots"):
        load_robot_description("hector")
    # A checkout: robots/ beside the package.
    (package.parent / "robots").mkdir()
    assert robots_dir() == package.parent / "robots"
    # An installed wheel: the package data wins over a stray site-packages/robots.
    shutil.copytree(HECTOR_DIR, package / "_data" / "robots" / "hector")
    assert robots_dir() == package / "_data" / "robots"
    assert load_robot_description("hector").mjcf_path == (
        package / "_data" / "robots" / "hector" / "hector.xml"
    )
    # $LOCOPLAN_ROBOTS_DIR beats both.
    monkeypatch.setenv(ROBOTS_DIR_ENV, str(tmp_path / "mine"))
    assert robots_dir() == tmp_path / "mine"


def _raw() -> dict:
    raw = YAML(typ="safe").load((HECTOR_DIR / "robot.yaml").read_text())
    raw["mjcf"] = str((HECTOR_DIR / "hector.xml").resolve())
    return dict(raw)


def _write(directory: Path, raw: dict) -> Path:
    path = directory / "robot.yaml"
    yaml = YAML(typ="safe")
    with path.open("w") as f:
        yaml.dump(raw, f)
    return path


def _swap_first_joints(raw: dict) -> None:
    raw["joints"][0], raw["joints"][1] = raw["joints"][1], raw["joints"][0]


def _set(path: list, value: object):
    def edit(raw: dict) -> None:
        node = raw
        for key in path[:-1]:
            node = node[key]
        node[path[-1]] = value

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_set(["fall_height"], -1.0), "'fall_height' must be positive"),
        (_set(["fall_height"], 0.7), "fall_height must be below"),
        (_set(["foot"], None), "foot: expected a mapping"),
        (_set(["joints", 0, "torque_Nm"], "lots"), r"joints\[0\]: 'torque_Nm' must be a finite"),
        (_set(["joints", 3, "range_deg"], [160, 15]), "lower 160.0 must be below"),
        (_set(["joints", 3, "range_deg"], [10, 160]), "joint ranges differ"),
        (_set(["joints", 3, "torque_Nm"], 33.5), "ctrlrange"),
        (_swap_first_joints, "joint order differs"),
        (_set(["legs", "L"], ["L_hip_yaw", "L_toe"]), r"legs.L: unknown joints \['L_toe'\]"),
        (_set(["contacts", "hands", "L"], "L_palm"), "site 'L_palm' missing"),
        (_set(["nominal", "joints_deg", "L_knee"], 69.0), "keyframe 'stand' differs"),
        (_set(["nominal", "joints_deg", "L_knee"], 5.0), "within the joint ranges"),
        (_set(["nominal_keyframe"], "crouch"), "keyframe 'crouch' missing"),
        (_set(["mjcf"], "nowhere.xml"), "MJCF file .* not found"),
        (_set(["trunk_body"], "pelvis"), "trunk body 'pelvis' missing"),
    ],
)
def test_bad_files_raise(tmp_path: Path, edit, message: str) -> None:
    raw = _raw()
    edit(raw)
    path = _write(tmp_path, raw)
    with pytest.raises(RobotDescriptionError, match=message) as info:
        load_robot_description(str(path))
    assert str(path) in str(info.value) or "hector.xml" in str(info.value)


def test_unreadable_yaml_and_missing_key(tmp_path: Path) -> None:
    path = tmp_path / "robot.yaml"
    path.write_text("name: [unclosed\n")
    with pytest.raises(RobotDescriptionError, match="cannot read YAML"):
        load_robot_description(str(path))
    raw = _raw()
    del raw["contacts"]
    with pytest.raises(RobotDescriptionError, match="missing key 'contacts'"):
        load_robot_description(str(_write(tmp_path, raw)))
    with pytest.raises(RobotDescriptionError, match="no robot description"):
        load_robot_description(str(tmp_path / "absent.yaml"))


# -- a second robot: H1 (torso joint, 4-DoF arms, the optional fields) -------------------------
H1_DIR = robots_dir() / "h1"


def _raw_h1() -> dict:
    raw = YAML(typ="safe").load((H1_DIR / "robot.yaml").read_text())
    raw["mjcf"] = str((H1_DIR / "h1.xml").resolve())
    return dict(raw)


def test_h1_loads_with_torso_and_four_joint_arms() -> None:
    h1 = load_robot_description("h1")
    assert h1.n_joints == 19 and h1.trunk_body == "pelvis"
    assert [list(i) for i in h1.leg_joint_indices] == [[0, 1, 2, 3, 4], [5, 6, 7, 8, 9]]
    assert [list(i) for i in h1.arm_joint_indices] == [[11, 12, 13, 14], [15, 16, 17, 18]]
    assert list(h1.torso_joint_indices) == [h1.joint_names.index("torso_yaw")] == [10]
    assert (h1.hand_radius, h1.foot_sphere_radius) == (0.033, 0.014)
    assert h1.stance_width == 0.40572
    assert h1.mpc_body == "upper-body"
    assert h1.reach is not None
    assert h1.reach.shoulder_bodies == ("L_shoulder_roll_link", "R_shoulder_roll_link")
    assert (h1.reach.max, h1.reach.nominal) == (0.613, 0.458)
    # 1e-9 kg: a sum of decimal link masses (robots/h1/README.md).
    assert abs(h1.total_mass - 51.437) < 1e-9
    assert h1.hand_approach_kp == 1500.0
    with pytest.raises(ValueError):
        h1.torso_joint_indices[0] = 3


def test_optional_fields_default_to_hector(desc: RobotDescription) -> None:
    """HECTOR's robot.yaml has none of the optional fields: its contact geoms' radii
    (hector.xml) and the planner's 0.2 m foothold spacing, no torso joint, no stated reach."""
    assert len(desc.torso_joint_indices) == 0
    assert (desc.hand_radius, desc.foot_sphere_radius, desc.stance_width) == (0.02, 0.01, 0.2)
    assert desc.reach is None
    assert desc.mpc_body == "composite"
    assert desc.planner == PlannerFigures()
    assert desc.hand_approach_kp is None


def test_a_partial_planner_section_keeps_hector_s_other_figures(tmp_path: Path) -> None:
    raw = _raw()
    raw["planner"] = {"walk_stride": 0.25, "hand_default": [0.3, 0.1, 0]}
    planner = load_robot_description(str(_write(tmp_path, raw))).planner
    assert (planner.walk_stride, planner.hand_default) == (0.25, (0.3, 0.1, 0.0))
    assert planner.hand_tuck == PlannerFigures().hand_tuck
    assert planner.hip_yaw_range == PlannerFigures().hip_yaw_range


def _drop_torso(raw: dict) -> None:
    del raw["torso"]


def _torso_twice(raw: dict) -> None:
    raw["torso"] = ["torso_yaw", "L_elbow"]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_drop_torso, r"must list every joint exactly once \(not listed: \['torso_yaw'\]\)"),
        (_torso_twice, r"listed more than once: \['L_elbow'\]"),
        (_set(["torso"], ["waist"]), r"torso: unknown joints \['waist'\]"),
        (_set(["contacts", "hand_radius"], 0.0), "'hand_radius' must be positive"),
        (_set(["reach", "nominal"], 0.7), "nominal 0.7 must not exceed max 0.613"),
        (_set(["reach", "shoulders", "L"], "L_clavicle"), "shoulder body 'L_clavicle' missing"),
        (_set(["stance_width"], "wide"), "'stance_width' must be a finite number"),
        (_set(["planner", "hand_default"], [0.3, 0.2]), "'hand_default' must be a list of three"),
        (_set(["planner", "hand_tuck"], [0.1, -0.2, 0.0]), "the left hand's y must be positive"),
        (_set(["planner", "walk_stride"], -0.3), "'walk_stride' must be positive"),
        (_set(["planner", "throw_stop_offset"], -0.1), "'throw_stop_offset' must not be neg"),
        (_set(["planner", "hip_yaw_range_deg"], 0), "'hip_yaw_range_deg' must be positive"),
        (_set(["mpc_body"], "legs"), r"'mpc_body' must be one of \['composite', 'upper-body'\]"),
        (_set(["hand_approach_kp"], -5), "'hand_approach_kp' must be positive"),
        (_set(["planner", "hand_accel_limit"], 0), "'hand_accel_limit' must be positive"),
        (_set(["planner", "arm_moving_mass"], "heavy"), "'arm_moving_mass' must be a finite"),
        (_set(["planner", "tuck_lift_duration"], -1), "'tuck_lift_duration' must be positive"),
    ],
)
def test_bad_h1_files_raise(tmp_path: Path, edit, message: str) -> None:
    raw = _raw_h1()
    edit(raw)
    path = _write(tmp_path, raw)
    with pytest.raises(RobotDescriptionError, match=message):
        load_robot_description(str(path))


def test_hector_missing_a_joint_is_refused(tmp_path: Path) -> None:
    raw = _raw()
    raw["arms"]["R"] = ["R_shoulder_roll", "R_shoulder_pitch"]
    with pytest.raises(RobotDescriptionError, match=r"not listed: \['R_elbow'\]"):
        load_robot_description(str(_write(tmp_path, raw)))
