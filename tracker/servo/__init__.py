"""Pan/tilt servo drivers behind one interface (`ServoDriver`), opened from a URL by `open_servo`:
'sim' (SimulatedGimbal, the default), 'maestro:/dev/ttyACM0' (Pololu Maestro), 'ascii:/dev/ttyUSB0'
(an Arduino-class board speaking docs/servo-ascii-protocol.md)."""

from tracker.servo.base import AxisLimits, ServoDriver, ServoError
from tracker.servo.sim import SimGimbalConfig, SimulatedGimbal
from tracker.servo.url import open_servo

__all__ = ["AxisLimits", "ServoDriver", "ServoError", "SimGimbalConfig", "SimulatedGimbal", "open_servo"]
