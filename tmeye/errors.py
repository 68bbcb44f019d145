"""Errors the `tmeye` command reports as one line with exit status 2."""


class UserError(Exception):
    """An input problem the user can fix: printed as one line, exit status 2."""
