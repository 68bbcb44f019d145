"""A solid target's unseen depth (tracker.localize.SolidPrior): the centre is placed behind the seen face
along the line of sight by ρ/2 times the smaller seen extent, and the range's 1-σ grows by σ_ρ/2 times it;
the angles stay; without a prior (flat targets) nothing changes."""

from __future__ import annotations

import math

import numpy as np

from tracker.localize import Localizer, SolidPrior
from tracker.rectify import Rectifier
from tracker.sim.rig import default_rig


def _pair(z_m: float, extent_px: tuple[float, float]):  # type: ignore[no-untyped-def]
    rect = Rectifier(default_rig())
    x, y = rect.rig.left.size[0] / 2.0 + 40.0, rect.rig.left.size[1] / 2.0 - 20.0
    d = rect.f * rect.rig.baseline / z_m
    args = (np.array([x, y]), d, 0.05, 400, None, (0.0, 0.0), extent_px)
    flat = Localizer(rect).locate(*args)
    solid = Localizer(rect, solid=SolidPrior(0.5, 0.3)).locate(*args)
    return flat, solid, rect


def test_the_centre_lies_behind_the_face_by_half_the_assumed_depth() -> None:
    flat, solid, rect = _pair(10.0, (60.0, 165.0))  # a person 0.6 x 1.65 m at 10 m: extent 0.6 m
    e = 60.0 * float(flat.rig[2]) / rect.f
    c = 0.5 * (rect.rig.left.c + rect.rig.right.c)
    moved = float(np.linalg.norm(solid.rig - c) - np.linalg.norm(flat.rig - c))
    assert math.isclose(moved, 0.25 * e, rel_tol=1e-9)
    u = (flat.rig - c) / np.linalg.norm(flat.rig - c)
    assert np.allclose(np.cross(solid.rig - flat.rig, u), 0.0, atol=1e-12)  # along the line of sight
    assert math.isclose(solid.sigma_r ** 2, flat.sigma_r ** 2 + (0.15 * e) ** 2, rel_tol=0.02)
    assert abs(solid.theta - flat.theta) < 1e-3 and abs(solid.phi - flat.phi) < 1e-3
    # the same lateral spread a little farther, and the depth's spread seen about the origin by parallax
    assert math.isclose(solid.sigma_theta, flat.sigma_theta, rel_tol=0.1)


def test_the_smaller_extent_counts_and_no_extent_or_prior_changes_nothing() -> None:
    _, tall, _ = _pair(10.0, (60.0, 165.0))
    _, wide, _ = _pair(10.0, (165.0, 60.0))
    assert np.allclose(tall.rig, wide.rig) and math.isclose(tall.sigma_r, wide.sigma_r)
    rect = Rectifier(default_rig())
    args = (np.array([300.0, 200.0]), 12.0, 0.05, 400, None)
    a = Localizer(rect, solid=SolidPrior()).locate(*args)  # no extent given
    b = Localizer(rect).locate(*args, (0.0, 0.0), (60.0, 165.0))  # flat targets
    c = Localizer(rect).locate(*args)
    assert np.array_equal(a.rig, c.rig) and np.array_equal(b.rig, c.rig) and a.sigma_r == b.sigma_r == c.sigma_r
