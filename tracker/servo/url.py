"""Open a servo driver from a URL.

    sim                               SimulatedGimbal with default dynamics
    sim?latency=0.05&tau=0.1&rate=200&backlash=0.3    (seconds, seconds, deg/s, degrees)
    maestro:/dev/ttyACM0              Pololu Maestro, compact protocol (?baud=115200&timeout=0.2)
    ascii:/dev/ttyUSB0                TMEye ASCII protocol board (?baud=115200&timeout=0.3&boot=2.5)

Unknown schemes, missing paths, unknown or malformed options and missing ports raise ServoError with a
one-line message.
"""

from __future__ import annotations

from urllib.parse import parse_qsl

from tracker.servo.base import ServoDriver, ServoError
from tracker.servo.sim import SimGimbalConfig, SimulatedGimbal

SCHEMES = ("sim", "maestro", "ascii")


def _split(url: str) -> tuple[str, str, dict[str, float]]:
    """'scheme:path?k=v&...' -> (scheme, path, {k: float(v)})."""
    head, _, query = url.strip().partition("?")
    scheme, _, path = head.partition(":")
    opts: dict[str, float] = {}
    for key, value in parse_qsl(query, keep_blank_values=True):
        try:
            opts[key] = float(value)
        except ValueError:
            raise ServoError(f"servo URL {url!r}: option {key}={value!r} is not a number") from None
    return scheme.lower(), path, opts


def _check_keys(url: str, opts: dict[str, float], allowed: tuple[str, ...]) -> None:
    unknown = sorted(set(opts) - set(allowed))
    if unknown:
        raise ServoError(
            f"servo URL {url!r}: unknown option(s) {', '.join(unknown)} (known: {', '.join(allowed)})"
        )


def open_servo(url: str) -> ServoDriver:
    """A driver for `url` (see the module docstring). Raises ServoError on any problem."""
    scheme, path, opts = _split(url)
    if scheme not in SCHEMES:
        raise ServoError(f"servo URL {url!r}: unknown scheme {scheme!r} (use one of: {', '.join(SCHEMES)})")
    if scheme == "sim":
        _check_keys(url, opts, ("latency", "tau", "rate", "backlash"))
        cfg = SimGimbalConfig(
            time_constant_s=opts.get("tau", SimGimbalConfig.time_constant_s),
            max_rate_deg_s=opts.get("rate", SimGimbalConfig.max_rate_deg_s),
            latency_s=opts.get("latency", SimGimbalConfig.latency_s),
            backlash_deg=opts.get("backlash", SimGimbalConfig.backlash_deg),
        )
        return SimulatedGimbal(cfg)
    if not path:
        raise ServoError(f"servo URL {url!r}: no serial port given (e.g. {scheme}:/dev/ttyUSB0)")
    if scheme == "maestro":
        from tracker.servo.maestro import MaestroDriver

        _check_keys(url, opts, ("baud", "timeout"))
        return MaestroDriver(path, baud=int(opts.get("baud", 115200)), timeout_s=opts.get("timeout", 0.2))
    from tracker.servo.ascii import AsciiServoDriver

    _check_keys(url, opts, ("baud", "timeout", "boot"))
    return AsciiServoDriver(
        path,
        baud=int(opts.get("baud", 115200)),
        timeout_s=opts.get("timeout", 0.3),
        boot_timeout_s=opts.get("boot", 2.5),
    )
