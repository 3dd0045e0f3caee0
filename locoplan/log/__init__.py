"""MCAP logging of closed-loop runs: `RunLogWriter` writes, `read_log` reads, `recover_log`
repairs a file left by a killed process. Only this package imports the Foxglove SDK and mcap.
"""

from locoplan.log.reader import (
    JsonDecoderFactory,
    LogReadError,
    RunLog,
    TopicInfo,
    log_summary,
    read_log,
    recover_log,
)
from locoplan.log.scene import (
    Arrow,
    Box,
    LineStrip,
    Rgba,
    SceneItem,
    Sphere,
    box,
    force_arrow,
    line_strip,
    sphere,
)
from locoplan.log.termination import install_termination_handlers
from locoplan.log.transform import Transform
from locoplan.log.writer import RunLogWriter

__all__ = [
    "Arrow",
    "Box",
    "JsonDecoderFactory",
    "LineStrip",
    "LogReadError",
    "Rgba",
    "RunLog",
    "RunLogWriter",
    "SceneItem",
    "Sphere",
    "TopicInfo",
    "Transform",
    "box",
    "force_arrow",
    "install_termination_handlers",
    "line_strip",
    "log_summary",
    "read_log",
    "recover_log",
    "sphere",
]
