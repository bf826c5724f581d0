"""Pan-tilt head kinematics in hearsee.geometry (thesis ch. 4, fig. 4.1)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hearsee.audio.arrays import MicArray
from hearsee.errors import GeometryError
from hearsee.geometry import (
    HeadPose,
    array_to_robot,
    as_pose,
    direction_deg,
    head_rotation,
    mic_positions_at,
    robot_to_array,
    unit_vector_deg,
)

angles = st.floats(-180.0, 180.0)
tilts = st.floats(-90.0, 90.0)
coords = st.floats(-3.0, 3.0)
vec = st.tuples(coords, coords, coords)


def test_pan_turns_left_and_tilt_looks_up():
    x = np.array([1.0, 0.0, 0.0])
    np.testing.assert_allclose(head_rotation(90, 0).apply(x), [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(head_rotation(-90, 0).apply(x), [0, -1, 0], atol=1e-12)
    # +tilt raises the gaze (opposite to REP 103's right-hand rotation about +y, which is nose-down)
    np.testing.assert_allclose(head_rotation(0, 30).apply(x), unit_vector_deg(0, 30), atol=1e-12)
    assert head_rotation(0, 30).apply(x)[2] > 0
    # tilt is about the *panned* y axis: gaze azimuth stays = pan
    np.testing.assert_allclose(head_rotation(60, 20).apply(x), unit_vector_deg(60, 20), atol=1e-12)
    # the head's y axis stays horizontal under tilt (no roll)
    assert head_rotation(60, 20).apply([0, 1, 0])[2] == pytest.approx(0.0, abs=1e-12)


@given(angles, tilts)
def test_gaze_is_pan_tilt_direction(pan, tilt):
    pose = HeadPose(pan, tilt)
    az, el = direction_deg(pose.gaze)
    assert float(el) == pytest.approx(tilt, abs=1e-7)
    if abs(tilt) < 89.9:
        d = (float(az) - pan + 180.0) % 360.0 - 180.0
        assert d == pytest.approx(0.0, abs=1e-6)


@settings(max_examples=60)
@given(angles, tilts, vec, vec, vec)
def test_robot_array_round_trip(pan, tilt, p, pivot, offset):
    pts = np.array([p, [0.1, -0.2, 0.3]])
    r = array_to_robot(pts, (pan, tilt), pivot, offset)
    back = robot_to_array(r, HeadPose(pan, tilt), pivot, offset)
    np.testing.assert_allclose(back, pts, atol=1e-6)
    # rigid motion: distances preserved
    assert np.linalg.norm(r[0] - r[1]) == pytest.approx(np.linalg.norm(pts[0] - pts[1]), rel=1e-9)


@settings(max_examples=40)
@given(angles, tilts, vec)
def test_tdoa_invariant_to_joint_motion(pan, tilt, src):
    """TDOAs of the moved array for a robot-frame source equal the array-frame ones."""
    arr = MicArray.from_preset("three-mic")
    pivot, offset = np.array([0.0, 0.0, 1.0]), np.array([0.05, 0.0, 0.1])
    s_robot = np.array(src) + [5.0, 0.0, 0.0]
    mics = mic_positions_at(arr, (pan, tilt), pivot, offset)
    moved = MicArray(mics)
    s_array = robot_to_array(s_robot, (pan, tilt), pivot, offset)
    np.testing.assert_allclose(moved.tdoa(s_robot), arr.tdoa(s_array), atol=1e-12)


def test_pivot_offset_moves_array_centre():
    arr = MicArray.from_preset("three-mic")
    off = [0.10, 0.0, 0.0]
    c0 = mic_positions_at(arr, (0, 0), offset_m=off).mean(axis=0)
    c90 = mic_positions_at(arr, (90, 0), offset_m=off).mean(axis=0)
    np.testing.assert_allclose(c0, [0.1, 0, 0], atol=1e-6)
    np.testing.assert_allclose(c90, [0, 0.1, 0], atol=1e-6)
    # no offset: the centre stays at the pivot
    np.testing.assert_allclose(
        mic_positions_at(arr, (45, 20), pivot_m=[0, 0, 1]).mean(axis=0), [0, 0, 1], atol=1e-6
    )


def test_bad_poses():
    with pytest.raises(GeometryError):
        HeadPose(0.0, 120.0)
    with pytest.raises(GeometryError):
        HeadPose(float("nan"), 0.0)
    with pytest.raises(GeometryError):
        HeadPose("a", 0.0)  # type: ignore[arg-type]
    with pytest.raises(GeometryError):
        as_pose((1.0, 2.0, 3.0))
    with pytest.raises(GeometryError):
        mic_positions_at(np.zeros((3, 2)), (0, 0))
    with pytest.raises(GeometryError):
        array_to_robot([0, 0, 0], (0, 0), pivot_m=[0, 0])
