"""A simulated pan servo for closed-loop runs of the live robot loop without hardware.

:class:`ServoHead` speaks the head-driver protocol of :func:`hearsee.robot.hardware.run_robot`
(``pose_deg``, ``command(t, pan_deg, tilt_deg)``; see
:class:`hearsee.robot.hardware.PrintHeadDriver`) and turns toward the last commanded pan at a
fixed rate. Its clock is the audio's: whoever renders the audio moves it with :meth:`advance`
(e.g. at the end of each block, before the loop reads the block), so that the audio and the
head's poses agree -- ``bench/live_head.py`` renders each block from the talker's path in the
array's frame at :meth:`pan_at`.
"""

from __future__ import annotations

import numpy as np

from hearsee.config import finite_number
from hearsee.errors import ConfigError, GeometryError
from hearsee.geometry import wrap_deg


class ServoHead:
    """A pan-only head (tilt 0) turning toward the last commanded pan at ``rate_dps`` degrees
    per second of audio, the short way round, from ``pan_deg`` (robot frame, + = left).

    ``history`` holds ``(t, pan)`` at time 0 and at every :meth:`advance`; ``n_printed``
    counts the commands (as :class:`~hearsee.robot.hardware.PrintHeadDriver` does)."""

    def __init__(self, rate_dps: float, pan_deg: float = 0.0) -> None:
        self.rate_dps = finite_number("rate_dps", rate_dps, 0.0, lo_open=True)
        self.pan = float(wrap_deg(finite_number("pan_deg", pan_deg, error=GeometryError)))
        self.target: float | None = None
        self.t = 0.0
        self.history: list[tuple[float, float]] = [(0.0, self.pan)]
        self.n_printed = 0

    @property
    def pose_deg(self) -> tuple[float, float]:
        """The head's (pan, tilt) now, degrees."""
        return (self.pan, 0.0)

    def advance(self, t: float) -> None:
        """Move the clock to ``t`` seconds of audio (not before the last): the pan turns toward
        the target at ``rate_dps`` for the time elapsed and stops on it."""
        t = finite_number("t", t, error=ConfigError)
        if t < self.t:
            raise ConfigError(f"ServoHead.advance: t {t:g} s is before the head's clock "
                              f"{self.t:g} s")
        if self.target is not None:
            step = float(wrap_deg(self.target - self.pan))
            limit = self.rate_dps * (t - self.t)
            self.pan = float(wrap_deg(self.pan + np.clip(step, -limit, limit)))
        self.t = t
        self.history.append((t, self.pan))

    def pan_at(self, t: float) -> float:
        """The pan (degrees, unwrapped along the history) at ``t`` seconds: linear between the
        :meth:`advance` times -- the servo turns at a constant rate between them unless it
        reached its target -- and held outside them. ``t`` must be a finite number
        (ConfigError, as for :meth:`advance`: NaN read as a NaN pan)."""
        t = finite_number("t", t, error=ConfigError)
        ts, pans = np.array(self.history).T
        return float(np.interp(t, ts, np.unwrap(pans, period=360.0)))

    def command(self, t: float, pan_deg: float, tilt_deg: float) -> dict[str, float]:
        """The loop's desired pose (degrees); the pan becomes the target (the tilt is
        ignored: a pan-only head, but it must be a finite number too: GeometryError)."""
        pan = finite_number("pan_deg", pan_deg, error=GeometryError)
        tilt = finite_number("tilt_deg", tilt_deg, error=GeometryError)
        self.target = float(wrap_deg(pan))
        self.n_printed += 1
        return {"pan_deg": pan, "tilt_deg": tilt}
