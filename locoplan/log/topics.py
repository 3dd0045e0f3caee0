"""Names of the topics, metadata records and attachments in a locoplan MCAP log.

The writer owns the first group; the others are the names the closed loop is expected to use
for its JSON and scene topics, kept here so the writer, the reader and `locoplan inspect`
agree on them.
"""

# Written by RunLogWriter itself.
TF = "/tf"
JOINT_STATES = "/joint_states"
JOINT_LIMITS = "/robot/joint_limits"
EVENTS = "/events"

# Scene topics (foxglove.SceneUpdate).
SCENE_OBJECTS = "/scene/objects"
SCENE_FIXTURES = "/scene/fixtures"
SCENE_FOOTHOLDS = "/scene/footholds"
SCENE_CONTACTS = "/scene/contacts"

# Controller topics (JSON).
CONTACT_SCHEDULE = "/contact/schedule"
CONTACT_FORCES = "/contact/forces"
MPC_PLAN = "/mpc/plan"
MPC_SOLVE = "/mpc/solve"
WBC = "/wbc"
TASKS = "/tasks"

# Metadata records and attachments.
METADATA_RUN = "locoplan"
METADATA_METRICS = "metrics"
METADATA_RUN_END = "run_end"
ATTACHMENT_SCENARIO = "scenario.yaml"
ATTACHMENT_METRICS = "metrics.json"
