"""Thesis ch. 4: 3D localization by turning the head (figs. 4.6-4.8 and 4.13).

Figs. 4.6-4.8: the locus of one pose of the three-microphone array is a 3D curve (two mirror
branches); turning the head gives new curves that meet at the source. Turning only in azimuth
(pan) keeps the up/down mirror of a horizontal array, so the solver reports two candidates;
turning in elevation (tilt) or both makes the point unique.

Fig. 4.13: position error vs the ratio of source distance to array size (TDOA noise 5 us, five
poses turning in both angles -- fig. 4.8's three and two more -- array 10 cm in front of and
5 cm above the pivot).

Run: ``python examples/ch4_active.py [--out DIR]`` -> ch4_fig4_6-8.png, ch4_fig4_13.png (default
folder examples/out)
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hearsee.audio.active import localize_multipose, solve_range_differences  # noqa: E402
from hearsee.audio.arrays import MicArray, load_array  # noqa: E402
from hearsee.geometry import angle_between, mic_positions_at, sph_to_cart  # noqa: E402

ARRAY = load_array("three-mic")
OFFSET = (0.10, 0.0, 0.05)
CASES = {
    "Fig. 4.6: turn in azimuth": [(0, 0), (30, 0), (-30, 0)],
    "Fig. 4.7: turn in elevation": [(0, 0), (0, 25), (0, -25)],
    "Fig. 4.8: turn in both": [(0, 0), (30, 20), (-30, -20)],
}


def locus(pose, tdoa, distances):
    """Points of the one-pose locus (both mirror branches) at the given distances from the
    pivot: the directions whose exact TDOAs at that distance match ``tdoa``."""
    mics = mic_positions_at(ARRAY, pose, offset_m=OFFSET)
    pts = []
    for r in distances:
        est = solve_range_differences([mics], [ARRAY.pairs], [tdoa], tdoa_std_s=1e-6,
                                      distance_bounds_m=(r, r * 1.0001), n_directions=300,
                                      n_starts=4, max_rel_distance_std=np.inf)
        for c in est.candidates:
            if c["cost"] < 1.0:  # exact fit only
                pts.append(sph_to_cart(np.radians(c["azimuth_deg"]),
                                       np.radians(c["elevation_deg"]), r))
    return np.array(pts)


def figs_4_6_to_4_8(out: Path) -> None:
    src = np.array([1.2, 0.7, 0.45])
    dists = np.linspace(0.4, 2.5, 30)
    fig, axes = plt.subplots(2, 3, figsize=(14, 8))
    for col, (title, poses) in enumerate(CASES.items()):
        taus = [MicArray(mic_positions_at(ARRAY, p, offset_m=OFFSET)).tdoa(src) for p in poses]
        est = localize_multipose(taus, poses, ARRAY, offset_m=OFFSET, tdoa_std_s=1e-6)
        for k, (pose, tau) in enumerate(zip(poses, taus, strict=True)):
            P = locus(pose, tau, dists)
            if len(P):
                axes[0, col].plot(P[:, 0], P[:, 1], ".", ms=3, color=f"C{k}",
                                  label=f"pose pan {pose[0]}, tilt {pose[1]}")
                axes[1, col].plot(P[:, 0], P[:, 2], ".", ms=3, color=f"C{k}")
        for row, (i, j) in enumerate(((0, 1), (0, 2))):
            axes[row, col].plot(src[i], src[j], "k*", ms=14, label="source" if row == 0 else None)
            for c in est.candidates:
                if c["position_m"] is not None:
                    axes[row, col].plot(c["position_m"][i], c["position_m"][j], "rx", ms=10)
            axes[row, col].set(xlabel="x (m)", ylabel="yz"[row] + " (m)")
            axes[row, col].set_aspect("equal", adjustable="datalim")
        verdict = "unique" if est.unique else f"NOT unique: {len(est.candidates)} candidates"
        axes[0, col].set_title(f"{title}\n{verdict}", fontsize=10)
        axes[0, col].legend(fontsize=7)
        els = ", ".join(f"{c['elevation_deg']:.1f}" for c in est.candidates)
        print(f"{title}: {verdict}; candidate elevations {els} deg (true "
              f"{np.degrees(np.arctan2(src[2], np.hypot(*src[:2]))):.1f}); distance "
              f"{est.distance_m if est.distance_m is None else round(est.distance_m, 3)} m "
              f"(true {np.linalg.norm(src):.3f})")
    fig.suptitle("Loci of single poses (top: plan view x-y, bottom: side view x-z); "
                 "red x = solver candidates")
    fig.tight_layout()
    fig.savefig(out / "ch4_fig4_6-8.png", dpi=90)
    plt.close(fig)


def fig_4_13(out: Path, n: int = 25, sigma: float = 5e-6) -> None:
    rng = np.random.default_rng(0)
    poses = CASES["Fig. 4.8: turn in both"] + [(30, -20), (-30, 20)]
    D = ARRAY.aperture
    ratios = np.array([3, 5, 8, 12, 16, 20, 27, 35])
    med_pos, med_dir, reported = [], [], []
    for q in ratios:
        e_pos, e_dir, rep = [], [], 0
        for _ in range(n):
            az = rng.uniform(-np.pi / 3, np.pi / 3)
            el = rng.uniform(-0.3, 0.6)
            src = sph_to_cart(az, el, q * D)
            taus = [MicArray(mic_positions_at(ARRAY, p, offset_m=OFFSET)).tdoa(src)
                    + rng.normal(0, sigma, 3) for p in poses]
            est = localize_multipose(taus, poses, ARRAY, offset_m=OFFSET, tdoa_std_s=sigma,
                                     distance_bounds_m=(0.2, 30.0))
            e_dir.append(float(np.degrees(angle_between(est.direction, src))))
            if est.position_m is not None:
                rep += 1
                e_pos.append(np.linalg.norm(est.position_m - src) / np.linalg.norm(src) * 100)
        med_pos.append(np.median(e_pos) if e_pos else np.nan)
        med_dir.append(np.median(e_dir))
        reported.append(rep / n * 100)
        print(f"distance/array size {q:3d} ({q * D:.2f} m): median 3D error "
              f"{med_pos[-1]:.1f}% of distance (distance reported in {reported[-1]:.0f}%), "
              f"direction {med_dir[-1]:.2f} deg")
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    ax[0].plot(ratios, med_pos, "o-", label="median 3D error (% of distance)")
    ax[0].plot(ratios, reported, "s--", label="distance reported (%)")
    ax[0].set(xlabel="distance / array size", ylabel="%", title="Fig. 4.13: effect of the "
              "distance-to-dimension ratio")
    ax[0].legend()
    ax[1].plot(ratios, med_dir, "o-")
    ax[1].set(xlabel="distance / array size", ylabel="median direction error (deg)")
    fig.tight_layout()
    fig.savefig(out / "ch4_fig4_13.png", dpi=90)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "out"),
                    help="output folder (default: examples/out)")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    figs_4_6_to_4_8(out)
    fig_4_13(out)
    print(f"wrote {out / 'ch4_fig4_6-8.png'} and {out / 'ch4_fig4_13.png'}")


if __name__ == "__main__":
    main()
