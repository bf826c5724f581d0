"""render_scene(view=...): the scene seen from a turned camera (used by the robot pipeline)."""

import numpy as np
import pytest

from hearsee.sim.scenes import Entity, SceneSpec, default_rig, render_scene


def _yaw(deg: float) -> np.ndarray:
    """Optical-frame rotation of a camera turned ``deg`` to the left about the vertical."""
    a = np.radians(deg)
    # scene-frame vectors -> camera frame for a camera whose optical axis is rotated by +deg
    # toward -x (left) about the y (down) axis
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def test_turned_camera_centres_an_off_axis_person():
    rig = default_rig(320, 240, camera_height_m=1.3)
    person = Entity("person", x=-2.0, z=2.0, yaw_deg=-45.0, height_m=1.75)
    spec = SceneSpec(entities=[person], width_left_m=4, width_right_m=4, depth_m=6, back_m=3,
                     camera_height_m=1.3, seed=1)
    straight = render_scene(spec, rig)
    assert straight.objects[0].box is None  # 45 deg left: outside the 32.6 deg half field of view
    turned = render_scene(spec, rig, view=(_yaw(45.0), np.zeros(3)))
    obj = turned.objects[0]
    assert obj.box is not None
    x, y, w, h = obj.box
    assert abs((x + w / 2) - rig.left.width / 2) < 0.1 * rig.left.width
    # position in the turned camera frame: straight ahead at the true range
    assert obj.position_m[0] == pytest.approx(0.0, abs=0.05)
    assert obj.position_m[2] == pytest.approx(np.hypot(2.0, 2.0), abs=0.05)
    # ground-truth disparity along the optical axis: f B / Z at the torso
    d = turned.disparity[int(y + 0.4 * h), int(x + w / 2)]
    assert d == pytest.approx(rig.focal_px * rig.baseline_m / np.hypot(2, 2), rel=0.1)


def test_identity_view_is_the_default():
    spec = SceneSpec(entities=[Entity("person", 0.3, 3.0)], seed=2)
    rig = default_rig(160, 120)
    a = render_scene(spec, rig)
    b = render_scene(spec, rig, view=(np.eye(3), np.zeros(3)))
    assert np.array_equal(a.left, b.left) and np.array_equal(a.disparity, b.disparity)


@pytest.mark.parametrize("view", [
    (np.diag([1.0, 1.0, -1.0]), np.zeros(3)),  # a mirror, not a rotation
    (2.0 * np.eye(3), np.zeros(3)),  # a scale
    (np.eye(3), [np.nan, 0.0, 0.0]),
    (np.eye(2), np.zeros(3)),
    (np.eye(3), np.zeros(2)),
])
def test_a_bad_view_is_a_geometry_error(view):
    """A NaN centre or a wrongly shaped R/C let numpy's ValueError escape; a mirror or a scale
    for R was rendered as given (the docstring says R rotates), with wrong ground truth."""
    from hearsee.errors import GeometryError

    spec = SceneSpec(entities=[Entity("person", 0.3, 3.0)], seed=2)
    with pytest.raises(GeometryError, match="view"):
        render_scene(spec, default_rig(160, 120), view=view)


def test_a_raised_view_reports_the_height_it_was_rendered_at():
    """A view raising the camera 0.3 m (C_y = -0.3, y down) rendered from 1.7 m while the
    truth and the returned rig said spec.camera_height_m = 1.4. The floor's height in the
    left optical frame is the bottom of a box standing on it."""
    rig = default_rig(160, 120, thermal_size=(40, 30))
    spec = SceneSpec(entities=[Entity("box", 0.0, 3.0, 0.0, 0.5)], seed=1)
    s = render_scene(spec, rig, view=(np.eye(3), np.array([0.0, -0.3, 0.0])))
    floor_y = s.objects[0].position_m[1] + 0.25
    assert floor_y == pytest.approx(1.7)
    assert s.truth()["camera_height_m"] == pytest.approx(floor_y)
    assert s.rig.camera_height_m == pytest.approx(floor_y)


@pytest.mark.parametrize("centre, camera", [
    ([0.0, -2.0, 0.0], "left"),  # 3.4 m up under a 2.8 m ceiling
    ([0.0, 1.5, 2.0], "left"),  # under the floor
    ([0.0, 0.0, -2.0], "left"),  # behind the back wall (0.5 m behind the origin)
    ([5.0, 0.0, 3.0], "left"),  # beyond the right wall (4 m)
    ([0.0, 0.0, 12.0], "left"),  # beyond the far wall (10 m)
    ([3.95, 0.0, 3.0], "right"),  # the left camera in, the right one 0.07 m through the wall
])
def test_a_view_with_a_camera_outside_the_room_is_a_geometry_error(centre, camera):
    """A camera centre outside the room was rendered: the walls seen from behind, a person
    'seen' through them, ground truth for a picture no camera in the room takes. (The room:
    x in [-4, 4], y in [-1.4, 1.4] (ceiling 2.8 m, camera 1.4 m, y down), z in [-0.5, 10].)"""
    from hearsee.errors import GeometryError

    spec = SceneSpec(entities=[Entity("person", 0.3, 3.0)], seed=2)
    with pytest.raises(GeometryError, match=f"the {camera} camera's centre .* outside the room"):
        render_scene(spec, default_rig(160, 120), view=(np.eye(3), np.array(centre)))


def test_a_view_on_the_room_s_boundary_is_rendered():
    """Inside the room, its walls included (a camera against the back wall), is rendered."""
    spec = SceneSpec(entities=[Entity("person", 0.3, 3.0)], seed=2)
    for centre in ([0.0, 0.0, -0.5], [-4.0, 1.3, 0.0], [3.0, -1.3, 9.0]):
        s = render_scene(spec, default_rig(160, 120), view=(np.eye(3), np.array(centre)))
        assert np.all(np.isfinite(s.disparity)) and np.all(s.disparity > 0)


def test_pitched_view_looks_up_by_its_angle():
    """pitched_view(p): the camera pitched p deg up (no roll). A person's torso 3 m ahead at
    camera height, seen level on the optical axis, lies p deg below the pitched axis, at the
    same range; the up vector is (0, -cos p, sin p). Bad pitches are a GeometryError."""
    from hearsee.errors import GeometryError
    from hearsee.sim.scenes import pitched_view

    R, C = pitched_view(20.0)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0) and C.tolist() == [0.0, 0.0, 0.0]
    a = np.radians(20.0)
    np.testing.assert_allclose(R @ [0.0, -1.0, 0.0], [0.0, -np.cos(a), np.sin(a)], atol=1e-12)
    rig = default_rig(320, 240, camera_height_m=1.3)
    spec = SceneSpec(entities=[Entity("person", x=0.0, z=3.0, yaw_deg=0.0, height_m=1.75)],
                     width_left_m=3, width_right_m=3, depth_m=6, camera_height_m=1.3, seed=1)
    level = render_scene(spec, rig).objects[0].position_m
    up = render_scene(spec, rig, view=pitched_view(20.0)).objects[0].position_m
    np.testing.assert_allclose(up, R @ level, atol=1e-9)
    assert np.linalg.norm(up) == pytest.approx(np.linalg.norm(level))
    below = np.degrees(np.arctan2(up[1], up[2])) - np.degrees(np.arctan2(level[1], level[2]))
    assert below == pytest.approx(20.0, abs=1e-6)  # (y down: the torso is 20 deg lower)
    for bad in (np.nan, 85.0, "10"):
        with pytest.raises(GeometryError, match="pitch_deg"):
            pitched_view(bad)
