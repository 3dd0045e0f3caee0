"""Plan compiler: scenario -> contact schedule, trunk reference, hand targets and events.

Entry point: `compile_plan(scenario, strategy=None, *, base_height=0.60, foot_width=0.2)`.
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
