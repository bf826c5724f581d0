"""Kalman filter on the ITD state vector (thesis 2.2.2) with innovation gating.

State ``s_n`` = the N-1 ITDs relative to a reference microphone ``ref``:
``s = [t_k - t_ref for k != ref]`` (seconds). Thesis model:

    prediction   s_{n+1} = s_n + w_n,     w_n ~ N(0, Q_s)      (random walk, F = I)
    measurement  z_n     = H s_n + v_n,   v_n ~ N(0, R)

In the thesis ``z_n`` are the N-1 reference-pair ITDs and ``H = I``. Here the measurement may be
any set of pairs (by default all of them): pair (i, j) measures ``t_i - t_j = s_i - s_j`` (with
``s_ref = 0``), so ``H`` has a +1 and a -1 per row -- the redundant pairs of a 3-microphone array
then all inform the state. Every other pair's TDOA follows from the state (:meth:`pair_tdoas`).

Reconstruction addition (the thesis's text stops before its gating): **innovation gating**. The
squared Mahalanobis distance of the innovation ``y = z - H x``, ``d2 = y^T S^-1 y`` with
``S = H P H^T + R``, is chi-square distributed with ``dim z`` degrees of freedom for a correct
measurement; measurements with ``d2`` above the ``gate_prob`` quantile are rejected as anomalous
GCC peaks (predict only), as in Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to
Tracking and Navigation* (2001), sec. 5.7 (validation gate). After ``max_rejects`` consecutive
rejections the filter re-initialises on the measurement (the source moved or the state is stale).
Missing frames (None or NaN) are predicted only.

The filter is filterpy's :class:`filterpy.kalman.KalmanFilter`, with the textbook names ``x``,
``P``, ``F``, ``H``, ``Q``, ``R`` available on :attr:`ItdKalman.kf` (``R`` set by hand is the
base measurement noise from the next step on, which per-frame scales multiply).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from filterpy.kalman import KalmanFilter
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from hearsee.audio.arrays import MAX_MICS, check_pairs, pair_matrix
from hearsee.audio.localize import as_tdoas, check_real_tdoas, check_tdoa_magnitude
from hearsee.config import is_real, real_entries, whole_number
from hearsee.errors import ConfigError, EstimationError, GeometryError

__all__ = ["ItdKalman", "confidence_r_scale", "max_itd_step_s", "pair_matrix",
           "itd_filter_entries", "smooth_recording_itds", "tune_itd_noise"]

#: :func:`tune_itd_noise`'s grids, in samples at the recording's rate: the random walk's
#: standard deviation per frame (q) and the measurement's (r)
TUNE_Q_SAMPLES = (0.03, 0.1, 0.3, 1.0, 3.0)
TUNE_R_SAMPLES = (0.3, 1.0, 3.0)
#: :meth:`ItdKalman.log_likelihood`'s share of anomalous measurements (GCC peaks of a
#: reflection or of noise), uniform over the pairs' lag box
OUTLIER_PROB = 0.1
#: :func:`max_itd_step_s`: the fastest turn about the array (deg/s) whose ITD change per frame
#: ``hearsee localize`` lets its tuned random walk allow (a person walking 1.5 m/s past at 1 m)
TUNE_MAX_RATE_DPS = 90.0
#: :func:`confidence_r_scale`: the GCC confidence's margin ``c - 1`` (``c`` the
#: peak-to-second-peak ratio) at which a frame's measurement noise is the filter's ``r_std_s``
#: (``c`` = 1.3), and the range of the scale
CONFIDENCE_R_REF = 0.3
CONFIDENCE_R_RANGE = (0.1, 10.0)


def confidence_r_scale(confidence: ArrayLike) -> NDArray:
    """Per-frame, per-pair scale of the ITD filter's measurement noise from the GCC's
    confidence ``c`` (peak-to-second-peak ratio, :attr:`hearsee.audio.tdoa.TdoaFrames.confidence`,
    (n_frames, n_pairs)): ``sqrt(CONFIDENCE_R_REF / (c - 1))`` clipped to
    :data:`CONFIDENCE_R_RANGE` -- a peak barely above the next one (a reflection's or the
    noise's rival peak) is a measurement to trust little, a peak that stands alone one to
    follow closely. Frames without a peak (``c`` <= 1, NaN) get the largest scale.

    Why: one measurement noise cannot serve every frame. On simulated moving and static
    sources (three-mic, RT60 0.3 s, male voice, dev seeds 60/61, 3132 frame-pairs) the per-frame
    error grew steadily as the confidence fell: RMS 1.3, 2.0, 2.5, 3.0 and 3.7 samples over its
    quintiles (c from 4.2 down to 1.0), and half the frames of the lowest quintile were more
    than 2 samples off, against 8 % of the highest. The scale's form (the error's standard
    deviation falling with the square root of the peak's margin over its rival) is our
    construction; per-measurement noise from the estimator's own quality is the adaptive
    measurement noise of the tracking literature (Bar-Shalom, Li & Kirubarajan 2001, ch. 11)."""
    if not real_entries(confidence):  # (text was numpy's ValueError, None the largest scale)
        raise ConfigError(f"confidence must be numbers (GCC peak-to-second-peak ratios), got "
                          f"{confidence!r:.60}")
    c = np.asarray(confidence, dtype=float)
    lo, hi = CONFIDENCE_R_RANGE
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.sqrt(CONFIDENCE_R_REF / (c - 1.0))
    return np.where(np.isfinite(s) & (c > 1.0), np.clip(s, lo, hi), hi)


def _frames(Z: ArrayLike) -> NDArray:
    """Frames of pair TDOAs ``Z`` as a float (n_frames, n_pairs) array, or a GeometryError (text
    was read as seconds and True as 1 s, which :meth:`ItdKalman.step` refuses)."""
    check_real_tdoas(Z)
    Zm = np.asarray(Z, dtype=float)
    if Zm.ndim != 2:
        raise GeometryError(f"expected (n_frames, n_pairs) TDOAs, got shape {Zm.shape}")
    return Zm


def max_itd_step_s(max_tdoa_s: ArrayLike, hop_s: float,
                   rate_dps: float = TUNE_MAX_RATE_DPS) -> float:
    """The largest change (s) of any pair's ITD over one hop of ``hop_s`` seconds while the
    source turns about the array at ``rate_dps`` deg/s: a pair's far-field ITD is
    ``max_tdoa cos(theta)``, whose rate is at most ``max_tdoa * omega``. ``max_tdoa_s``: the
    pairs' largest TDOAs (s). :func:`tune_itd_noise`'s ``q_max_s`` in
    :func:`hearsee.audio.localize.localize_recording`: a random walk allowed to move faster
    explained a reverberant voice's bursts of reflection peaks as motion (RT60 0.3 s, male
    voice at 90 deg/s, 20 dB: q of one sample per frame picked, 80 us per-frame RMSE where a
    third of a sample gave 57)."""
    m = np.asarray(max_tdoa_s, dtype=float) if real_entries(max_tdoa_s) else np.zeros(0)
    if not (m.size and np.all(np.isfinite(m) & (m > 0))):  # (text: numpy's ValueError)
        raise GeometryError(f"max_tdoa_s must be finite numbers > 0 seconds, got "
                            f"{max_tdoa_s!r:.80}")
    if not all(is_real(v) and v > 0 for v in (hop_s, rate_dps)):
        raise ConfigError(f"hop_s and rate_dps must be numbers > 0, got {hop_s!r}, {rate_dps!r}")
    return float(np.max(m) * np.radians(rate_dps) * hop_s)


#: :class:`ItdKalman`'s standard deviations (``q_std_s``, ``r_std_s``, ``p0_std_s``) lie within
#: these bounds (seconds): a nanosecond is a thousandth of a sample at 1 MHz, and their squares
#: stay normal floats
ITD_STD_RANGE_S = (1e-9, 1.0)
#: A frame's measurement-noise scale (``r_scale``) lies within these bounds
R_SCALE_RANGE = (1e-6, 1e6)


def _scales(r_scale: ArrayLike | None, shape: tuple[int, ...]) -> NDArray | None:
    """``r_scale`` as a float array of ``shape`` ((n_frames, n_pairs), or (n_pairs,) for one
    frame), finite and > 0, or None; a ConfigError otherwise."""
    if r_scale is None:
        return None
    s = np.asarray(r_scale, dtype=float) if real_entries(r_scale) else None
    lo, hi = R_SCALE_RANGE
    if s is None or s.shape != shape or not np.all((s >= lo) & (s <= hi)):
        # (1e-200 made R singular: numpy's LinAlgError)
        what = "one per frame and pair" if len(shape) == 2 else "one per pair"
        raise ConfigError(f"r_scale must be numbers from {lo:g} to {hi:g} of shape {shape} "
                          f"({what}), got {r_scale!r:.80}")
    return s


def _size(z: ArrayLike) -> int | None:
    """How many numbers ``z`` holds (None for a ragged nesting)."""
    try:
        return int(np.size(z))
    except ValueError:
        return None


class ItdKalman:
    """Random-walk Kalman filter on the N-1 reference ITDs with chi-square innovation gating.

    Parameters
    ----------
    n_mics : int
        Number of microphones N (state dimension N-1).
    pairs : list of (i, j), optional
        Pairs measured in each :meth:`step` (default: all ``i < j``).
    ref : int
        Reference microphone.
    q_std_s : float
        Random-walk standard deviation per step, seconds (``Q_s = q_std_s^2 I``).
    r_std_s : float
        Measurement standard deviation per pair, seconds (``R = r_std_s^2 I``).
    gate_prob : float
        Probability mass of the validation gate (0.99 -> reject ~1 % of correct measurements).
    max_rejects : int
        Consecutive rejections after which the filter re-initialises on the measurement (>= 1).
    p0_std_s : float
        State standard deviation before the first measurement, seconds (``P = p0_std_s^2 I``
        until then; the first measurement sets the state and its covariance by least squares
        over the pairs, whatever ``p0_std_s``).

    Examples
    --------
    >>> kf = ItdKalman(3, q_std_s=1e-5, r_std_s=2e-5)
    >>> for _ in range(5):
    ...     _ = kf.step([1e-4, 2e-4, 1e-4])          # pairs 0-1, 0-2, 1-2
    >>> np.round(kf.pair_tdoas() * 1e6)              # microseconds
    array([100., 200., 100.])
    """

    def __init__(self, n_mics: int, pairs: Sequence[tuple[int, int]] | None = None, ref: int = 0,
                 q_std_s: float = 2e-5, r_std_s: float = 3e-5, gate_prob: float = 0.99,
                 max_rejects: int = 5, p0_std_s: float = 1e-3) -> None:
        # (not numbers: TypeErrors from numpy or range(); ref=1.5 was truncated to 1)
        n_mics = whole_number("n_mics", n_mics, lo=2, hi=MAX_MICS, error=GeometryError)
        ref = whole_number("ref", ref, lo=0, hi=n_mics - 1, error=GeometryError)
        # (pairs: check_pairs; (0.7, 1.9) was truncated to (0, 1))
        pairs = None if pairs is None else check_pairs(pairs, n_mics)
        lo, hi = ITD_STD_RANGE_S
        if not all(is_real(v) and lo <= v <= hi for v in (q_std_s, r_std_s, p0_std_s)):
            # (NaN passed "<= 0": NaN TDOAs, or an SVD that did not converge; 1e-200 squared to
            # a singular R -- numpy's LinAlgError -- and 1e200 overflowed)
            raise ConfigError(f"q_std_s, r_std_s and p0_std_s must be numbers from {lo:g} to "
                              f"{hi:g} seconds, got {q_std_s}, {r_std_s}, {p0_std_s}")
        if not (is_real(gate_prob) and 0 < gate_prob < 1):
            raise ConfigError(f"gate_prob must be in (0, 1), got {gate_prob}")
        self.n_mics = int(n_mics)
        self.ref = int(ref)
        self.pairs = ([(i, j) for i in range(n_mics) for j in range(i + 1, n_mics)]
                      if pairs is None else pairs)
        self.p0_std_s = float(p0_std_s)
        # (0 or less re-initialised on every rejected measurement: no gate at all)
        self.max_rejects = whole_number("max_rejects", max_rejects, lo=1)
        dim_x, dim_z = self.n_mics - 1, len(self.pairs)
        H = pair_matrix(self.n_mics, self.pairs, self.ref)
        if np.linalg.matrix_rank(H) < dim_x:
            raise GeometryError("the measured pairs do not determine all N-1 ITDs")
        kf = KalmanFilter(dim_x=dim_x, dim_z=dim_z)
        kf.F = np.eye(dim_x)
        kf.H = H
        kf.Q = np.eye(dim_x) * q_std_s**2
        kf.R = np.eye(dim_z) * r_std_s**2
        self._R0 = kf.R.copy()  # (the base measurement noise that per-frame scales multiply)
        self._R_set = kf.R.copy()  # (what _step last put in kf.R: a hand edit differs from it)
        kf.P = np.eye(dim_x) * p0_std_s**2
        self.kf = kf
        self.gate = float(chi2.ppf(gate_prob, dim_z))
        self.initialized = False
        self.n_inits = 0  # (first measurement and re-initialisations: where smooth() cuts)
        self.n_rejected = 0
        self._run = 0
        self.last_d2 = float("nan")
        self.last_logdet_s = float("nan")
        self.last_accepted = False

    # textbook views
    @property
    def x(self) -> NDArray:
        """State: ``t_k - t_ref`` for k != ref, seconds. An EstimationError before the first
        measurement (:attr:`initialized`): there is no estimate yet (the prior's zeros read
        as a source at broadside)."""
        if not self.initialized:
            raise EstimationError("the ITD filter has no state before its first measurement")
        return self.kf.x.reshape(-1)

    @property
    def P(self) -> NDArray:
        """State covariance, seconds^2."""
        return self.kf.P

    def pair_tdoas(self, pairs: Sequence[tuple[int, int]] | None = None) -> NDArray:
        """TDOAs ``t_i - t_j`` (seconds) of any pairs, from the state; an EstimationError
        before the first measurement (see :attr:`x`)."""
        prs = self.pairs if pairs is None else list(pairs)
        return pair_matrix(self.n_mics, prs, self.ref) @ self.x

    def _init_from(self, z: NDArray) -> None:
        """The state from one measurement ``z`` by least squares over the pairs, weighted by
        the frame's measurement noise ``kf.R`` -- the estimate whose covariance is the
        ``P = (H^T R^-1 H)^-1`` it gets. (Until 2026-12-08 the fit was unweighted whatever
        the frame's per-pair noise: with ``r_scale`` (0.1, 10, 10) a well-measured pair's
        TDOA took the others' errors, 4.7 samples where P said 0.1 -- the next frames were
        rejected and the filter re-initialised over and over.)"""
        H, R = self.kf.H, self.kf.R
        if np.array_equal(R, R[0, 0] * np.eye(len(R))):  # (one noise for all: unweighted)
            x, *_ = np.linalg.lstsq(H, z, rcond=None)
        else:  # (whitened by R's Cholesky factor)
            L = np.linalg.cholesky(R)
            x, *_ = np.linalg.lstsq(np.linalg.solve(L, H), np.linalg.solve(L, z), rcond=None)
        self.kf.x = x.reshape(-1, 1)
        self.kf.P = np.linalg.pinv(H.T @ np.linalg.inv(R) @ H)
        self.initialized = True
        self._run = 0
        self.n_inits += 1

    def _r_for(self, sc: NDArray | None) -> NDArray:
        """The measurement noise (seconds^2) of a frame whose scales are ``sc`` (n_pairs,)
        or None."""
        return self._R0 if sc is None else self._R0 * np.outer(sc, sc)

    def _set_r(self, sc: NDArray | None) -> None:
        """``kf.R`` for a frame whose measurement scales are ``sc`` (n_pairs,) or None."""
        self.kf.R = self._r_for(sc)
        self._R_set = self.kf.R.copy()

    def _adopt_hand_set_r(self) -> None:
        """A ``kf.R`` set by hand since the last step (filterpy's textbook name, which the
        module offers) becomes the base measurement noise from now on -- per-frame scales
        multiply it -- instead of being overwritten by the next step's (until 2026-12-04 it
        was, without a word). A ConfigError unless it is a finite symmetric positive-definite
        (n_pairs, n_pairs) matrix (seconds^2)."""
        R = self.kf.R
        if np.shape(R) == self._R_set.shape and np.array_equal(R, self._R_set):
            return
        m = len(self.pairs)
        Rm = np.asarray(R, dtype=float) if real_entries(R) else None
        if (Rm is None or Rm.shape != (m, m) or not np.all(np.isfinite(Rm))
                or not np.allclose(Rm, Rm.T) or np.linalg.eigvalsh(Rm).min() <= 0):
            raise ConfigError(f"kf.R must be a finite symmetric positive-definite ({m}, {m}) "
                              f"matrix (seconds^2), got {R!r:.80}")
        self._R0 = Rm.copy()

    def step(self, z: ArrayLike | None, r_scale: ArrayLike | None = None) -> bool:
        """One frame: predict, then update with pair TDOAs ``z`` (n_pairs,) seconds.

        ``z`` None or containing NaN: predict only. Returns True when the measurement was
        accepted (inside the gate, or the re-initialisation on it after ``max_rejects``
        consecutive rejections), False when missing or rejected. The first measurement
        initialises the state (least squares over the pairs). ``r_scale`` (n_pairs,) > 0:
        this frame's measurement standard deviations are ``r_std_s`` times it (e.g.
        :func:`confidence_r_scale`); None: ``r_std_s``.
        """
        sc = _scales(r_scale, (len(self.pairs),))
        return self._step(z, sc)

    def _step(self, z: ArrayLike | None, sc: NDArray | None) -> bool:
        """:meth:`step` with a checked scale ``sc`` (n_pairs,) or None."""
        if z is not None and _size(z) != len(self.pairs):
            raise GeometryError(f"expected {len(self.pairs)} pair TDOAs, got {_size(z)}")
        self._adopt_hand_set_r()
        # (text raised numpy's ValueError; 1e300 s made the gate distance NaN: accepted)
        return self._step_checked(None if z is None else as_tdoas(z, len(self.pairs)), sc)

    def _checked_frames(self, Z: ArrayLike) -> NDArray:
        """Frames ``Z`` (n_frames, n_pairs) checked once as :meth:`step` checks each (so the
        loops of :meth:`filter`, :meth:`smooth` and :meth:`log_likelihood` need not: those
        checks were ~20 % of a step), and a hand-set ``kf.R`` adopted before them."""
        Zm = _frames(Z)
        m = len(self.pairs)
        if Zm.shape[1] != m:
            raise GeometryError(f"expected {m} pair TDOAs, got {Zm.shape[1]}")
        check_tdoa_magnitude(Zm)
        self._adopt_hand_set_r()
        return Zm

    def _step_checked(self, zz: NDArray | None, sc: NDArray | None) -> bool:
        """:meth:`_step` of a measurement ``zz`` (n_pairs,) float seconds (NaN: missing) or None
        already checked, with a hand-set ``kf.R`` already adopted."""
        self._set_r(sc)
        self.last_d2 = float("nan")
        self.last_logdet_s = float("nan")
        self.last_accepted = False
        if not self.initialized:
            if zz is not None and np.all(np.isfinite(zz)):
                self._init_from(zz)
                self.last_accepted = True
            return self.last_accepted
        self.kf.predict()
        if zz is None or not np.all(np.isfinite(zz)):
            return False
        y = zz - (self.kf.H @ self.kf.x).reshape(-1)
        S = self.kf.H @ self.kf.P @ self.kf.H.T + self.kf.R
        d2 = float(y @ np.linalg.solve(S, y))
        self.last_d2 = d2
        self.last_logdet_s = float(np.linalg.slogdet(S)[1])  # (log det of S in s^2)
        if not d2 <= self.gate:  # (NaN included)
            self.n_rejected += 1
            self._run += 1
            if self._run >= self.max_rejects:
                self._init_from(zz)
                self.last_accepted = True
            return self.last_accepted
        self.kf.update(zz)
        self._run = 0
        self.last_accepted = True
        return True

    def filter(self, Z: ArrayLike, r_scale: ArrayLike | None = None) -> tuple[NDArray, NDArray]:
        """Run over frames ``Z`` (n_frames, n_pairs) (NaN rows = missing); ``r_scale``
        (n_frames, n_pairs): each frame's measurement noise scale (:meth:`step`).

        Returns (pair TDOAs (n_frames, n_pairs) from the state after each step -- NaN before the
        first measurement --, accepted (n_frames,) bool).
        """
        Zm = self._checked_frames(Z)
        S = _scales(r_scale, Zm.shape)
        out = np.full(Zm.shape, np.nan)
        acc = np.zeros(Zm.shape[0], dtype=bool)
        for n, z in enumerate(Zm):
            acc[n] = self._step_checked(z, None if S is None else S[n])
            if self.initialized:
                out[n] = self.pair_tdoas()
        return out, acc

    def smooth(self, Z: ArrayLike, r_scale: ArrayLike | None = None) -> tuple[NDArray, NDArray]:
        """Forward-backward over a whole sequence of frames ``Z`` (n_frames, n_pairs): the
        filter of :meth:`filter` (its gate and re-initialisations included), then the
        Rauch-Tung-Striebel smoother (Rauch, Tung & Striebel 1965; filterpy's
        ``KalmanFilter.rts_smoother``) on each stretch between re-initialisations, so that every
        frame's estimate uses the frames after it too -- no lag behind a moving source, and
        less noise, for recordings processed whole (``hearsee localize``).

        A re-initialisation looks back (since 2026-12-04): the rejected measurements just
        before it that fit the new state start the new stretch (:meth:`_run_start`), so a
        source that moved while it paused is followed from its first frames after the pause.
        Before, those frames took the old stretch's value: a male voice circling the three-mic
        array at 90 deg/s (free field, 16 kHz, 20 dB) had its 6 such frames 174 us off where
        their own TDOAs were 4.6 us off. Adopted under a rule written before its held-out run
        (``bench/results/HISTORY.md``; held out on 36 three-mic and 12 masked cells: none
        worse, 7 better by 5 % or more, e.g. that voice at 10 / 20 dB 57 / 47 -> 19 / 11 us
        against 41 / 21 raw).

        Returns (pair TDOAs (n_frames, n_pairs) -- NaN before the first measurement --,
        accepted (n_frames,) bool, as :meth:`filter`, the frames that start a stretch by looking
        back counted as accepted; ``r_scale`` as there). The filter's state afterwards is the
        forward pass's with that look-back (the last frame's estimate is the same either way),
        :attr:`n_rejected` its rejections. A filter that has a state already (an earlier
        step, :meth:`filter` or :meth:`smooth`: a recording in chunks) goes on from it, its
        first stretch smoothed from the first frame (until 2026-12-07 that stretch was left
        out: every frame before a re-initialisation NaN).
        """
        Zm = self._checked_frames(Z)
        S = _scales(r_scale, Zm.shape)
        n, dx = Zm.shape[0], self.kf.dim_x
        xs, Ps = np.full((n, dx), np.nan), np.full((n, dx, dx), np.nan)
        start = np.zeros(n, dtype=bool)  # (frames where the state was (re)initialised)
        # (a filter that has a state already -- an earlier step, filter or smooth -- starts a
        # stretch at the first frame: its frames before any re-initialisation were left out of
        # the smoothing, all NaN, though every one was measured and taken)
        had_state = self.initialized
        acc = np.zeros(n, dtype=bool)
        k = 0
        while k < n:
            inits, was = self.n_inits, self.initialized
            acc[k] = self._step_checked(Zm[k], None if S is None else S[k])
            if self.initialized:
                xs[k], Ps[k], start[k] = self.kf.x.reshape(-1), self.kf.P, self.n_inits > inits
            j = self._run_start(Zm, S, acc, start, k) if was and start[k] else k
            if j < k:  # (the re-initialisation's run of rejected frames: see below)
                start[k] = False
                self.n_inits -= 1
                # (the run's frames from j on are filtered again: their rejections are undone,
                # and those of the new pass counted)
                self.n_rejected -= sum(bool(np.all(np.isfinite(Zm[m]))) for m in range(j, k + 1))
                self._set_r(None if S is None else S[j])
                self._init_from(Zm[j])
                xs[j], Ps[j], start[j], acc[j] = self.kf.x.reshape(-1), self.kf.P, True, True
                for m in range(j + 1, k + 1):
                    acc[m] = self._step_checked(Zm[m], None if S is None else S[m])
                    xs[m], Ps[m] = self.kf.x.reshape(-1), self.kf.P
            k += 1
        out = np.full(Zm.shape, np.nan)
        cuts = start.copy()
        if n and had_state:
            cuts[0] = True
        bounds = [*np.flatnonzero(cuts), n]
        for a, b in zip(bounds[:-1], bounds[1:], strict=True):
            if b - a > 1:
                xs[a:b], Ps[a:b], _, _ = self.kf.rts_smoother(xs[a:b], Ps[a:b])
            out[a:b] = xs[a:b] @ self.kf.H.T  # (H: the measured pairs' matrix)
        return out, acc

    def _run_start(self, Zm: NDArray, S: NDArray | None, acc: NDArray, start: NDArray,
                   k: int) -> int:
        """The first frame of the new stretch that :meth:`smooth` re-initialised at frame
        ``k`` after a run of rejected measurements: walking back over that run (missing frames
        passed over; up to the last accepted frame or stretch start), each rejected
        measurement that fits the new state -- inside the gate of its covariance grown by the
        random walk over the frames between -- joins it, up to the first that does not. A
        source that moved while it paused is thus followed from its first frames after the
        pause (they were the run), while a reflection's rejected peaks stay out."""
        x, P, Q = self.kf.x.reshape(-1), self.kf.P, self.kf.Q
        H = self.kf.H
        j = k
        for m in range(k - 1, -1, -1):
            if start[m] or acc[m]:
                break
            if not np.all(np.isfinite(Zm[m])):
                continue
            y = Zm[m] - H @ x
            R = self._r_for(None if S is None else S[m])
            d2 = float(y @ np.linalg.solve(H @ (P + Q * (k - m)) @ H.T + R, y))
            if not d2 <= self.gate:
                break
            j = m
        return j

    def log_likelihood(self, Z: ArrayLike, max_tdoa_s: ArrayLike,
                       outlier_prob: float = OUTLIER_PROB,
                       r_scale: ArrayLike | None = None) -> tuple[float, int]:
        """Run the filter over frames ``Z`` (n_frames, n_pairs) (as :meth:`filter`) and
        score how well its noise model explains them: the sum over the frames measured after
        the first of ``max(log(1 - eps) + log N(y; 0, S), log eps - log V)`` -- each
        innovation ``y`` either a measurement of the model (Gaussian, covariance ``S``) or an
        anomalous GCC peak, uniform over the pairs' lag box of volume ``V = prod(2
        max_tdoa_s)`` (s^n_pairs), with probability ``eps = outlier_prob``. The innovation
        likelihood of Schweppe (1965) / Mehra (1970) for tuning Q and R, made robust by the
        outlier term so that a few reflections' peaks do not decide it. ``r_scale`` as in
        :meth:`filter`. Returns (the sum, the number of frames scored)."""
        Zm = self._checked_frames(Z)
        S = _scales(r_scale, Zm.shape)
        if not (is_real(outlier_prob) and 0 < outlier_prob < 1):
            raise ConfigError(f"outlier_prob must be in (0, 1), got {outlier_prob!r}")
        box = (np.asarray(max_tdoa_s, dtype=float).reshape(-1) if real_entries(max_tdoa_s)
               else np.zeros(0))  # (text: numpy's ValueError)
        if box.shape != (len(self.pairs),) or not np.all(np.isfinite(box) & (box > 0)):
            raise GeometryError(f"max_tdoa_s must be {len(self.pairs)} finite numbers > 0 "
                                f"seconds (one per pair), got {max_tdoa_s!r:.80}")
        m = len(self.pairs)
        floor = np.log(outlier_prob) - float(np.sum(np.log(2.0 * box)))
        inlier = np.log1p(-outlier_prob) - 0.5 * m * np.log(2.0 * np.pi)
        total, n = 0.0, 0
        for k, z in enumerate(Zm):
            scored = self.initialized and bool(np.all(np.isfinite(z)))
            self._step_checked(z, None if S is None else S[k])
            if scored:
                total += max(inlier - 0.5 * (self.last_logdet_s + self.last_d2), floor)
                n += 1
        return total, n


def tune_itd_noise(Z: ArrayLike, n_mics: int, pairs: Sequence[tuple[int, int]],
                   fs: float, max_tdoa_s: ArrayLike, ref: int = 0,
                   q_std_s: Sequence[float] | None = None,
                   r_std_s: Sequence[float] | None = None, r_scale: ArrayLike | None = None,
                   q_max_s: float | None = None) -> tuple[float, float] | None:
    """The ``(q_std_s, r_std_s)`` (seconds) of :class:`ItdKalman` that explain the frames
    ``Z`` (n_frames, n_pairs; NaN rows missing) best: the largest
    :meth:`ItdKalman.log_likelihood` over a grid -- ``q_std_s`` / ``r_std_s`` (candidates in
    seconds), by default :data:`TUNE_Q_SAMPLES` / :data:`TUNE_R_SAMPLES` samples at ``fs``
    Hz. None when fewer than two frames could be scored (nothing to tell the grid apart).
    ``r_scale`` (n_frames, n_pairs): each frame's measurement-noise scale
    (:func:`confidence_r_scale`), the same for every candidate. ``q_max_s``: only the q
    candidates at or below it (at least the smallest one) -- a prior on how fast the ITDs can
    move (:func:`hearsee.audio.localize.localize_recording` caps q at the ITD change per frame
    of a source turning at 90 deg/s about the array).

    Why: one fixed noise model cannot serve every recording. The former default of
    ``hearsee localize`` (q a quarter sample per frame, r one sample) lagged a moving
    white-noise source by far more than its frames erred (three-mic, free field, 90 deg/s:
    13 us smoothed vs 1.3 us per frame at 16 kHz, 40 vs 0.6 us at 48 kHz, where a sample is
    a third as long), while a voice's sparse frames, with reflections' peaks among them, need
    the smoothing. Reconstruction beyond the thesis, which fixes Q_s and R by hand."""
    if not (is_real(fs) and fs > 0):
        raise ConfigError(f"fs must be a sample rate > 0 Hz, got {fs!r}")
    fs = float(fs)
    qs = [v / fs for v in TUNE_Q_SAMPLES] if q_std_s is None else _candidates("q_std_s", q_std_s)
    rs = [v / fs for v in TUNE_R_SAMPLES] if r_std_s is None else _candidates("r_std_s", r_std_s)
    if q_max_s is not None:
        if not (is_real(q_max_s) and q_max_s > 0):
            raise ConfigError(f"q_max_s must be a number > 0 seconds, got {q_max_s!r}")
        qs = [q for q in qs if q <= q_max_s] or [min(qs)]
    S = None if r_scale is None else _scales(r_scale, _frames(Z).shape)
    best: tuple[float, float, float] | None = None
    for q in qs:
        for r in rs:
            ll, n = ItdKalman(n_mics, pairs, ref, q_std_s=q, r_std_s=r).log_likelihood(
                Z, max_tdoa_s, r_scale=S)
            if n < 2:
                return None
            if best is None or ll > best[0]:
                best = (ll, q, r)
    return None if best is None else (best[1], best[2])


def _candidates(name: str, values: ArrayLike) -> list[float]:
    """One number or a sequence of them (seconds) as a list; a ConfigError for anything else
    (text, an empty list: a builtin TypeError or no candidate at all)."""
    v = np.atleast_1d(np.asarray(values, dtype=float)) if real_entries(values) else None
    if v is None or v.ndim != 1 or v.size == 0:
        raise ConfigError(f"{name} must be one or more numbers > 0 seconds, got {values!r:.60}")
    return [float(a) for a in v]


def itd_filter_entries(noise: tuple[float, float] | None, model: str | None
                       ) -> dict[str, float | str | None]:
    """The ``hearsee localize`` document's ``kalman_q_std_s`` / ``kalman_r_std_s`` (s) /
    ``kalman_noise`` entries of :func:`smooth_recording_itds`' ``(q, r)`` and model (None,
    without the filter: nulls) -- one place for every array's document."""
    if noise is not None and (isinstance(noise, str) or len(noise) != 2):  # (IndexError)
        raise ConfigError(f"noise must be (q_std_s, r_std_s) in seconds or None, got "
                          f"{noise!r:.60}")
    return {"kalman_q_std_s": None if noise is None else float(noise[0]),
            "kalman_r_std_s": None if noise is None else float(noise[1]),
            "kalman_noise": model}


def smooth_recording_itds(Z: ArrayLike, confidence: ArrayLike, n_mics: int,
                          pairs: Sequence[tuple[int, int]], fs: float, max_tdoa_s: ArrayLike,
                          hop_s: float, q_std_s: float | None = None,
                          r_std_s: float | None = None, tune: bool = False
                          ) -> tuple[NDArray, tuple[float, float], str]:
    """A whole recording's frame TDOAs ``Z`` (n_frames, n_pairs; NaN rows: no estimate) through
    :class:`ItdKalman` (reference microphone 0) forward and backward (:meth:`ItdKalman.smooth`):
    what ``hearsee localize`` reports per frame, for every array (a masked pair's too).
    ``confidence`` (n_frames, n_pairs): the frames' GCC confidence
    (:attr:`hearsee.audio.tdoa.TdoaFrames.confidence`); ``max_tdoa_s``: the pairs' largest
    TDOAs (s; a masked pair's largest tabled ITD); ``hop_s``: the frames' hop (s).

    The noise model, in this order:

    - ``tune``: ``q_std_s`` and ``r_std_s`` (those not given) from :func:`tune_itd_noise`'s
      grid, one measurement noise for every frame ("tuned");
    - neither given: "adaptive" -- each frame's measurement noise one sample times
      :func:`confidence_r_scale` of its confidence, the random walk's by the likelihood among
      the grid's values up to :func:`max_itd_step_s` (a 90 deg/s turn);
    - otherwise "fixed": the given values, a quarter sample per frame of random walk and one
      sample of measurement noise for the one not given (also what "adaptive" and "tuned" fall
      back to when too few frames tell the grid apart).

    Returns (the smoothed TDOAs (n_frames, n_pairs), NaN where ``Z`` has none; the filter's
    ``(q_std_s, r_std_s)`` in seconds; the model's name)."""
    if not (is_real(fs) and fs > 0):  # (text with a given q_std_s: a builtin TypeError)
        raise ConfigError(f"fs must be a sample rate > 0 Hz, got {fs!r}")
    Zm = _frames(Z)
    noise: tuple[float, float] | None = None
    r_scale = None
    model = "fixed"
    if tune:
        noise = tune_itd_noise(Zm, n_mics, pairs, fs, max_tdoa_s,
                               q_std_s=None if q_std_s is None else (q_std_s,),
                               r_std_s=None if r_std_s is None else (r_std_s,))
        model = "tuned"
    elif q_std_s is None and r_std_s is None:
        r_scale = confidence_r_scale(confidence)
        noise = tune_itd_noise(Zm, n_mics, pairs, fs, max_tdoa_s, r_std_s=(1.0 / fs,),
                               r_scale=r_scale, q_max_s=max_itd_step_s(max_tdoa_s, hop_s))
        model = "adaptive"
    if noise is None:  # (the fixed defaults; also when too few frames tell the grid apart)
        noise = (q_std_s if q_std_s is not None else 0.25 / fs,
                 r_std_s if r_std_s is not None else 1.0 / fs)
        model = "fixed" if r_scale is None else model
    kf = ItdKalman(n_mics, pairs, ref=0, q_std_s=noise[0], r_std_s=noise[1])
    filt, _ = kf.smooth(Zm, r_scale=r_scale)
    return np.where(np.isnan(Zm).any(axis=1)[:, None], np.nan, filt), noise, model
