"""What the API's request bodies share: no field they do not name, no NaN or infinity in a number, and
the ranges a stored row id and a Unix time can take.

JSON has neither NaN nor infinity, but the parser the server reads bodies with accepts both, and where
a field had no bounds they got past validation: a bookmark at NaN seconds failed in the database (a 500);
a lock ending at infinity and a bookmark at infinity were accepted and read back with no time (null). A
row id past SQLite's INTEGER range (a lock's track_id of 10²³) failed in the driver, not as "not found".
A time before 1970 or after 9999 is no time the recorder can hold. (An alarm condition's numbers were
already checked finite by server.alarms.conditions; that check stays, for rules stored before.)"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

SQLITE_MAX_INT = 2**63 - 1
UNIX_MAX_S = 253402300799.0  # 9999-12-31T23:59:59Z


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


DbId = Annotated[int, Field(ge=1, le=SQLITE_MAX_INT, description="row id")]
UnixTime = Annotated[float, Field(ge=0.0, le=UNIX_MAX_S, description="Unix s")]
