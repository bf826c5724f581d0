import logging

import numpy as np
import pytest

from hearsee.errors import ConfigError
from hearsee.robot.evaluate import evaluate, summarize


def test_summarize_percentiles_and_rates():
    runs = [{"success": True, "position_error_median_m": e, "false_person_objects": 0}
            for e in (0.05, 0.07, 0.09)] + [{"success": False, "position_error_median_m":
                                             float("nan"), "false_person_objects": 1}]
    s = summarize(runs)
    assert s["scenarios"] == 4 and s["success_rate"] == pytest.approx(0.75)
    assert s["position_error_median_m"]["p50"] == pytest.approx(0.07)
    assert s["position_error_median_m"]["n"] == 3
    assert s["objects_reported_as_person"] == 1


def test_bad_counts_and_durations():
    with pytest.raises(ConfigError):
        evaluate(0)
    with pytest.raises(ConfigError, match="duration"):
        evaluate(1, duration_s=0.5)
    # (was a ValueError; the rule gained an upper bound, MAX_WORKERS)
    with pytest.raises(ConfigError, match=r"--workers must be an integer in \[0, 1024\]"):
        evaluate(1, workers=-1)
    # (numpy ValueError; the rule gained an upper bound, 2**32 - 1 less the count)
    with pytest.raises(ConfigError, match=r"--seed must be an integer in \[0, "):
        evaluate(1, seed0=-5)
    # wrong types: one typed error naming the option (were builtin TypeErrors from comparing a
    # string or None with a number)
    for kw, name in [({"n_scenarios": "3"}, "--scenarios"), ({"duration_s": "5"}, "--duration"),
                     ({"duration_s": None}, "--duration"), ({"workers": 1.5}, "--workers"),
                     ({"seed0": None}, "--seed")]:
        args = {"n_scenarios": 1} | kw
        with pytest.raises(ConfigError, match=f"^{name} must be "):
            evaluate(**args)


def test_duration_range_is_a_scenarios(monkeypatch):
    """evaluate took 2-120 s, a scenario file and random_scenario 1-120 s: a 1.5 s scenario
    file was fine for `hearsee demo`, its length refused by `hearsee eval`. One named range
    now, the same edges everywhere (runs stubbed: what reaches them is checked)."""
    import hearsee.robot.evaluate as ev

    got = []
    monkeypatch.setattr(ev, "run_one",
                        lambda seed, duration_s: got.append(duration_s) or {"seed": seed})
    assert evaluate(2, seed0=5, workers=1, duration_s=1.5).runs == [{"seed": 5}, {"seed": 6}]
    from hearsee.robot.scenario import (  # (the one range, new)
        MAX_DURATION_S,
        MIN_DURATION_S,
        random_scenario,
        scenario_from_dict,
    )

    assert (MIN_DURATION_S, MAX_DURATION_S) == (1.0, 120.0)
    got.clear()
    for d in (MIN_DURATION_S, 1.5, MAX_DURATION_S):
        evaluate(1, workers=1, duration_s=d)
        assert scenario_from_dict({"duration_s": d}).duration_s == d
        assert random_scenario(0, d).duration_s == d
    for d in (np.nextafter(MIN_DURATION_S, 0), np.nextafter(MAX_DURATION_S, 200)):
        with pytest.raises(ConfigError, match=r"^--duration must be a finite number in "
                                              r"\[1, 120\]"):
            evaluate(1, workers=1, duration_s=d)
        with pytest.raises(ConfigError, match="duration_s"):
            scenario_from_dict({"duration_s": float(d)})
        with pytest.raises(ConfigError, match="duration_s"):
            random_scenario(0, d)
    assert got == [MIN_DURATION_S, 1.5, MAX_DURATION_S]


@pytest.mark.parametrize("scheduler", ["not an address", 5])
def test_bad_scheduler_is_a_config_error(scheduler):
    """distributed's own errors for an address it cannot parse or a value of the wrong type
    (ValueError, TypeError) passed through as builtins."""
    pytest.importorskip("distributed")
    with pytest.raises(ConfigError, match=r"^--scheduler .* is not a Dask scheduler address"):
        evaluate(1, scheduler=scheduler)


@pytest.mark.slow
def test_dask_local_cluster_gives_identical_results():
    distributed = pytest.importorskip("distributed")
    local = evaluate(2, seed0=11, workers=1, duration_s=2.5)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  silence_logs=logging.ERROR,
                                  dashboard_address=None) as cluster:
        remote = evaluate(2, seed0=11, scheduler=cluster.scheduler_address, duration_s=2.5)
    assert local.runs == remote.runs
    # the local process pool (spawned workers) gives the same runs as in-process
    assert evaluate(2, seed0=11, workers=2, duration_s=2.5).runs == local.runs
    assert [r["seed"] for r in remote.runs] == [11, 12]
    assert np.isfinite(local.summary["success_rate"])


def test_eval_seeds_are_the_seeds_a_scenario_file_takes(monkeypatch):
    """One seed range: 0 to 2**32 - 1. random_scenario(2**32) and `hearsee eval --seed
    4294967295 -n 2` were accepted, and such a scenario, saved, was refused by
    scenario_from_dict ('scenario.seed: must be <= 4294967295')."""
    import hearsee.robot.evaluate as ev
    from hearsee.robot.scenario import random_scenario, scenario_from_dict

    top = 2**32 - 1
    sc = random_scenario(top, 1.0)
    assert scenario_from_dict(sc.to_dict()).to_dict() == sc.to_dict()
    with pytest.raises(ConfigError, match="seed"):
        scenario_from_dict({**sc.to_dict(), "seed": top + 1})
    with pytest.raises(ConfigError, match="seed"):
        random_scenario(top + 1, 1.0)
    monkeypatch.setattr(ev, "run_one", lambda seed, duration_s: {"seed": seed})
    assert evaluate(2, seed0=top - 1, workers=1).runs == [{"seed": top - 1}, {"seed": top}]
    for seed0, n in ((top, 2), (top + 1, 1), (2**40, 3)):
        with pytest.raises(ConfigError, match=r"^--seed must be an integer in \[0, "):
            evaluate(n, seed0=seed0, workers=1)


@pytest.mark.parametrize("runs", [None, "runs", {"success": True}, [1, 2]])
def test_summarize_refuses_what_is_no_list_of_runs(runs):
    """None was a builtin TypeError."""
    with pytest.raises(ConfigError, match="runs must be a list of run results"):
        summarize(runs)
    assert summarize([{"success": True}])["success_rate"] == 1.0


def test_eval_takes_another_array_for_the_same_scenes(monkeypatch):
    """``array`` (``hearsee eval --array``): the same random scenes with another robot array,
    checked once before any scenario runs (a bad one named --array); every run gets it."""
    from hearsee.robot import evaluate as ev
    from hearsee.robot.scenario import random_scenario

    a, b = random_scenario(4), random_scenario(4, array="mask2-asym")
    assert b.robot.array == "mask2-asym" and a.robot.array != b.robot.array
    da, db = a.to_dict(), b.to_dict()
    da["robot"].pop("array"), db["robot"].pop("array")
    assert da == db  # (the scene is the seed's)
    for bad, msg in (("nope", "unknown array preset"), ("two-mic", "cannot give"),
                     (3, "expected a preset name")):
        with pytest.raises(ConfigError, match=f"^--array.*{msg}"):
            evaluate(2, workers=1, array=bad)
    seen = []
    monkeypatch.setattr(ev, "run_one", lambda seed, duration_s, array: seen.append(
        (seed, array)) or {"seed": seed, "success": True, "position_error_median_m": 0.1,
                           "false_person_objects": 0})
    evaluate(2, seed0=7, workers=1, array="mask2")
    assert seen == [(7, "mask2"), (8, "mask2")]
