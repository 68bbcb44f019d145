"""The audit log: every control action with user, time and address."""

from __future__ import annotations

import time
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from server.db.models import AuditEntry, User


def record(db: Session, user: User | None, address: str | None, action: str, target: str | None = None,
           detail: dict[str, Any] | None = None) -> AuditEntry:
    """Add an entry to the session (committed with the action it records)."""
    entry = AuditEntry(at=time.time(), user_id=None if user is None else user.id,
                       username=None if user is None else user.username, address=address, action=action,
                       target=target, detail=detail)
    db.add(entry)
    return entry


def list_entries(db: Session, start: float | None, end: float | None, action: str | None,
                 limit: int) -> list[AuditEntry]:
    q = select(AuditEntry).order_by(AuditEntry.at.desc(), AuditEntry.id.desc()).limit(limit)
    if start is not None:
        q = q.where(AuditEntry.at >= start)
    if end is not None:
        q = q.where(AuditEntry.at <= end)
    if action:
        q = q.where(AuditEntry.action == action)
    return list(db.scalars(q))
