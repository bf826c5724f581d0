"""``hearsee eval``: many random scenarios, in parallel on this machine or on a Dask cluster.

Each scenario ``random_scenario(seed0 + k)`` runs the full pipeline without writing a report and
returns its summary metrics. Runs are deterministic per seed: BLAS/OpenCV threads are pinned to
one per worker, so the same seeds give identical numbers on a local process pool, in a single
process, or through ``dask.distributed`` (``scheduler="tcp://host:port"`` or a ``Client``).
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from hearsee.config import finite_number, whole_number
from hearsee.errors import ConfigError, HearseeError
from hearsee.robot.scenario import MAX_DURATION_S, MAX_SEED, MIN_DURATION_S

__all__ = ["MAX_SCENARIOS", "TALKERS", "EvalResult", "evaluate", "run_one", "summarize"]


#: ``talkers`` of :func:`evaluate`: one speaker, or two people taking turns.
TALKERS = (1, 2)


def _check_talkers(talkers: Any) -> None:
    """ConfigError unless ``talkers`` is one of :data:`TALKERS` (a bool is not a count)."""
    if talkers not in TALKERS or isinstance(talkers, bool):
        raise ConfigError(f"--talkers: expected 1 or 2, got {talkers!r}")


def run_one(seed: int, duration_s: float = 6.0, array: str | None = None,
            talkers: int = 1) -> dict[str, Any]:
    """Run random scenario ``seed`` (with the robot's ``array``, default the default
    scenario's: :func:`hearsee.robot.scenario.random_scenario`; with ``talkers`` 2, the
    same scene with a second talker taking turns,
    :func:`hearsee.robot.scenario.random_conversation`) and return its metrics
    (single-threaded, deterministic).

    ``runtime_s`` (wall-clock) is dropped so that results compare exactly across runs."""
    from threadpoolctl import threadpool_limits

    from hearsee.robot.pipeline import run_scenario
    from hearsee.robot.scenario import random_conversation, random_scenario

    _check_talkers(talkers)
    make = random_conversation if talkers == 2 else random_scenario
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:  # pragma: no cover - cv2 is a hard dependency
        pass
    with threadpool_limits(1):
        result = run_scenario(make(seed, duration_s, array), keep_images=False)
    out = {k: v for k, v in result.summary.items() if k != "runtime_s"}
    out["seed"] = int(seed)
    return out


@dataclass
class EvalResult:
    """Per-scenario metrics and their aggregate."""

    runs: list[dict[str, Any]]
    summary: dict[str, Any]


def summarize(runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Success rate and error percentiles over runs (NaN errors are excluded from percentiles);
    ``objects_reported_as_person``: the human-like objects accepted as a person in at least
    one camera frame, summed over the runs (each object of a run counted once);
    ``object_detections_accepted_as_person``: their accepted detections (object x frame);
    ``phantom_detections_accepted``: accepted detections of nothing (summed over the runs);
    ``talker_changes`` / ``talker_changes_followed``: summed over the runs, and
    ``time_to_follow_s`` the percentiles of the runs' ``time_to_follow_median_s`` (runs with
    two people taking turns: ``evaluate(talkers=2)``).
    ConfigError unless ``runs`` is a list of mappings (None was a builtin TypeError)."""
    if isinstance(runs, str | bytes) or not isinstance(runs, Sequence) or \
            not all(isinstance(r, dict) for r in runs):
        raise ConfigError(f"runs must be a list of run results (dicts, as evaluate gives), got "
                          f"{type(runs).__name__}")
    n = len(runs)
    success = [bool(r.get("success", False)) for r in runs]
    out: dict[str, Any] = {"scenarios": n, "success_rate": float(np.mean(success)) if n else 0.0}
    for key, name in (("position_error_median_m", None), ("azimuth_error_initial_deg", None),
                      ("azimuth_error_at_turn_deg", None), ("velocity_rmse_mps", None),
                      ("time_to_verify_s", None),
                      ("time_to_follow_median_s", "time_to_follow_s")):
        # (None, a run without a followed change of talker, is NaN here)
        vals = np.array([np.nan if r.get(key) is None else r[key] for r in runs], dtype=float)
        vals = vals[np.isfinite(vals)]
        out[name or key] = (
            {f"p{q}": float(np.percentile(vals, q)) for q in (50, 75, 90, 95)}
            | {"n": int(len(vals))}
            if len(vals) else {"n": 0}
        )
    # distinct objects summed over the runs (a run's false_person_objects counts each object
    # once; until 2026-12-02 it counted object x frame detections), and those detections
    out["objects_reported_as_person"] = int(
        sum(int(r.get("false_person_objects", 0)) for r in runs))
    for key in ("object_detections_accepted_as_person", "phantom_detections_accepted",
                "talker_changes", "talker_changes_followed"):
        out[key] = int(sum(int(r.get(key, 0)) for r in runs))
    return out


#: Most scenarios one evaluation runs: a million is about 6 CPU-years at ~6 s each (the
#: per-scenario results are held in memory); a larger count is a typo, not a plan.
MAX_SCENARIOS = 1_000_000

#: Most local worker processes (``workers``): more than any machine's cores; 1e20 reached
#: multiprocessing as a C int (an OverflowError traceback).
MAX_WORKERS = 1024


def evaluate(
    n_scenarios: int,
    seed0: int = 0,
    workers: int | None = None,
    scheduler: Any = None,
    progress: Callable[[int], None] | None = None,
    duration_s: float = 6.0,
    array: str | None = None,
    talkers: int = 1,
) -> EvalResult:
    """Run ``n_scenarios`` random scenarios (1 to :data:`MAX_SCENARIOS`) with seeds
    ``seed0 .. seed0 + n - 1``, each at most :data:`hearsee.robot.scenario.MAX_SEED`
    (2**32 - 1, a scenario file's range; else a ConfigError naming --seed).

    Parameters
    ----------
    workers : int, optional
        Local processes, 0 to :data:`MAX_WORKERS` (default or 0: all cores; never more than
        the scenarios). ``1`` runs in this process.
    scheduler : str or distributed.Client, optional
        A Dask scheduler address (``tcp://...``) or a ``Client``; runs there instead.
    progress : callable, optional
        Called with 1 after each finished scenario.
    duration_s : float
        Simulated seconds per scenario, within a scenario's range
        (:data:`hearsee.robot.scenario.MIN_DURATION_S` - ``MAX_DURATION_S``, 1-120 s).
    array : str, optional
        The robot's array in every scenario (a preset name or YAML path; checked before any
        scenario runs), e.g. ``"mask2-asym"``; default the default scenario's (three-mic).
    talkers : int
        1: one speaker (:func:`hearsee.robot.scenario.random_scenario`); 2: the same scenes
        with a second talker, the two taking turns
        (:func:`hearsee.robot.scenario.random_conversation`; try ``duration_s`` 10 or more).
    """
    # (a string or None raised a builtin TypeError from the comparisons; 1e11 a MemoryError)
    n_scenarios = whole_number("--scenarios", n_scenarios, 1, MAX_SCENARIOS)
    # seconds: a scenario's range (a scenario file's duration_s; was 2-120 s here, 1-120 there)
    duration_s = finite_number("--duration", duration_s, MIN_DURATION_S, MAX_DURATION_S)
    if workers is not None:
        workers = whole_number("--workers", workers, 0, MAX_WORKERS)  # (0 = all cores)
    # (every seed a scenario file takes, so that any run can be saved and re-run with
    # `hearsee demo --scenario`; there was no upper bound)
    seed0 = whole_number("--seed", seed0, 0, MAX_SEED - n_scenarios + 1)
    seeds = list(range(seed0, seed0 + n_scenarios))
    _check_talkers(talkers)
    if array is not None:  # (a bad one: one error before the workers start, not one each)
        from hearsee.robot.scenario import random_scenario

        try:
            random_scenario(seeds[0], duration_s, array)
        except HearseeError as exc:
            raise type(exc)(f"--array {array!r}: {exc}") from None
        array = str(Path(array).resolve()) if Path(array).is_file() else array
    job = partial(run_one, duration_s=float(duration_s),
                  **({} if array is None else {"array": array}),
                  **({} if talkers == 1 else {"talkers": int(talkers)}))
    tick = progress or (lambda n=1: None)
    runs: dict[int, dict[str, Any]] = {}
    if scheduler is not None:
        runs = _evaluate_dask(seeds, scheduler, tick, job)
    else:
        workers = min(workers or os.cpu_count() or 1, len(seeds))
        if workers == 1:
            for s in seeds:
                runs[s] = job(s)
                tick(1)
        else:
            # spawn, not fork: a fork taken while BLAS / progress-bar threads hold a lock left
            # the workers waiting forever on it (seen in a 200-scenario run)
            ctx = multiprocessing.get_context("spawn")
            with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
                for s, r in zip(seeds, pool.map(job, seeds), strict=True):
                    runs[s] = r
                    tick(1)
    ordered = [runs[s] for s in seeds]
    return EvalResult(runs=ordered, summary=summarize(ordered))


def _evaluate_dask(seeds: list[int], scheduler: Any, tick: Callable[[int], None],
                   job: Callable[[int], dict[str, Any]]) -> dict:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise ConfigError(
            "--scheduler needs dask.distributed: pip install 'hearsee[dask]'"
        ) from None
    own = not isinstance(scheduler, Client)
    try:
        client = Client(scheduler, timeout="10s") if own else scheduler
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    except (TypeError, ValueError) as exc:  # (distributed's own: not a str, no port, ...)
        raise ConfigError(f"--scheduler {scheduler!r} is not a Dask scheduler address "
                          f"(tcp://HOST:PORT) or Client: {exc}") from None
    try:
        futures = client.map(job, seeds, pure=False)
        index = {f.key: s for f, s in zip(futures, seeds, strict=True)}
        runs = {}
        for fut in as_completed(futures):
            runs[index[fut.key]] = fut.result()
            tick(1)
        return runs
    finally:
        if own:
            client.close()
