"""The one runtime of a rig, shared by `tmeye track` and `tmeye serve`: composition from settings
(`compose`), the worker thread (`Runtime`), drop-oldest publishing (`Hub`, `Subscription`), operator servo
control (`ServoControl`) and the per-frame telemetry."""

from tmeye.runtime.compose import ComposeError, Composition, compose
from tmeye.runtime.config import RuntimeConfig, TrackerTuning
from tmeye.runtime.events import FrameEvent, ServoState
from tmeye.runtime.publish import Hub, Subscription
from tmeye.runtime.servo import ServoMode, ServoRequestError
from tmeye.runtime.worker import NoServoError, Runtime

__all__ = ["ComposeError", "Composition", "FrameEvent", "Hub", "NoServoError", "Runtime", "RuntimeConfig",
           "ServoMode", "ServoRequestError", "ServoState", "Subscription", "TrackerTuning", "compose"]
