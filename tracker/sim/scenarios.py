"""Named scenarios for the simulated rig (`tmeye eval --list`) and the simulated-rig frame source."""

from __future__ import annotations

import zlib
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import cv2
import numpy as np
from numpy.typing import NDArray

from tracker.closedloop_path import MANOEUVRE
from tracker.frames import GimbalState, StereoFrame
from tracker.geometry import StereoRig, gimbal_rotation
from tracker.sim.bodies import PERSON_STATURE_M, BodyObject, body_texture, draw_stature
from tracker.sim.endless import EndlessScene
from tracker.sim.render import FrameTruth, SimRenderer, TargetTruth
from tracker.sim.rig import default_rig
from tracker.sim.scene import (
    CAMERA_HEIGHT_M,
    MovingObject,
    Surface,
    backdrop,
    foliage,
    person_texture,
    plate_texture,
    smooth_texture,
)

F64 = NDArray[np.float64]
TWO_PI = 2.0 * np.pi


def _walk(t: float) -> F64:
    """Crossing walk: range 3 -> 15 -> 3 m every 10 s, weaving left and right, bobbing."""
    z = 9.0 - 6.0 * np.cos(TWO_PI * t / 10.0)
    return np.array([0.3 * z * np.sin(TWO_PI * t / 6.0), 0.1 + 0.15 * np.sin(TWO_PI * t / 4.0), z])


def _approach(t: float) -> F64:
    """Approach from 30 m to 2 m in 10 s with a slight weave."""
    z = max(30.0 - 2.8 * t, 2.0)
    return np.array([0.25 * np.sin(TWO_PI * t / 5.0), 0.05 * np.sin(TWO_PI * t / 3.0), z])


def _crosser(t: float) -> F64:
    """Second object: crosses from left to right at 5 m, in front of the primary's path."""
    return np.array([-2.2 + 0.45 * t, 0.05, 5.0])


def _primary_far(t: float) -> F64:
    """Primary for two-targets: slow walk at 8 to 12 m near the centre."""
    z = 10.0 - 2.0 * np.cos(TWO_PI * t / 9.0)
    return np.array([0.6 * np.sin(TWO_PI * t / 7.0), 0.1, z])


def _panned(t: float) -> F64:
    """Target for `pan`: azimuth ±10°, range 6-12 m."""
    az = np.radians(10.0 * np.sin(TWO_PI * t / 7.0))
    z = 9.0 - 3.0 * np.cos(TWO_PI * t / 11.0)
    return np.array([z * np.tan(az), 0.1 + 0.1 * np.sin(TWO_PI * t / 5.0), z])


def _behind_post(t: float) -> F64:
    """Passes behind the post at 9 m (partial then full occlusion) at 12 m range."""
    return np.array([-7.0 + 0.55 * t, 0.3, 12.0])


def _illumination_gain(t: float) -> float:
    """Global illumination: steps and ramps of ±30 %."""
    if t < 2.0:
        return 1.0
    if t < 4.0:
        return 1.3  # step up
    if t < 5.0:
        return 0.7  # step down
    if t < 7.0:
        return 0.7 + 0.3 * (t - 5.0)  # ramp 0.7 -> 1.3
    if t < 8.0:
        return 1.3 - 0.6 * (t - 7.0)  # ramp 1.3 -> 0.7
    return 1.0  # step back


def _pan_schedule(t: float) -> GimbalState:
    return GimbalState(12.0 * np.sin(TWO_PI * t / 8.0), 3.0 * np.sin(TWO_PI * t / 6.0))


def _still(t: float) -> GimbalState:
    return GimbalState(0.0, 0.0)


def _unity(t: float) -> float:
    return 1.0


@dataclass(frozen=True)
class Scenario:
    """A scripted run of the simulated rig. `paths` are (target id, trajectory) pairs: id 1 is primary;
    `frames` its length at `fps` frames per second.

    `script` (seed -> EndlessScene): an endless scenario, whose moving objects and light come from the
    seeded script instead of `paths` and `gain` (which it leaves empty and at 1); its SimRig never runs
    out, and `frames` is only the default length of bounded runs (`tmeye eval`, `tmeye bench`)."""

    name: str
    description: str
    frames: int = 300
    fps: float = 30.0
    paths: tuple[tuple[int, Callable[[float], F64]], ...] = ((1, _walk),)
    foliage: bool = False
    gain: Callable[[float], float] = _unity
    # the right camera's exposure over the left's (its own auto-exposure, a different sensor): 1 alike
    right_gain: Callable[[float], float] = _unity
    gimbal: Callable[[float], GimbalState] = _still
    closed_loop: bool = False
    tags: tuple[str, ...] = field(default_factory=tuple)
    script: Callable[[int], EndlessScene] | None = None
    wall_m: float | None = None  # a textured wall across the view at this range (m) hides what is behind it
    person: bool = False  # targets are upright person-sized boards (0.5 x 1.7 m) instead of round plates
    enter_s: float = 0.0  # the targets of `paths` appear at this scene time (s)
    bodies: bool = False  # targets drawn as solid bodies (tracker.sim.bodies): the scenario `NAME:body`
    body_kinds: tuple[str, ...] = ("person", "sphere")  # with `bodies`: the kind of target 1, of the others

    @property
    def endless(self) -> bool:
        return self.script is not None


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario("walk", "target crossing at 3 to 15 m, cameras still"),
        Scenario("illumination", "walk with global illumination steps and ramps of ±30 %",
                 gain=_illumination_gain),
        Scenario("foliage", "walk beside a swaying bush", foliage=True),
        Scenario("approach", "target approaching from 30 m to 2 m", paths=((1, _approach),),
                 body_kinds=("sphere",)),
        Scenario("two-targets", "primary at 8-12 m, a second object crossing in front of it at 5 m",
                 paths=((1, _primary_far), (2, _crosser))),
        Scenario("pan", "cameras panning ±12° and tilting ±3° on a schedule while the target moves",
                 frames=240, paths=((1, _panned),), gimbal=_pan_schedule),
        Scenario("occlusion", "target passing behind a post at 9 m (partial, then full occlusion)",
                 frames=330, paths=((1, _behind_post),), body_kinds=("vehicle",)),
        Scenario("manoeuvre", "closed loop: the servos follow a target turning at up to 30°/s, accelerating "
                 "and stopping, over azimuth -19° to +38°", frames=294, paths=((1, MANOEUVRE),),
                 closed_loop=True, body_kinds=("sphere",)),
        Scenario("endless", "people (0.5 x 1.7 m) entering, walking, stopping, turning and leaving at 3 to 30 m, "
                 "for ever (seeded), beside a swaying bush, light ramps and ±20-30 % steps, now and then a "
                 "second object; eval/bench run 2 minutes", frames=3600, paths=(), foliage=True,
                 script=EndlessScene),
    )
}


PERSON_HALF_W_M = 0.25


def near_wall(rng: np.random.Generator, range_m: float) -> Surface:
    """A wall across the view at `range_m` (16 x 8 m, standing on the ground), textured with 3 cm blobs."""
    ex, ey, _ = np.eye(3)
    return Surface("near wall", np.array([0.0, CAMERA_HEIGHT_M - 4.0, range_m]), ex, ey, 8.0, 4.0,
                   smooth_texture(rng, (800, 1600), 3.0, 30, 170), 0.01)


def near_wall_path(wall_m: float, gap_m: float) -> Callable[[float], F64]:
    """A person walking left and right (±1 m, 6 s period) with the farthest edge of its board `gap_m` in
    front of a wall at `wall_m`: the board turns to face the gimbal base, so its centre stands
    gap + half width · sin(bearing) in front of the wall."""
    def path(t: float) -> F64:
        x = 1.0 * np.sin(TWO_PI * t / 6.0)
        lean = PERSON_HALF_W_M * abs(x) / float(np.hypot(x, wall_m))
        return np.array([x, CAMERA_HEIGHT_M - 0.85, wall_m - gap_m - lean])
    return path


def near_wall_scenario(gap_m: float, wall_m: float = 7.0, light: bool = False, frames: int = 300,
                       enter_s: float = 3.0) -> Scenario:
    """A person-sized target walking `gap_m` in front of a wall at `wall_m` from `enter_s` seconds on (the
    temporal model learns the wall's own deviation first), cameras still (issue 12 item 3); with `light`,
    the illumination steps and ramps of `illumination`."""
    return Scenario(f"near-wall-{gap_m:g}{'-light' if light else ''}",
                    f"person walking {gap_m:g} m in front of a wall at {wall_m:g} m, cameras still",
                    frames=frames, paths=((1, near_wall_path(wall_m, gap_m)),), enter_s=enter_s,
                    gain=_illumination_gain if light else _unity, wall_m=wall_m, person=True)


BODY_SUFFIX = ":body"
PLATE_SUFFIX = ":plate"


def split_name(name: str) -> tuple[str, str]:
    """A scenario name's base and its suffix (`:body`, `:plate` or ""); ValueError for an unknown base."""
    base, suffix = next(((name[:-len(s)], s) for s in (BODY_SUFFIX, PLATE_SUFFIX) if name.endswith(s)), (name, ""))
    if base not in SCENARIOS:
        raise ValueError(f"unknown scenario {name!r}; known: {', '.join(sorted(SCENARIOS))} "
                         f"(each also as NAME{BODY_SUFFIX} and NAME{PLATE_SUFFIX})")
    return base, suffix


def get_scenario(name: str) -> Scenario:
    """A scenario by name; `NAME:body` is scenario NAME with its targets drawn as solid bodies, `NAME:plate`
    (or NAME alone) with its targets as flat plates."""
    base, suffix = split_name(name)
    scenario = SCENARIOS[base]
    return replace(scenario, name=name, bodies=suffix == BODY_SUFFIX) if suffix else scenario


class SimFrame:
    """A rendered frame and its ground truth. The truth (projections, pixel centroids and areas of each
    object) is worked out when first asked for: a source that only shows the frames (the server's) does
    not pay for it."""

    def __init__(self, frame: StereoFrame, truth: Callable[[], FrameTruth]):
        self.frame = frame
        self._make: Callable[[], FrameTruth] | None = truth
        self._truth: FrameTruth | None = None

    @property
    def truth(self) -> FrameTruth:
        if self._truth is None:
            assert self._make is not None
            self._truth, self._make = self._make(), None
        return self._truth


class SimRig:
    """The simulated stereo rig as a frame source. Gimbal angles come from the scenario's schedule, or
    from `step(gimbal)` when a servo loop closes through the simulator. Deterministic for a seed.

    `index` counts the frames rendered since construction and the frames' times are index / fps (s), so
    they keep increasing when a finite scenario is looped with `rewind()`; the scene's own time restarts
    at each pass (`scene_t`). An endless scenario (`Scenario.script`) is never exhausted."""

    def __init__(self, scenario: Scenario, seed: int = 0, size: tuple[int, int] = (640, 480),
                 rig: StereoRig | None = None, noise_sigma: float = 1.2, edge_samples: int = 1):
        self.scenario = scenario
        self.rig = rig or default_rig(size)
        rng = np.random.default_rng(seed)
        static: list[Surface] = backdrop(rng)
        self._foliage = foliage(rng, np.array([-1.3, 1.0, 6.0]), 0.7, 0.5) if scenario.foliage else None
        textures = {1: plate_texture(rng), 2: plate_texture(rng, 150, 235)}
        self.objects: list[MovingObject | BodyObject] = [
            MovingObject(tid, path, 0.3, textures[min(tid, 2)]) for tid, path in scenario.paths]
        if scenario.wall_m is not None:
            static.append(near_wall(rng, scenario.wall_m))
        if scenario.person:
            self.objects = [MovingObject(tid, path, PERSON_HALF_W_M, person_texture(rng, 90, 215), half_h_m=0.85)
                            for tid, path in scenario.paths]
        self._body_rng = np.random.default_rng(seed + 31337)  # not `rng`: the plates' draws stay as they are
        # people's statures: drawn apart from the textures, and per scene (each scene its own people)
        self._stature_rng = np.random.default_rng([seed, 7127, zlib.crc32(scenario.name.split(":")[0].encode())])
        self._bodies: dict[int, tuple[MovingObject, BodyObject]] = {}  # endless: its objects as bodies
        if scenario.bodies:
            self.objects = [self._as_body(o) for o in self.objects]
        if scenario.enter_s > 0:
            for o in self.objects:
                o.visible = self._entered
        self.script = scenario.script(seed) if scenario.script is not None else None
        self.renderer = SimRenderer(self.rig, static, seed, noise_sigma, edge_samples)
        self.index = 0
        self._pass_start = 0  # index of the current pass's first frame
        self._last: SimFrame | None = None

    def _entered(self, t: float) -> bool:
        return t >= self.scenario.enter_s

    @property
    def exhausted(self) -> bool:
        """Whether the current pass has rendered all the scenario's frames (never, for an endless one)."""
        return self.script is None and self.index - self._pass_start >= self.scenario.frames

    @property
    def scene_t(self) -> float:
        """The scene time (s) of the next frame: seconds since the current pass started."""
        return (self.index - self._pass_start) / self.scenario.fps

    def rewind(self) -> None:
        """Start the scenario again at its first frame (to loop a finite scenario once `exhausted`): the
        objects, light and gimbal schedule restart, frame indices and times keep counting (a servo loop's
        clock never goes back), the renderer keeps its cache, the sensor noise goes on (not a bit-for-bit
        replay). For an endless scenario the same people come again."""
        self._pass_start = self.index

    def objects_at(self, t: float) -> list[MovingObject | BodyObject]:
        """The moving objects whose truth is reported at scene time t (s): all the scenario's paths, or the
        endless script's objects present at t (as bodies in a `NAME:body` scenario)."""
        if self.script is None:
            return self.objects
        present = self.script.present(t)
        return [self._as_body(o) for o in present] if self.scenario.bodies else list(present)

    def _as_body(self, obj: MovingObject | BodyObject) -> BodyObject:
        """A plate or person board as a solid body: id 1 of the scenario's first body kind, the others of
        its last (an endless scene's people stay people, its plates become spheres); kept per object."""
        if isinstance(obj, BodyObject):
            return obj
        known = self._bodies.pop(id(obj), None)
        if known is not None and known[0] is obj:
            self._bodies[id(obj)] = known  # the most recently used last: the oldest is forgotten first
            return known[1]
        kinds = self.scenario.body_kinds
        kind = "person" if obj.half_h_m is not None else kinds[0] if obj.target_id == 1 else kinds[-1]
        if self.scenario.script is not None and obj.half_h_m is None:
            kind = "sphere"
        stature = draw_stature(self._stature_rng) if kind == "person" else PERSON_STATURE_M
        body = BodyObject(obj.target_id, kind, obj.trajectory, body_texture(self._body_rng, kind), obj.visible,
                          stature)
        if len(self._bodies) > 64:  # forget the least recently used: those present keep texture and stature
            del self._bodies[next(iter(self._bodies))]
        self._bodies[id(obj)] = (obj, body)
        return body

    def background(self, gimbal: GimbalState | None = None) -> StereoFrame:
        """An empty-scene pair (no moving objects; foliage in its state at t = -1 s) at the given pose: what
        a survey would capture."""
        g = gimbal or self.scenario.gimbal(0.0)
        scenery = [self._foliage] if self._foliage is not None else []  # the bush is background too
        frame, _ = self.renderer.render(-1, -1.0, g, scenery, 1.0, right_gain=self.scenario.right_gain(0.0))
        return frame

    def step(self, gimbal: GimbalState | None = None) -> SimFrame:
        """Render the next frame; `gimbal` overrides the scenario's schedule (closed loop)."""
        i, ts = self.index, self.scene_t
        t = i / self.scenario.fps
        g = gimbal if gimbal is not None else self.scenario.gimbal(ts)
        R_wr = gimbal_rotation(g.pan_deg, g.tilt_deg)
        objects = self.objects_at(ts)
        moving = [o.surface(ts, R_wr) for o in objects if o.visible(ts)]
        if self._foliage is not None:
            moving.append(self._foliage)
        gain = self.script.gain(ts) if self.script is not None else self.scenario.gain(ts)
        frame, ids = self.renderer.render(i, t, g, moving, gain, right_gain=self.scenario.right_gain(ts))
        windows = tuple(self.renderer.windows)
        depth = self.renderer.depth_window(0) if any(isinstance(o, BodyObject) for o in objects) else None

        def truth() -> FrameTruth:
            return FrameTruth(t, g, tuple(self._truth(o, ts, R_wr, ids, windows, depth) for o in objects),
                              ids[0], ids[1])

        self.index += 1
        self._last = SimFrame(frame, truth)
        return self._last

    @property
    def last_truth(self) -> FrameTruth | None:
        """The truth of the last frame rendered (None before the first)."""
        return None if self._last is None else self._last.truth

    def read(self) -> StereoFrame | None:
        """FrameSource protocol: the next frame, None after the scenario's last."""
        return None if self.exhausted else self.step().frame

    def close(self) -> None:
        pass

    def _truth(self, obj: MovingObject | BodyObject, t: float, R_wr: F64, ids: list[NDArray[np.uint8]],
               windows: tuple[tuple[int, int, int, int] | None, ...],
               depth: tuple[tuple[int, int, int, int], NDArray[np.float32]] | None) -> TargetTruth:
        """Truth of one object at scene time t (s): its centre, projections, and its pixels' centroids and
        areas in each image (ids: the (left, right) id images, moving objects drawn only inside `windows`);
        visible fraction against area·(f/z)²; for a body, the mean point of the surface it shows the left
        camera and its silhouette's point (depth: that render's depth_window(0); Renderer.surface_mean)."""
        tid, world = obj.target_id, obj.trajectory(t)
        rig_p = R_wr.T @ world
        pl = self.rig.left.project(rig_p[None, :])[0]
        pr = self.rig.right.project(rig_p[None, :])[0]
        cents: list[F64 | None] = []
        areas = [0, 0]
        for k, img in enumerate(ids):
            win = windows[k]
            if win is None:
                cents.append(None)
                continue
            x0, y0, x1, y1 = win  # moving objects are only ever drawn inside this window
            m = cv2.moments((img[y0:y1, x0:x1] == tid).view(np.uint8), binaryImage=True)
            areas[k] = int(m["m00"])
            cents.append(np.array([m["m10"] / m["m00"] + x0, m["m01"] / m["m00"] + y0])
                         if m["m00"] > 0 else None)
        expected = obj.area_m2 * (self.rig.left.f / max(rig_p[2], 0.1)) ** 2
        near, surface, silhouette = 0.0, None, None
        if isinstance(obj, BodyObject):
            near = obj.near_depth_m(t, R_wr @ self.rig.left.c)
            seen = self.renderer.surface_mean(0, ids[0], tid, depth)
            surface = None if seen is None else R_wr @ seen
            ray = self.renderer.surface_mean(0, ids[0], tid, depth, on_mean_ray=True)
            silhouette = None if ray is None else R_wr @ ray
        return TargetTruth(tid, world, rig_p, pl, pr, cents[0], cents[1], areas[0],
                           min(areas[0] / expected, 1.0), areas[1], near, surface, silhouette)
