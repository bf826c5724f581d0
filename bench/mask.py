"""Benchmark: 360-degree azimuth with a masked two-microphone array vs a bare pair (thesis ch. 3).

All in one process on the same inputs. For every trial a source is drawn at a random azimuth in
the horizontal plane (far field, or near field at d0 = 1 m / 0.5 m); the same source signal and
the same sensor-noise seed are recorded

* through the ``mask2`` array (the BEM transfer functions,
  :func:`hearsee.audio.mask.simulate_masked`) and localized with
  :func:`hearsee.audio.mask.localize_mask` (one 360-degree azimuth);
* through the same mask with a *model mismatch* (front 5 mm longer, 2 mm taller, a 1280-panel
  mesh instead of 980 panels) and still localized with the nominal ``mask2`` tables -- so the
  numbers are not only the "inverse crime" of simulating and inverting with the same model;
* through a bare two-microphone array (``two-mic``, same microphone positions, free field) and
  localized with hearsee's ITD core (:func:`hearsee.audio.localize.localize_recording`); a bare
  pair can only guess front/back (it returns the front candidate first).

Front/back is "correct" unless the estimate is closer to the mirror image ``180 - az`` than to
the true azimuth and more than 10 deg from the truth (a front/back confusion). Reported per
signal (white noise, synthetic male and female voices), field and SNR: front/back correct rate,
360-degree azimuth RMSE, median absolute error, the RMSE of the sources more than 3 deg off the
median plane (diagnostic: at 0 / 180 deg a left/right symmetric mask has ITD = IID = 0 for the
source and its mirror alike), mean front/back confidence. Targets (issue 3):
front/back >= 95 % at SNR >= 10 dB for broadband sources, RMSE <= 5 deg at SNR >= 20 dB.

Run ``python bench/mask.py`` (about 5 min on 2 cores once the mask models are cached; the first
run solves the BEM for both masks, a few minutes more) or ``--quick``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import RESULTS, markdown_table, print_table, write_markdown  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import localize_recording  # noqa: E402
from hearsee.audio.mask import MaskModel, localize_mask, simulate_masked  # noqa: E402
from hearsee.audio.propagation import simulate_free_field  # noqa: E402
from hearsee.audio.signals import synthetic_voice, white_noise  # noqa: E402
from hearsee.config import load_yaml  # noqa: E402

FS = 16000
SIGNALS = ("noise", "male", "female")
FIELDS = ("far", "near")


def perturbed_mask2() -> MicArray:
    """mask2 with a 5 mm longer front, 2 mm taller body and a finer (1280-panel) mesh."""
    d = load_yaml(Path(MicArray.from_preset.__func__.__globals__["_preset_dir"]()) / "mask2.yaml")
    d["name"] = "mask2-perturbed"
    d["mask"].update(front=0.125, half_height=0.082, mesh_subdivision=8)
    return MicArray.from_dict(d, where="mask2-perturbed")


def angdiff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0


def fb_correct(est: np.ndarray, true: np.ndarray) -> np.ndarray:
    """False for a front/back confusion: the estimate is nearer the mirror image ``180 - az``
    than the truth, and more than 10 deg from the truth (near the lateral axis, where the two
    coincide, small errors are not confusions)."""
    e_true = np.abs(angdiff(est, true))
    return (e_true <= np.abs(angdiff(est, (180.0 - true) % 360.0))) | (e_true <= 10.0)


def make_signal(kind: str, duration: float, rng: np.random.Generator) -> np.ndarray:
    if kind == "noise":
        return white_noise(duration, FS, rng)
    return synthetic_voice(kind, duration, FS, rng)


def run(trials: int, snrs: list[float], duration: float, seed: int, mismatch: bool) -> list[dict]:
    model = MaskModel("mask2")
    pert = MaskModel(perturbed_mask2()) if mismatch else None
    bare = MicArray.from_preset("two-mic")
    assert np.allclose(bare.positions, model.array.positions)
    rows = []
    for kind in SIGNALS:
        for fld in FIELDS:
            for snr in snrs:
                rng = np.random.default_rng([seed, SIGNALS.index(kind), FIELDS.index(fld),
                                             int(snr)])
                res: dict[str, list] = {k: [] for k in ("true", "mask", "conf", "mis", "bare")}
                cpu = 0.0
                for _ in range(trials):
                    az = rng.uniform(0.0, 360.0)
                    u = np.array([np.cos(np.radians(az)), np.sin(np.radians(az)), 0.0])
                    far = fld == "far"
                    src = u if far else u * rng.choice([1.0, 0.5])
                    sig = make_signal(kind, duration, rng)
                    nseed = int(rng.integers(2**31))
                    x = simulate_masked(sig, FS, model, src, snr, nseed, far_field=far)
                    t0 = time.process_time()
                    est = localize_mask(x, FS, model)
                    cpu += time.process_time() - t0
                    res["true"].append(az)
                    res["mask"].append(est.azimuth_deg)
                    res["conf"].append(est.confidence)
                    if pert is not None:
                        xm = simulate_masked(sig, FS, pert, src, snr, nseed, far_field=far)
                        res["mis"].append(localize_mask(xm, FS, model).azimuth_deg)
                    xb = simulate_free_field(sig, FS, bare, src, snr, nseed, far_field=far)
                    doc = localize_recording(xb, FS, bare, kalman=False)
                    a = doc["summary"]["azimuth_deg"]
                    res["bare"].append(np.nan if a is None else a % 360.0)
                true = np.array(res["true"])
                row = {"signal": kind, "field": fld, "snr": snr, "n": trials,
                       "cpu_ms": 1000 * cpu / trials / duration}
                for name in ("mask", "mis", "bare"):
                    if not res[name]:
                        continue
                    e = np.array(res[name], float)
                    ok = np.isfinite(e)
                    err = np.abs(angdiff(e[ok], true[ok]))
                    row[f"{name}_fb"] = 100.0 * np.mean(fb_correct(e[ok], true[ok])) if ok.any() \
                        else float("nan")
                    row[f"{name}_rmse"] = float(np.sqrt(np.mean(err**2))) if ok.any() else np.nan
                    row[f"{name}_med"] = float(np.median(err)) if ok.any() else np.nan
                # diagnostic: the median plane (within 3 deg of 0 / 180 deg) is where a left/right
                # symmetric mask cannot tell front from back (ITD = IID = 0 for both)
                off = np.abs(np.sin(np.radians(true))) > np.sin(np.radians(3.0))
                e = np.abs(angdiff(np.array(res["mask"]), true))[off]
                row["mask_rmse_off"] = float(np.sqrt(np.mean(e**2))) if len(e) else np.nan
                row["conf"] = float(np.mean(res["conf"]))
                rows.append(row)
                print(f"{kind:6s} {fld:4s} {snr:4.0f} dB  mask fb {row['mask_fb']:5.1f}% rmse "
                      f"{row['mask_rmse']:6.2f}  bare fb {row['bare_fb']:5.1f}%", flush=True)
    return rows


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    for kind in SIGNALS:
        for fld, ls in zip(FIELDS, ("-", "--"), strict=True):
            rr = [r for r in rows if r["signal"] == kind and r["field"] == fld]
            s = [r["snr"] for r in rr]
            ax[0].plot(s, [r["mask_fb"] for r in rr], ls, marker="o", label=f"mask2 {kind} {fld}")
            ax[1].semilogy(s, [max(r["mask_rmse"], 1e-2) for r in rr], ls, marker="o",
                           label=f"mask2 {kind} {fld}")
    for kind in SIGNALS:
        rr = [r for r in rows if r["signal"] == kind and r["field"] == "far"]
        ax[0].plot([r["snr"] for r in rr], [r["bare_fb"] for r in rr], ":", color="grey",
                   marker="x", label=f"bare pair {kind}" if kind == "noise" else None)
    ax[0].axhline(95, color="k", lw=0.8)
    ax[0].set_ylim(0, 105)
    ax[0].set_xlabel("SNR (dB)")
    ax[0].set_ylabel("front/back correct (%)")
    ax[1].axhline(5, color="k", lw=0.8)
    ax[1].set_xlabel("SNR (dB)")
    ax[1].set_ylabel("360-degree azimuth RMSE (deg)")
    ax[0].legend(fontsize=7)
    fig.suptitle("mask2 (BEM mask, 2 microphones) vs bare two-microphone pair")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=20, help="sources per condition")
    ap.add_argument("--snrs", default="0,10,20,30")
    ap.add_argument("--duration", type=float, default=1.0, help="seconds per recording")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--no-mismatch", action="store_true", help="skip the perturbed-mask column")
    ap.add_argument("--quick", action="store_true", help="6 trials, SNR 10 and 20 dB")
    a = ap.parse_args(argv)
    snrs = [float(s) for s in a.snrs.split(",")]
    trials = a.trials
    if a.quick:
        trials, snrs = 6, [10.0, 20.0]
    t0 = time.time()
    rows = run(trials, snrs, a.duration, a.seed, not a.no_mismatch)
    mis = not a.no_mismatch
    headers = ["signal", "field", "SNR dB", "n", "mask2 F/B %", "mask2 RMSE", "mask2 median",
               "RMSE off median plane", "F/B conf"]
    if mis:
        headers += ["mismatch F/B %", "mismatch RMSE", "mismatch median"]
    headers += ["bare F/B %", "bare RMSE", "bare median", "mask CPU ms/s"]
    table = []
    for r in rows:
        line = [r["signal"], r["field"], r["snr"], r["n"], r["mask_fb"], r["mask_rmse"],
                r["mask_med"], r["mask_rmse_off"], r["conf"]]
        if mis:
            line += [r["mis_fb"], r["mis_rmse"], r["mis_med"]]
        line += [r["bare_fb"], r["bare_rmse"], r["bare_med"], r["cpu_ms"]]
        table.append(line)
    print_table("mask2 vs bare two-mic: 360-degree azimuth", headers, table)
    # targets
    bb = [r for r in rows if r["signal"] == "noise" and r["snr"] >= 10]
    hi = [r for r in rows if r["snr"] >= 20]
    voices10 = [r for r in rows if r["signal"] != "noise" and r["snr"] >= 10]
    summary = [
        ["front/back >= 95 % at SNR >= 10 dB, white noise (mask2)",
         f"min {min(r['mask_fb'] for r in bb):.1f} %"],
        ["360-deg RMSE <= 5 deg at SNR >= 20 dB, white noise (mask2)",
         f"max {max(r['mask_rmse'] for r in hi if r['signal'] == 'noise'):.2f} deg"],
        ["360-deg RMSE at SNR >= 20 dB, voices (mask2)",
         f"max {max(r['mask_rmse'] for r in hi if r['signal'] != 'noise'):.2f} deg"],
        ["same, sources more than 3 deg off the median plane (voices)",
         f"max {max(r['mask_rmse_off'] for r in hi if r['signal'] != 'noise'):.2f} deg"],
        ["front/back at SNR >= 10 dB, voices (mask2)",
         f"min {min(r['mask_fb'] for r in voices10):.1f} %"],
        ["bare pair front/back (all conditions)",
         f"mean {np.nanmean([r['bare_fb'] for r in rows]):.1f} %"],
    ]
    if mis:
        summary.insert(2, ["same, with model mismatch (white noise)",
                           f"F/B min {min(r['mis_fb'] for r in bb):.1f} %, RMSE max "
                           f"{max(r['mis_rmse'] for r in hi if r['signal'] == 'noise'):.2f} deg"])
    print_table("targets (issue 3)", ["target", "measured"], summary)
    RESULTS.mkdir(parents=True, exist_ok=True)
    png = RESULTS / "mask.png"
    plot(rows, png)
    md = write_markdown("mask", [
        ("Targets", markdown_table(["target", "measured"], summary)),
        ("Results", markdown_table(headers, table)),
        ("Plot", f"![mask]({png.name})"),
    ], intro=(__doc__.split("\n\n")[0] + f"\n\nRun: `python bench/mask.py` (trials={trials}, "
              f"duration={a.duration} s, fs={FS} Hz, seed={a.seed}); wall time "
              f"{time.time() - t0:.0f} s."))
    print(f"wrote {md} and {png}")


if __name__ == "__main__":
    main()
