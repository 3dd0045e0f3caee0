"""Plan compiler: scenario -> contact schedule, trunk reference, hand targets and events.

Entry point: `compile_plan(scenario, strategy=None, *, geometry=HECTOR_GEOMETRY)`; the robot's
figures come in as a `locoplan.plan.robot_geometry.PlanGeometry`
(`locoplan.sim.robot_plan.compile_robot_plan` builds it from the script's robot).
"""

from locoplan.plan.compiler import STRATEGIES, compile_plan
from locoplan.plan.errors import PlanError
from locoplan.plan.events import PlanEvent
from locoplan.plan.gait import FOOT_NAMES, ContactSchedule, GaitBlock, SwingPhase
from locoplan.plan.hands import HandSegment, HandTrack, HandWaypoint
from locoplan.plan.manipulation import HAND_NAMES, HandContact, ObjectHold, ObjectTarget
from locoplan.plan.plan import HandTargets, ObjectReference, Plan
from locoplan.plan.tasks import PlannedTask
from locoplan.plan.trunk import TrunkReference, TrunkState

__all__ = [
    "FOOT_NAMES",
    "HAND_NAMES",
    "STRATEGIES",
    "ContactSchedule",
    "GaitBlock",
    "HandContact",
    "HandSegment",
    "HandTargets",
    "HandTrack",
    "HandWaypoint",
    "ObjectHold",
    "ObjectReference",
    "ObjectTarget",
    "Plan",
    "PlanError",
    "PlanEvent",
    "PlannedTask",
    "SwingPhase",
    "TrunkReference",
    "TrunkState",
    "compile_plan",
]
