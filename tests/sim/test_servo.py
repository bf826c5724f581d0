import numpy as np
import pytest

from hearsee.errors import ConfigError, GeometryError
from hearsee.sim.servo import ServoHead


def test_servo_turns_toward_the_command_at_its_rate_the_short_way():
    """30 deg/s from 170 deg toward -170 (20 deg away across the seam, not 340 the long way):
    15 deg after 0.5 s, on target after 1 s and held there; pan_at interpolates the history
    (unwrapped across the seam)."""
    head = ServoHead(30.0, 170.0)
    head.advance(0.2)  # (no command yet: it stays)
    assert head.pose_deg == (170.0, 0.0)
    assert head.command(0.2, -170.0, 5.0) == {"pan_deg": -170.0, "tilt_deg": 5.0}
    head.advance(0.7)
    assert head.pose_deg[0] == pytest.approx(-175.0)
    head.advance(1.5)
    assert head.pose_deg == (-170.0, 0.0) and head.n_printed == 1
    assert head.pan_at(0.45) == pytest.approx(177.5)
    assert head.pan_at(1.1) == pytest.approx(187.5)  # (185 -> 190 over 0.7-1.5 s, unwrapped)
    assert head.pan_at(-1.0) == 170.0 and np.isclose(head.pan_at(9.0) % 360.0, 190.0)


@pytest.mark.parametrize("call, error, words", [
    (lambda: ServoHead(0.0), ConfigError, "rate_dps"),
    (lambda: ServoHead(float("nan")), ConfigError, "rate_dps"),
    (lambda: ServoHead(30.0, float("inf")), GeometryError, "pan_deg"),
    (lambda: ServoHead(30.0).command(0.0, float("nan"), 0.0), GeometryError, "pan_deg"),
    (lambda: ServoHead(30.0).advance(float("nan")), ConfigError, "t must be"),
    # (a NaN time read as a NaN pan, text as a time; a None tilt was float()'s TypeError)
    (lambda: ServoHead(30.0).pan_at(float("nan")), ConfigError, "t must be"),
    (lambda: ServoHead(30.0).pan_at("0.1"), ConfigError, "t must be"),
    (lambda: ServoHead(30.0).command(0.0, 10.0, None), GeometryError, "tilt_deg"),
    (lambda: ServoHead(30.0).command(0.0, 10.0, float("nan")), GeometryError, "tilt_deg"),
])
def test_servo_refuses_bad_numbers(call, error, words):
    with pytest.raises(error, match=words):
        call()


def test_servo_clock_does_not_run_backwards():
    head = ServoHead(30.0)
    head.advance(1.0)
    with pytest.raises(ConfigError, match="before the head's clock"):
        head.advance(0.5)
