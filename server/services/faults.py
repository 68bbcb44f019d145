"""How a background task (alarm store, recorder, track writer, retention) logs a failure it retries."""

from __future__ import annotations

import logging

from sqlalchemy.exc import OperationalError


def brief(exc: BaseException) -> str:
    """An exception as one line: its type and its message's first line."""
    return f"{type(exc).__name__}: {(str(exc).splitlines() or [''])[0]}"


class FailureLog:
    """A device fault (the database's OperationalError: locked past its busy timeout, read-only, full; and
    any of `device`, such as OSError for a full disk) is a condition of the machine, not a bug: one line at
    `level` every time. Anything else is a bug: logged at ERROR with its traceback the first time, and in
    one line after (a bug that repeats every retry would otherwise fill the log with the same traceback)."""

    def __init__(self, logger: logging.Logger, device: tuple[type[BaseException], ...] = (OperationalError,),
                 level: int = logging.WARNING):
        self.logger, self.device, self.level = logger, device, level
        self.traced = False  # a bug was logged with its traceback

    def log(self, exc: BaseException, message: str, *args: object) -> None:
        """Log `message % args` for the failure `exc`, as the class describes."""
        bug = not self.traced and not isinstance(exc, self.device)
        self.traced |= bug
        self.logger.log(logging.ERROR if bug else self.level, message, *args, exc_info=exc if bug else None)
