"""`tmeye eval --alarms`: its interval bookkeeping against hand-made truths, a short real run, bad input."""

from __future__ import annotations

import json
import math
import subprocess
import sys

from server.alarms.conditions import Approach, RangeBelow
from server.alarms.engine import Rule
from tmeye.alarm_eval import compare, expected, runs


def test_runs_expected_and_compare() -> None:
    dt = 0.1
    truth = [(k * dt, 10 <= k < 20 or 25 <= k < 30 or 60 <= k < 61) for k in range(100)]
    raw = runs(truth, dt)
    assert [(round(a, 3), round(b, 3)) for a, b in raw] == [(1.0, 2.0), (2.5, 3.0), (6.0, 6.1)]
    rule = Rule("rule:1", "r", "low", RangeBelow(5.0), 0.0, 1.0)
    exp = expected(rule, raw)  # the 0.5 s gap is under the off-delay: one alarm
    assert [(round(a, 3), round(b, 3)) for a, b in exp] == [(1.0, 4.0), (6.0, 7.1)]
    slow = Rule("rule:2", "a", "low", Approach(1.0, for_s=0.6), 0.0, 1.0)
    assert [(round(a, 3), round(b, 3)) for a, b in expected(slow, raw)] == [(1.6, 3.0)]  # short runs never hold
    late = Rule("rule:3", "d", "low", RangeBelow(5.0), 0.5, 1.0)
    assert [(round(a, 3), round(b, 3)) for a, b in expected(late, raw)] == [(1.5, 4.0)]  # 6.0-6.1 is too short
    got = [(1.05, 4.02), (5.0, 5.2), (6.1, math.inf)]
    res = compare(exp, got, end=9.9)
    assert (res["expected"], res["alarms"], res["matched"], res["misses"], res["false_alarms"]) == (2, 3, 2, 0, 1)
    assert res["activation_error"]["max_abs_s"] == 0.1 and res["clear_error"]["within_0.1s"] == 1
    assert res["out_of_view"] is None
    seen = [(k * dt, 15 <= k < 20) for k in range(100)]  # the first run seen only from 1.5 s, the second never
    late = compare(exp, [(1.6, 4.0)], end=9.9, in_view=seen)
    assert late["out_of_view"] == {"misses": 1, "late": 1}
    assert compare(exp, [(1.6, 4.0)], end=9.9, in_view=[(t, True) for t, _ in seen])["out_of_view"] == {
        "misses": 0, "late": 0}


def test_short_run_and_bad_input() -> None:
    out = subprocess.run([sys.executable, "-m", "tmeye", "eval", "--alarms", "--minutes", "0.1"],
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout)
    assert res["frames"] == 180 and len(res["rules"]) == 3
    for r in res["rules"]:
        assert r["matched"] + r["misses"] == r["expected"] and r["alarms"] >= r["matched"]
        assert r["out_of_view"]["misses"] <= r["misses"]
    bad = subprocess.run([sys.executable, "-m", "tmeye", "eval", "--alarms", "--minutes", "0"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "--minutes" in bad.stderr
