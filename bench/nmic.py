"""Benchmark: arrays of four or more microphones (issue 2's "N >= 4 microphones ... so users of
larger arrays are served too") -- volume arrays' 3D direction vs pyroomacoustics SRP-PHAT, MUSIC
and NormMUSIC on the whole sphere, and planar arrays of four and six microphones in the array
plane as ``bench/doa.py`` measures its two- and three-microphone arrays.

Four parts, in one process:

1. **TDOA level** (no audio): exact TDOAs of random sources plus i.i.d. Gaussian noise per pair,
   for three arrays (a 15 cm tetrahedron and its centre, a 20 cm cube of eight, a 5 cm hexagon
   with a microphone 8 cm above its centre), sources 0.5-1, 1-2 and 2-4 m away: the RMS
   direction error of the plane wave (:func:`hearsee.audio.localize.far_field_volume`) and of
   :func:`~hearsee.audio.localize.localize_tdoa`'s answer, which takes the direction of the
   fitted point source when a likelihood-ratio test finds the wavefront's curvature
   (``extra["direction_model"]``); and the share of answers from the position. Then random
   arrays (5-8 microphones, 5-40 cm, sources 0.3-5 m, 0-30 us). These are the numbers of
   ``localize_tdoa``'s docstring and the README (2026-11-27), made reproducible here.
2. **Recordings in rooms**, side by side: the tetrahedron + centre and the cube in the
   8 x 7 x 3 m room of ``bench/doa.py`` (anechoic, RT60 0.3 / 0.6 s; pyroomacoustics image
   sources), SNR 10 / 20 dB, white noise, synthetic male / female voices and CMU ARCTIC speech
   (when ``../shared`` is present), sources 0.5-3 m away in random directions (elevation
   within +-30 deg, inside the room). Each method gives one whole-recording direction, scored
   by its great-circle error from the true direction (seen from the array centre, the frame's
   origin): RMSE, median, share above 10 deg, CPU per second of audio. hearsee runs
   ``bench/doa.py``'s benchmarked setting (its ``HEARSEE``) and is scored twice: its answer
   (curvature test) and the plane wave alone (``extra["far_field"]``), which isolates what
   the curvature test does on reverberant TDOAs -- it was chosen on TDOAs with Gaussian noise,
   and reflections bias TDOAs instead. The peers steer plane waves (their default; no fixed
   range suits sources 0.5-3 m away) on a Fibonacci grid of :data:`PEER_GRID_POINTS`
   directions, then on a local azimuth x colatitude grid of :data:`PEER_FINE_DEG` around
   its maximum (so their grid does not round their answers: the coarse grid alone would cost
   ~0.5 deg RMS). Their CPU time is that of both stages.
3. **Planar arrays of four and six microphones** (the ``respeaker-4`` / ``respeaker-6``
   presets), exactly as ``bench/doa.py`` part 1 runs its arrays: its room, sources 1-3 m away
   in the array plane, SNR 0 / 10 / 20 dB, the same signals; hearsee's azimuth with its
   benchmarked setting (``HEARSEE``, in-plane, with its fallback) and the peers in the plane
   (``dim=2``) on the 0.1-deg grid, steered to points 2 m away (``pra_azimuth``). hearsee is
   also scored with ``joint="pairs"``, the summary's search before ``joint="auto"`` (which
   steers the in-plane search for these arrays when the recording is judged reverberant).
4. **Planar arrays on the whole sphere**: part 2's recordings (room, sources 0.5-3 m away,
   elevation within +-30 deg, signals, SNRs, scoring, peers with ``dim=3``) for two planar
   arrays -- ``respeaker-6`` and a circle of eight microphones of 10 cm radius -- whose
   answers hold a mirror twin about the array plane: every method is scored by the nearer of
   its direction and that direction's mirror image (a planar array cannot tell them apart;
   hearsee lists both as candidates, the peers' spectra are symmetric). hearsee's answer
   takes the direction of its near-field position when the curvature test finds it, as in
   part 2; "hearsee plane wave" is the plane wave's answer alone.

Parts 2 and 4 also score hearsee's near-field position (tables 2c and 4c; no peer gives one):
how often :func:`~hearsee.audio.localize.localize_tdoa` reports it (its default TDOA error:
5 us, raised to 3x the pairs' closure RMS where they disagree more -- since 2026-11-27's
thirty-fourth session, before which the declared 5 us alone was used; it withholds a position
whose distance the TDOAs do not fix), the relative distance
error of the reported positions and whether the truth lies inside their covariance's 95 %
ellipsoid, and the distance error of every fit, reported or withheld (what was reported before
2026-11-27).

Run: ``.venv/bin/python bench/nmic.py [--trials N] [--seed S] [--quick]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import scipy.fft as sfft
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import (  # noqa: E402
    RESULTS,
    arctic_files,
    markdown_table,
    print_table,
    shared_data_dir,
    write_markdown,
)
from doa import (  # noqa: E402
    ARRAY_AT,
    BANDS,
    FS,
    PRA_METHODS,
    PRA_NFFT,
    ROOM,
    az_error,
    hearsee_azimuth,
    pra_azimuth,
    summary_tdoas,
)
from doa import SNRS as PLANAR_SNRS  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import (  # noqa: E402
    Localization,
    array_geometry,
    far_field_volume,
    localize_tdoa,
)
from hearsee.audio.propagation import add_noise, room_impulse_responses  # noqa: E402
from hearsee.audio.signals import load_wav, synthetic_voice, white_noise  # noqa: E402
from hearsee.errors import HearseeError  # noqa: E402
from hearsee.geometry import angle_between, sph_to_cart, unit_vector_deg  # noqa: E402

_TET = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float) * (0.15 / np.sqrt(8))
#: the arrays (metres, array frame): a 15 cm regular tetrahedron (side) and its centre, a 20 cm
#: cube of eight, and a 5 cm-radius hexagon with a microphone 8 cm above its centre
ARRAYS = {
    "tetrahedron 15 cm + centre": np.vstack([_TET, [0.0, 0.0, 0.0]]),
    "cube 20 cm": np.array([[x, y, z] for x in (-.1, .1) for y in (-.1, .1) for z in (-.1, .1)]),
    "hexagon 5 cm + top": np.vstack(
        [[[0.05 * np.cos(a), 0.05 * np.sin(a), 0.0] for a in np.radians(np.arange(0, 360, 60))],
         [[0.0, 0.0, 0.08]]]),
}
#: part 2's arrays (the hexagon's range is barely measured: part 1 shows it)
ROOM_ARRAYS = ("tetrahedron 15 cm + centre", "cube 20 cm")
#: part 4's planar arrays on the whole sphere (in the z = 0 plane, centred at the origin)
SPHERE_PLANAR_ARRAYS = {
    "respeaker-6": MicArray.from_preset("respeaker-6").positions,
    "circle of 8, 10 cm radius": np.array(
        [[0.1 * np.cos(a), 0.1 * np.sin(a), 0.0] for a in np.radians(np.arange(0, 360, 45))]),
}
TDOA_RANGES_M = ((0.5, 1.0), (1.0, 2.0), (2.0, 4.0))
TDOA_NOISE_S = (0.0, 5e-6, 20e-6)
TDOA_EL_MAX_RAD = 0.6  # +-34 deg
RT60S = (0.0, 0.3, 0.6)
SNRS = (10.0, 20.0)
RANGE_M = (0.5, 3.0)
EL_MAX_DEG = 30.0
#: distance from the walls, floor and ceiling (m) a source keeps
WALL_MARGIN_M = 0.3
#: the peers' coarse grid (Fibonacci sphere; ~3.2 deg between neighbours) and local fine grid
PEER_GRID_POINTS = 4000
PEER_FINE_DEG = (4.0, 0.2)  # half-width and step of the azimuth x colatitude refinement
METHODS = ("hearsee", "hearsee plane wave", *PRA_METHODS)
#: chi-square quantile: a 3D Gaussian's 95 % ellipsoid (scipy.stats.chi2.ppf(0.95, 3))
CHI2_95_3DOF = 7.814727903251178


def angle_deg(u: np.ndarray | None, v: np.ndarray) -> float:
    """Great-circle angle in degrees (180 for no answer)."""
    if u is None or not np.all(np.isfinite(u)):
        return 180.0
    return float(np.degrees(angle_between(u, v)))


def mirror_blind_deg(u: np.ndarray | None, v: np.ndarray) -> float:
    """:func:`angle_deg` to ``v`` of the nearer of ``u`` and its mirror image about the
    z = 0 plane (part 4's arrays lie in it)."""
    return angle_deg(u, v) if u is None else min(angle_deg(u, v),
                                                 angle_deg(u * [1.0, 1.0, -1.0], v))


# ------------------------------------------------------------------------------ part 1: TDOAs
def run_tdoa(trials: int, seed: int, random_arrays: int) -> tuple[list, list]:
    """Rows of the structured sweep and of the random-array summary."""
    rng = np.random.default_rng(seed)
    rows = []
    for name, P in ARRAYS.items():
        arr = MicArray(P, name=name)
        for rlo, rhi in TDOA_RANGES_M:
            for sig in TDOA_NOISE_S:
                e_ff, e_sel, n_pos = [], [], 0
                for _ in range(trials):
                    u = sph_to_cart(rng.uniform(-np.pi, np.pi),
                                    rng.uniform(-TDOA_EL_MAX_RAD, TDOA_EL_MAX_RAD))
                    tau = arr.tdoa(rng.uniform(rlo, rhi) * u)
                    tau = tau + sig * rng.standard_normal(len(arr.pairs))
                    e_ff.append(angle_deg(far_field_volume(tau, arr).direction, u))
                    loc = localize_tdoa(tau, arr)
                    e_sel.append(angle_deg(loc.direction, u))
                    n_pos += loc.extra.get("direction_model") == "position"
                rows.append([name, f"{rlo:g}-{rhi:g}", sig * 1e6, _rms(e_ff), _rms(e_sel),
                             100.0 * n_pos / trials])
    e_ff, e_sel, worse, n_pos = [], [], 0, 0
    while len(e_ff) < random_arrays:
        n = int(rng.integers(5, 9))
        ap = rng.uniform(0.05, 0.4)
        P = rng.uniform(-ap / 2, ap / 2, (n, 3))
        try:
            arr = MicArray(P)
        except HearseeError:  # (two microphones drawn too close)
            continue
        if array_geometry(arr).kind != "volume":
            continue
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        sig = rng.choice([0.0, 2e-6, 10e-6, 30e-6])
        tau = arr.tdoa(rng.uniform(0.3, 5.0) * u) + sig * rng.standard_normal(len(arr.pairs))
        loc = localize_tdoa(tau, arr)
        e_ff.append(angle_deg(far_field_volume(tau, arr).direction, u))
        e_sel.append(angle_deg(loc.direction, u))
        n_pos += loc.extra.get("direction_model") == "position"
        worse += e_sel[-1] > e_ff[-1] + 10.0
    rnd = [[len(e_ff), _rms(e_ff), _rms(e_sel), float(np.median(e_ff)), float(np.median(e_sel)),
            100.0 * n_pos / len(e_ff), worse]]
    return rows, rnd


def _rms(e: list[float] | np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(e)))) if len(e) else float("nan")


# ------------------------------------------------------------------------- part 2: recordings
def draw_source(rng: np.random.Generator) -> np.ndarray:
    """A source position (array frame, m) RANGE_M away, elevation within EL_MAX_DEG, at least
    WALL_MARGIN_M inside the room."""
    while True:
        u = sph_to_cart(rng.uniform(-np.pi, np.pi),
                        np.radians(rng.uniform(-EL_MAX_DEG, EL_MAX_DEG)))
        p = rng.uniform(*RANGE_M) * u
        q = p + ARRAY_AT
        if np.all(q > WALL_MARGIN_M) and np.all(q < ROOM - WALL_MARGIN_M):
            return p


def _source_signal(kind: str, duration: float, rng: np.random.Generator,
                   speech: list[Path]) -> np.ndarray:
    """The source waveform of ``bench/doa.py``'s signal kinds (ARCTIC: a random utterance's
    first 3 s)."""
    if kind == "noise":
        return white_noise(duration, FS, rng)
    if kind == "arctic":
        return load_wav(speech[rng.integers(len(speech))], FS)[0][: int(3.0 * FS)]
    return synthetic_voice(kind, duration, FS, rng)


def _convolve(s: np.ndarray, h: np.ndarray) -> np.ndarray:
    """``s`` through each impulse response of ``h`` (n_mics, taps), cut to ``len(s)``."""
    n = sfft.next_fast_len(len(s) + h.shape[1])
    return sfft.irfft(sfft.rfft(s, n)[None] * sfft.rfft(h, n, axis=-1), n, axis=-1)[:, : len(s)]


def _recordings(arr: MicArray, trials: int, rng: np.random.Generator, kinds: list[str],
                speech: list[Path], duration: float, snrs: tuple[float, ...],
                draw: Callable[[np.random.Generator], np.ndarray], t_start: float
                ) -> Iterator[tuple]:
    """``(rt60, source, kind, band, snr, x)`` for each recording of ``arr`` in the room:
    ``trials`` sources drawn by ``draw`` (array frame, m) per RT60, each signal kind, each
    SNR (sensor noise drawn per recording); progress printed after each RT60."""
    for rt in RT60S:
        for _ in range(trials):
            src = draw(rng)
            h = room_impulse_responses(FS, arr.positions + ARRAY_AT, src + ARRAY_AT, ROOM, rt,
                                       speed_of_sound=arr.speed_of_sound)
            for kind in kinds:
                s = _source_signal(kind, duration, rng, speech)
                clean = _convolve(s, h)
                for snr in snrs:
                    yield (rt, src, kind, BANDS["noise" if kind == "noise" else "speech"], snr,
                           add_noise(clean, snr, rng))
        print(f"  {arr.name} rt60={rt}: done ({time.time() - t_start:.0f} s)", flush=True)


def _signal_kinds(data: Path | None) -> tuple[list[Path], list[str]]:
    """The ARCTIC utterances (none without ``../shared``) and the signal kinds of parts 2-4."""
    speech = arctic_files(data)
    return speech, ["noise", "male", "female"] + (["arctic"] if speech else [])


def _in_plane_source(rng: np.random.Generator) -> np.ndarray:
    """``bench/doa.py``'s source: a random azimuth, 1-3 m away in the array plane."""
    az = rng.uniform(-180, 180)
    return rng.uniform(1.0, 3.0) * sph_to_cart(np.radians(az), 0.0)


def hearsee_direction(x: np.ndarray, arr: MicArray, band: tuple[float, float]
                      ) -> tuple[np.ndarray | None, np.ndarray | None, str, Localization | None]:
    """hearsee's whole-recording direction (its answer and the plane wave's) with
    ``bench/doa.py``'s setting and fallback (an abstention is replaced by the estimate without
    the detection test, then from every frame with energy: the peers always answer), and the
    localization itself (its near-field position)."""
    tf = summary_tdoas(x, FS, arr, band)
    loc = localize_tdoa(tf.summary_tdoa_s, arr, tf.pairs)
    if loc.azimuth_deg is None:
        return None, None, "none", None
    model = loc.extra.get("direction_model", "plane_wave")
    ff = loc.extra.get("far_field")
    u_ff = (unit_vector_deg(ff["azimuth_deg"], ff["elevation_deg"])
            if model == "position" and ff else loc.direction)
    return loc.direction, u_ff, model, loc


def position_score(loc: Localization | None, src: np.ndarray, planar: bool
                   ) -> tuple[bool, float, bool, float]:
    """``(reported, relative distance error of the reported position, truth inside its 95 %
    ellipsoid, relative distance error of the fit whether reported or not)`` of a near-field
    position against the source ``src`` (array frame, m); a planar array's (in the z = 0
    plane) against the source's image on the fit's side."""
    nan = float("nan")
    fit = None if loc is None else loc.extra.get("position_fit_m")
    if fit is None:
        return False, nan, False, nan
    s = np.array([src[0], src[1], abs(src[2]) * np.sign(fit[2] or 1.0)]) if planar else src
    r = float(np.linalg.norm(s))
    fit_err = abs(float(np.linalg.norm(fit)) - r) / r
    if loc.position_m is None:
        return False, nan, False, fit_err
    d = loc.position_m - s
    inside = float(d @ np.linalg.solve(loc.position_covariance_m2, d)) <= CHI2_95_3DOF
    return True, abs(float(np.linalg.norm(loc.position_m)) - r) / r, inside, fit_err


def pra_direction(x: np.ndarray, arr: MicArray, algo: str, band: tuple[float, float]
                  ) -> np.ndarray:
    """A pyroomacoustics DOA method's direction on the whole sphere (``dim=3``, plane waves):
    the maximum of its spatial spectrum on a Fibonacci grid, then on a local azimuth x
    colatitude grid around it."""
    import pyroomacoustics as pra

    X = pra.transform.stft.analysis(x.T, PRA_NFFT, PRA_NFFT // 2, win=pra.hann(PRA_NFFT))
    X = X.transpose([2, 1, 0])
    L = arr.positions.T
    doa = pra.doa.algorithms[algo](L, FS, PRA_NFFT, c=arr.speed_of_sound, num_src=1, dim=3,
                                   n_grid=PEER_GRID_POINTS)
    doa.locate_sources(X, freq_range=list(band))
    az0, col0 = float(doa.azimuth_recon[0]), float(doa.colatitude_recon[0])
    half, step = np.radians(PEER_FINE_DEG[0]), np.radians(PEER_FINE_DEG[1])
    d = np.arange(-half, half + step / 2, step)
    col = np.clip(col0 + d, 1e-6, np.pi - 1e-6)
    fine = pra.doa.algorithms[algo](L, FS, PRA_NFFT, c=arr.speed_of_sound, num_src=1, dim=3,
                                    azimuth=az0 + d, colatitude=col)
    fine.locate_sources(X, freq_range=list(band))
    az, co = float(fine.azimuth_recon[0]), float(fine.colatitude_recon[0])
    return sph_to_cart(az, np.pi / 2 - co)


def run_rooms(trials: int, seed: int, data: Path | None, duration: float,
              arrays: dict[str, np.ndarray] | None = None,
              score: Callable[[np.ndarray | None, np.ndarray], float] = angle_deg
              ) -> tuple[dict, dict]:
    """Errors per (array, RT60, SNR, signal, method), with each trial's distance, and CPU:
    part 2 (``arrays`` None: :data:`ROOM_ARRAYS`), or part 4 (its arrays, ``score``
    :func:`mirror_blind_deg`)."""
    arrays = arrays or {name: ARRAYS[name] for name in ROOM_ARRAYS}
    rng = np.random.default_rng(seed)
    speech, kinds = _signal_kinds(data)
    errors: dict = {}
    cpu = {m: 0.0 for m in METHODS if m != "hearsee plane wave"}
    audio_s = 0.0
    t_start = time.time()
    for name, positions in arrays.items():
        arr = MicArray(positions, name=name)
        w = rng.standard_normal((arr.n_mics, FS // 2))  # warm-up: first-call costs
        hearsee_direction(w, arr, BANDS["speech"])
        for m in PRA_METHODS:
            pra_direction(w, arr, m, BANDS["speech"])
        for rt, src, kind, band, snr, x in _recordings(arr, trials, rng, kinds, speech, duration,
                                                        SNRS, draw_source, t_start):
            u = src / np.linalg.norm(src)
            audio_s += x.shape[1] / FS
            cell = errors.setdefault((name, rt, snr, kind),
                                     {m: [] for m in (*METHODS, "r", "model")})
            cell["r"].append(float(np.linalg.norm(src)))
            t0 = time.process_time()
            u_sel, u_ff, model, loc = hearsee_direction(x, arr, band)
            cpu["hearsee"] += time.process_time() - t0
            cell["hearsee"].append(score(u_sel, u))
            cell["hearsee plane wave"].append(score(u_ff, u))
            cell["model"].append(model)
            cell.setdefault("position", []).append(
                position_score(loc, src, score is mirror_blind_deg))
            for m in PRA_METHODS:
                t0 = time.process_time()
                est = pra_direction(x, arr, m, band)
                cpu[m] += time.process_time() - t0
                cell[m].append(score(est, u))
    return errors, {"cpu": cpu, "audio_s": audio_s}


def summarize_rooms(errors: dict, timing: dict, arrays: tuple[str, ...] = ROOM_ARRAYS
                    ) -> tuple[list, list, list, list, int, int, list]:
    """Headers and rows of the per-condition table, headers and rows of the per-(array, RT60)
    pools by distance, the count of conditions where hearsee is at or below the best peer,
    the number of conditions, and the CPU table's rows."""
    headers, rows, won = _condition_table(errors, METHODS)
    headers += ["hearsee from position %", "hearsee > 10 deg %", "SRP > 10 deg %"]
    for row, (_, cell) in zip(rows, sorted(errors.items()), strict=True):
        row += [100.0 * np.mean([m == "position" for m in cell["model"]]),
                100.0 * np.mean(np.array(cell["hearsee"]) > 10.0),
                100.0 * np.mean(np.array(cell["SRP"]) > 10.0)]
    pool_h = ["array", "RT60 s", "distance m", "n", *(f"{m} RMSE deg" for m in METHODS),
              "hearsee from position %"]
    pools = []
    for name in arrays:
        for rt in RT60S:
            cells = [c for (a, r, _, _), c in errors.items() if a == name and r == rt]
            if not cells:
                continue
            dist = np.concatenate([c["r"] for c in cells])
            for lo, hi in ((0.5, 1.0), (1.0, 2.0), (2.0, 3.0)):
                sel = (dist >= lo) & (dist < hi)
                if not sel.any():
                    continue
                pools.append([name, rt, f"{lo:g}-{hi:g}", int(sel.sum()),
                              *(_rms(np.concatenate([c[m] for c in cells])[sel]) for m in METHODS),
                              100.0 * np.mean(np.concatenate(
                                  [np.array(c["model"]) == "position" for c in cells])[sel])])
    return headers, rows, pool_h, pools, won, len(rows), _cpu_rows(timing)


POSITION_HEADERS = ["array", "RT60 s", "n", "position reported %",
                    "reported: median distance error %", "reported: off by > 50 % (share %)",
                    "reported: truth in 95 % ellipsoid %", "every fit: median distance error %"]


def summarize_positions(errors: dict, arrays: tuple[str, ...]) -> list:
    """Rows of the near-field position table per (array, RT60): how often ``localize_tdoa``
    reports a position (its default TDOA error: 5 us, raised to 3x the pairs' closure RMS),
    how good the reported ones are, and how good
    every fit was (reported or withheld). No peer gives a position."""
    rows = []
    for name in arrays:
        for rt in RT60S:
            sc = [t for (a, r, _, _), c in errors.items() if a == name and r == rt
                  for t in c.get("position", [])]
            if not sc:
                continue
            rep = np.array([t[0] for t in sc])
            err = np.array([t[1] for t in sc])[rep]
            ins = np.array([t[2] for t in sc])[rep]
            fit = np.array([t[3] for t in sc])
            pct = (lambda v: 100.0 * float(np.mean(v)) if len(v) else float("nan"))  # noqa: E731
            rows.append([name, rt, len(sc), pct(rep),
                         100.0 * float(np.median(err)) if len(err) else float("nan"),
                         pct(err > 0.5), pct(ins), 100.0 * float(np.nanmedian(fit))])
    return rows


def _condition_table(errors: dict, methods: tuple[str, ...]) -> tuple[list, list, int]:
    """Headers and rows of a per-condition table -- (array, RT60, SNR, signal, n), each
    method's RMSE and median, the best peer's RMSE and whether hearsee is at or below it --
    and the count of conditions where it is (parts 2-4)."""
    headers = ["array", "RT60 s", "SNR dB", "signal", "n"]
    for m in methods:
        headers += [f"{m} RMSE deg", f"{m} median deg"]
    headers += ["best peer RMSE deg", "hearsee <= best peer"]
    rows, won = [], 0
    for (name, rt, snr, kind), cell in sorted(errors.items()):
        row: list = [name, rt, snr, kind, len(cell["hearsee"])]
        for m in methods:
            row += [_rms(cell[m]), float(np.median(cell[m]))]
        best = min(_rms(cell[m]) for m in PRA_METHODS)
        ok = _rms(cell["hearsee"]) <= best
        won += ok
        rows.append(row + [best, "yes" if ok else "no"])
    return headers, rows, won


def _cpu_rows(timing: dict) -> list:
    """Rows of a CPU table: each timed method's ms per second of audio and SRP-PHAT's CPU over
    its own."""
    cpu = timing["cpu"]
    return [[m, cpu[m] / timing["audio_s"] * 1e3, cpu["SRP"] / max(cpu[m], 1e-12)] for m in cpu]


# ---------------------------------------------------------------- part 3: planar 4-6 microphones
PLANAR_ARRAYS = ("respeaker-4", "respeaker-6")
PLANAR_METHODS = ("hearsee", "hearsee joint='pairs'", *PRA_METHODS)


def run_planar(trials: int, seed: int, data: Path | None, duration: float) -> tuple[dict, dict]:
    """Azimuth errors per (array, RT60, SNR, signal, method) as ``bench/doa.py`` part 1
    scores them, and CPU (hearsee and the peers, on the scored grid)."""
    rng = np.random.default_rng(seed)
    speech, kinds = _signal_kinds(data)
    errors: dict = {}
    cpu = {m: 0.0 for m in PLANAR_METHODS if m != "hearsee joint='pairs'"}
    audio_s = 0.0
    t_start = time.time()
    for name in PLANAR_ARRAYS:
        arr = MicArray.from_preset(name)
        w = rng.standard_normal((arr.n_mics, FS // 2))  # warm-up: first-call costs
        hearsee_azimuth(w, FS, arr, BANDS["speech"])
        for m in PRA_METHODS:
            pra_azimuth(w, FS, arr, m, BANDS["speech"])
        for rt, src, kind, band, snr, x in _recordings(arr, trials, rng, kinds, speech, duration,
                                                        PLANAR_SNRS, _in_plane_source, t_start):
            az = float(np.degrees(np.arctan2(src[1], src[0])))
            audio_s += x.shape[1] / FS
            cell = errors.setdefault((name, rt, snr, kind), {m: [] for m in PLANAR_METHODS})
            t0 = time.process_time()
            est = hearsee_azimuth(x, FS, arr, band)
            cpu["hearsee"] += time.process_time() - t0
            cell["hearsee"].append(az_error(est, az, False))
            est = hearsee_azimuth(x, FS, arr, band, joint="pairs")
            cell["hearsee joint='pairs'"].append(az_error(est, az, False))
            for m in PRA_METHODS:
                t0 = time.process_time()
                est = pra_azimuth(x, FS, arr, m, band)
                cpu[m] += time.process_time() - t0
                cell[m].append(az_error(est, az, False))
    return errors, {"cpu": cpu, "audio_s": audio_s}


def summarize_planar(errors: dict, timing: dict) -> tuple[list, list, list, list, int, int, list]:
    """Per-condition table, per-(array, RT60) pools, count at or below the best peer, number
    of conditions, CPU rows."""
    headers, rows, won = _condition_table(errors, PLANAR_METHODS)
    pool_h = ["array", "RT60 s", "n", *(f"{m} RMSE deg" for m in PLANAR_METHODS)]
    pools = []
    for name in PLANAR_ARRAYS:
        for rt in RT60S:
            cells = [c for (a, r, _, _), c in errors.items() if a == name and r == rt]
            if cells:
                pools.append([name, rt, sum(len(c["hearsee"]) for c in cells),
                              *(_rms(np.concatenate([c[m] for c in cells]))
                                for m in PLANAR_METHODS)])
    return headers, rows, pool_h, pools, won, len(rows), _cpu_rows(timing)


def plot(pools: list, path: Path, arrays: tuple[str, ...] = ROOM_ARRAYS) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(arrays), figsize=(6 * len(arrays), 4), sharey=True)
    for ax, name in zip(np.atleast_1d(axes), arrays, strict=True):
        rows = [r for r in pools if r[0] == name]
        labels = [f"RT60 {r[1]:g}\n{r[2]} m" for r in rows]
        xs = np.arange(len(rows))
        width = 0.8 / len(METHODS)
        for k, m in enumerate(METHODS):
            ax.bar(xs + (k - len(METHODS) / 2 + 0.5) * width, [r[4 + k] for r in rows], width,
                   label=m)
        ax.set_xticks(xs, labels, fontsize=7)
        ax.set_title(name)
        ax.set_ylabel("direction RMSE (deg)")
        ax.set_yscale("log")
    np.atleast_1d(axes)[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


CPU_HEADERS = ["method", "CPU ms per s of audio", "speed-up vs SRP-PHAT"]


def report_rooms(errors: dict, timing: dict, arrays: tuple[str, ...], name: str, part: str,
                 title: str, position_note: str, plot_file: str, link_plot: bool
                 ) -> list[tuple[str, str]]:
    """Print part 2's or part 4's tables (whole-recording directions in the rooms, pooled by
    distance, CPU, near-field positions), draw its plot, and return its markdown sections (the
    first titled with a link to the plot when ``link_plot``)."""
    headers, rows, pool_h, pools, won, n_cells, cpu_rows = summarize_rooms(errors, timing, arrays)
    pos_rows = summarize_positions(errors, arrays)
    print_table(f"{part}. {title}", headers, rows)
    print_table(f"{name}: pooled by distance", pool_h, pools)
    print_table(f"{name}: CPU", CPU_HEADERS, cpu_rows)
    won_line = f"hearsee RMSE <= the best pyroomacoustics method in {won}/{n_cells} conditions"
    print(f"{name}: {won_line}")
    print_table(f"{name}: near-field positions", POSITION_HEADERS, pos_rows)
    plot(pools, RESULTS / plot_file, arrays)
    link = f" ![{Path(plot_file).stem}]({plot_file})" if link_plot else ""
    return [(f"{part}. {title}{link}", markdown_table(headers, rows) + f"\n\n{won_line}."),
            (f"{part}b. Pooled by the source's distance", markdown_table(pool_h, pools)),
            (f"{part}c. Near-field positions ({position_note})",
             markdown_table(POSITION_HEADERS, pos_rows)),
            (f"CPU time per second of audio (part {part})", markdown_table(CPU_HEADERS, cpu_rows))]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="few trials (a couple of minutes)")
    ap.add_argument("--trials", type=int, default=None, help="room recordings per condition")
    ap.add_argument("--tdoa-trials", type=int, default=300, help="sources per TDOA-level cell")
    ap.add_argument("--random-arrays", type=int, default=1500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data", default=None, help="shared data folder (default ../shared/data)")
    ap.add_argument("--duration", type=float, default=2.0, help="signal length in seconds")
    args = ap.parse_args(argv)
    trials = args.trials or (2 if args.quick else 10)
    tdoa_trials = 30 if args.quick else args.tdoa_trials
    n_random = 100 if args.quick else args.random_arrays
    data = shared_data_dir(args.data)
    t0 = time.time()
    with threadpool_limits(1):  # (as bench/doa.py: BLAS's idle second thread is no work)
        tdoa_rows, rnd_rows = run_tdoa(tdoa_trials, args.seed + 3106, n_random)
        errors, timing = run_rooms(trials, args.seed, data, args.duration)
        p_errors, p_timing = run_planar(trials, args.seed + 1, data, args.duration)
        s_errors, s_timing = run_rooms(trials, args.seed + 2, data, args.duration,
                                       SPHERE_PLANAR_ARRAYS, mirror_blind_deg)
    tdoa_h = ["array", "range m", "TDOA noise us", "plane wave RMSE deg",
              "hearsee RMSE deg", "answers from the position %"]
    rnd_h = ["random arrays", "plane wave RMSE deg", "hearsee RMSE deg",
             "plane wave median deg", "hearsee median deg", "answers from the position %",
             "hearsee worse by > 10 deg"]
    print_table("TDOA level: plane wave vs hearsee", tdoa_h, tdoa_rows)
    print_table("TDOA level: random arrays", rnd_h, rnd_rows)
    rooms_md = report_rooms(errors, timing, ROOM_ARRAYS, "Rooms", "2",
                            "Recordings in rooms: 3D direction error",
                            "no peer gives one; planar arrays' up to the mirror image",
                            "nmic.png", link_plot=False)  # (its plot heads the report)
    p_h, p_rows, p_pool_h, p_pools, p_won, p_cells, p_cpu = summarize_planar(p_errors, p_timing)
    print_table("Planar arrays of 4 and 6: azimuth error", p_h, p_rows)
    print_table("Planar arrays: pooled", p_pool_h, p_pools)
    print_table("Planar arrays: CPU", CPU_HEADERS, p_cpu)
    print(f"planar: hearsee RMSE <= best pyroomacoustics method in {p_won}/{p_cells} conditions")
    sphere_md = report_rooms(s_errors, s_timing, tuple(SPHERE_PLANAR_ARRAYS),
                             "Planar arrays, whole sphere", "4",
                             "Planar arrays on the whole sphere: mirror-blind 3D direction "
                             "error", "up to the mirror image", "nmic_planar.png",
                             link_plot=True)
    intro = (f"`python bench/nmic.py --trials {trials} --seed {args.seed}"
             f"{' --quick' if args.quick else ''}`; wall time {time.time() - t0:.0f} s on a "
             f"shared 2-core machine. ![nmic](nmic.png)\n\n" + __doc__.split("\n\n", 1)[1])
    path = write_markdown("nmic", [
        ("1. TDOA level: plane wave vs hearsee's answer", markdown_table(tdoa_h, tdoa_rows)),
        ("1b. Random volume arrays", markdown_table(rnd_h, rnd_rows)),
        *rooms_md,
        ("3. Planar arrays of four and six microphones: azimuth error",
         markdown_table(p_h, p_rows)
         + f"\n\nhearsee RMSE <= the best pyroomacoustics method in {p_won}/{p_cells} "
           "conditions."),
        ("3b. Pooled per array and room", markdown_table(p_pool_h, p_pools)),
        ("CPU time per second of audio (part 3; peers on the scored 0.1-deg grid)",
         markdown_table(CPU_HEADERS, p_cpu)),
        *sphere_md,
    ], intro=intro)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
