"""Composition of a replay: the recording source (tmeye.runtime.recording) with a pipeline whose background is
learnt as the live runtime learnt it. A recording of the simulated rig (config.scenario set): the empty
scene of that scenario rendered at the same survey poses (the mount's range when the recording carries mount
poses, as with the simulated gimbal live). Otherwise the first recorded pair starts the background and the
stream's statistics refine it (tracker.bglearn), the rule of a real source. No servo: each frame carries its
recorded mount pose."""

from __future__ import annotations

from pathlib import Path

from tmeye.runtime.compose import ComposeError, Composition, pipeline, rig_errors
from tmeye.runtime.config import RuntimeConfig, TrackerTuning
from tmeye.runtime.recording import RecordingError, RecordingSource
from tracker.closedloop import background_range, survey_grid, widen_background
from tracker.closedloop_eval import mount_range
from tracker.evaluation import survey_poses
from tracker.geometry import StereoRig
from tracker.sim.scenarios import SimRig, get_scenario


def compose_recording(cfg: RuntimeConfig, tuning: TrackerTuning, rig: StereoRig | None) -> Composition:
    assert cfg.start is not None and cfg.end is not None
    if cfg.servo not in (None, "none"):
        raise ComposeError("a replay drives no servo: the recorded mount pose of each frame is used")
    try:
        src = RecordingSource(Path(cfg.inputs[0]), cfg.start, cfg.end)
    except RecordingError as exc:
        raise ComposeError(str(exc)) from None
    try:
        if cfg.scenario:
            return _sim_background(cfg, tuning, rig, src)
        return _first_pair_background(cfg, tuning, rig, src)
    except BaseException:
        src.close()
        raise


def _sim_background(cfg: RuntimeConfig, tuning: TrackerTuning, rig: StereoRig | None,
                    src: RecordingSource) -> Composition:
    try:
        scenario = get_scenario(cfg.scenario)
    except ValueError as exc:
        raise ComposeError(str(exc)) from None
    sim = SimRig(scenario, seed=cfg.seed)
    rig = rig or sim.rig
    if rig.left.size != sim.rig.left.size:
        raise ComposeError(f"the rig's image size {rig.left.size} is not the simulated scene's {sim.rig.left.size}")
    pipe = pipeline(rig, cfg, tuning, scenario.fps)
    if src.mount_poses():  # recorded with a mount (the simulated gimbal): its surveyed range, as live
        pan, tilt = mount_range(scenario)
        widen_background(pipe, *background_range(pan, tilt, rig.left.size, pipe.rect.f))
        poses = survey_grid(pan, tilt)
    else:
        poses = survey_poses(scenario)
    with rig_errors(cfg):
        for g in poses:
            pipe.learn_background(sim.background(g))
    return Composition(cfg, rig, src, pipe, None, None, None, None, scenario.fps)


def _first_pair_background(cfg: RuntimeConfig, tuning: TrackerTuning, rig: StereoRig | None,
                           src: RecordingSource) -> Composition:
    if rig is None:
        raise ComposeError("a replay of real cameras' recordings needs a rig (a rig file or calibration)")
    first = src.read()
    if first is None:
        raise ComposeError(f"no frame of both cameras was recorded between {cfg.start:.3f} and {cfg.end:.3f}")
    if first.left.shape[::-1] != rig.left.size:
        raise ComposeError(f"the recorded frames ({first.left.shape[1]}x{first.left.shape[0]}) are not the rig's "
                           f"size {rig.left.size[0]}x{rig.left.size[1]}")
    pipe = pipeline(rig, cfg, tuning, src.fps)
    poses = src.mount_poses()
    if poses:
        pan = (min(g.pan_deg for g in poses), max(g.pan_deg for g in poses))
        tilt = (min(g.tilt_deg for g in poses), max(g.tilt_deg for g in poses))
        widen_background(pipe, *background_range(pan, tilt, rig.left.size, pipe.rect.f))
    with rig_errors(cfg):
        pipe.learn_background_from_stream(first)
    return Composition(cfg, rig, src, pipe, None, None, None, None, src.fps)
