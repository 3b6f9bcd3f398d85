"""The assembly module: the spiral's geometry and the search's depth rule (maths, no physics) and
one whole assembly on the physics.

The physics test runs one centre-grasp episode (scene 0 of root seed 7, which assembles
without a new search) and watches the peg's axis in the tool frame
during the search: touch-downs do not rub, so the search tilt holds in the pads.
"""

from __future__ import annotations

import math
from dataclasses import replace
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

from vgs.assembly.contact import ContactPhases
from vgs.assembly.episode import EpisodeRunner, offset_policy
from vgs.assembly.spiral import GOLDEN_ANGLE, spiral_points
from vgs.config import profile


def take(points, n: int) -> np.ndarray:
    return np.array([next(points) for _ in range(n)])


def test_the_spiral_starts_at_the_centre_and_steps_about_step_apart() -> None:
    center = np.array([0.42, 0.22])
    pts = take(spiral_points(center, pitch=0.006, step=0.006, radius=0.02), 40)
    assert np.allclose(pts[0], center)
    r = np.linalg.norm(pts - center, axis=1)
    assert r.max() <= 0.02 + 1e-12
    # r = b theta: the radius grows monotonically until the spiral starts again.
    first_turn = r[: int(np.argmax(r)) + 1]
    assert np.all(np.diff(first_turn) > 0)
    gaps = np.linalg.norm(np.diff(pts[: len(first_turn)], axis=0), axis=1)
    # Half a turn from the centre to the second point (r = pitch / 2), then about a step apart.
    assert gaps[0] == pytest.approx(0.006 / 2, rel=1e-9)
    assert np.all(gaps[2:] > 0.5 * 0.006) and np.all(gaps < 1.2 * 0.006)


def test_a_repeated_spiral_starts_at_the_centre_turned_by_the_golden_angle() -> None:
    center = np.zeros(2)
    points = spiral_points(center, pitch=0.006, step=0.006, radius=0.01)
    pts = take(points, 60)
    restarts = [k for k in range(1, len(pts)) if np.allclose(pts[k], center)]
    assert restarts, "the spiral never came back to its centre"
    k = restarts[0]
    angle_first = math.atan2(pts[1, 1], pts[1, 0])
    angle_again = math.atan2(pts[k + 1, 1], pts[k + 1, 0])
    turn = (angle_again - angle_first) % (2 * math.pi)
    assert turn == pytest.approx(GOLDEN_ANGLE % (2 * math.pi), abs=1e-9)


def test_spiral_rejects_a_degenerate_spiral() -> None:
    with pytest.raises(ValueError):
        next(spiral_points(np.zeros(2), pitch=0.0, step=0.006, radius=0.02))


@pytest.mark.slow
def test_a_centre_grasp_assembles_and_the_search_keeps_the_tilt() -> None:
    runner = EpisodeRunner(profile("paper"))
    seed = int(np.random.SeedSequence([7, 0]).generate_state(1)[0])
    record, robot, _ = runner.run(seed, offset_policy(0.0), trace=True)
    assert record.success, record.failure_reason
    assert record.retries == 0
    assert 10.0 < record.assembly_time < 60.0
    # The recorded states replayed through MuJoCo's kinematics (ground truth, test only): the
    # peg's axis in the tool frame over the search.
    cell, trace = robot.cell, robot.trace
    data = mujoco.MjData(cell.model)
    turns: list[float] = []
    axis0 = None
    for phase, qpos in zip(trace.phase, trace.qpos, strict=True):
        if phase != "search":
            continue
        data.qpos[:] = qpos
        mujoco.mj_kinematics(cell.model, data)
        R_world_tcp = data.site_xmat[cell.ids.tcp_site].reshape(3, 3)
        axis = R_world_tcp.T @ data.xmat[cell.ids.peg_body].reshape(3, 3)[:, 2]
        axis0 = axis if axis0 is None else axis0
        turns.append(math.degrees(math.acos(float(np.clip(np.dot(axis, axis0), -1.0, 1.0)))))
    assert turns, "no search ticks recorded"
    assert max(turns) < 1.0  # deg: nothing rubs, so the peg keeps its tilt in the pads


@pytest.mark.slow
def test_a_grasp_whose_jaws_lie_off_the_axis_still_inserts() -> None:
    """Jaws 6 deg off the peg's axis: the pads lock that angle in, so the peg stands leaning
    across the pinch axis, which the wiggle does not turn. The insertion's force control in
    rotation lets the hole stand it up (it jammed with the stiffness of the other phases)."""
    runner = EpisodeRunner(profile("paper"))
    centre = offset_policy(0.0)

    def turned(hm):
        command = centre(hm)
        return replace(command, yaw=command.yaw + math.radians(6.0))

    record, robot, _ = runner.run(0, turned)
    assert record.success, record.failure_reason
    assert record.final_tilt_deg < 2.0  # ground truth: it ends upright in the hole


class _Arm:
    def __init__(self) -> None:
        self.R_ref = np.eye(3)

    def tcp_height(self) -> float:
        return 0.100  # the approach's plane contact [m]


class _Search(ContactPhases):
    """The search's decision rule on scripted touch-down heights (no physics): each call of
    ``_touch_down`` returns the next height; ``landed`` counts them."""

    def __init__(self, heights: list[float]) -> None:
        self.robot = SimpleNamespace(arm=_Arm())
        self.cfg = profile("paper").assembly
        self.nominal_hole_xy = np.zeros(2)
        self.low_rim_from_tcp = np.zeros(3)
        self.retries = 0
        self._heights = iter(heights)
        self.landed = 0

    def _touch_down(self, tcp_xy: np.ndarray) -> float:
        self.landed += 1
        return next(self._heights)

    def _check_timeout(self, phase: str) -> None:
        pass


def test_a_touch_down_is_deep_against_its_neighbours_on_the_plane() -> None:
    # The plane's TCP height rises 0.3 mm over the search (the peg turns in the pads), then one
    # touch-down sinks 0.4 mm below its neighbours: 0.1 mm below the approach's plane contact,
    # but 0.7 mm below the plane where it lands.
    rising = [0.100 + 0.00003 * k for k in range(1, 11)]
    search = _Search([*rising, rising[-1] - 0.0007, 0.0])
    search.search()
    assert search.landed == 11
    assert search.z_plane == pytest.approx(rising[-1])


def test_touch_downs_sunk_in_a_row_do_not_lower_the_plane() -> None:
    # The spiral's first points lie in the hole and sink 0.2-0.4 mm each (the face resting on
    # the edge), more than the window holds: the plane stays the approach's contact, and the
    # touch-down 0.6 mm below it is two-point contact.
    sunk = [0.1000 - d for d in (0.0003, 0.0002, 0.0004, 0.0003, 0.0002, 0.0004, 0.0003)]
    search = _Search([*sunk, 0.0994, 0.0])
    search.search()
    assert search.landed == len(sunk) + 1
    assert search.z_plane == pytest.approx(0.100)


def test_one_touch_down_on_something_higher_does_not_make_the_plane() -> None:
    # A touch-down 0.8 mm high (an edge, a burr) is not taken for the plane: the touch-downs on
    # the plane after it are not taken for a drop.
    search = _Search([0.100, 0.100, 0.1008, 0.100, 0.100, 0.100, 0.0994])
    search.search()
    assert search.landed == 7  # only the last, 0.6 mm below the plane
    assert search.z_plane == pytest.approx(0.100)
