"""Service errors that routers turn into 4xx answers with {"detail": message}."""


class NotFound(LookupError):
    """404: the named thing does not exist."""


class Conflict(ValueError):
    """409: the request clashes with the current state (a duplicate name, the last admin)."""


class Invalid(ValueError):
    """422: the request is well-formed but its values cannot be used."""


def one_line(exc: object) -> str:
    """A pydantic ValidationError as one line: 'field: message; ...'."""
    errors = getattr(exc, "errors", None)
    if errors is None:
        return str(exc).splitlines()[0]
    parts = []
    for e in errors():
        loc = ".".join(str(x) for x in e.get("loc", ()))
        parts.append(f"{loc}: {e.get('msg', 'invalid')}" if loc else str(e.get("msg", "invalid")))
    return "; ".join(parts)
