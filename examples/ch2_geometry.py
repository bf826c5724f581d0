"""Thesis chapter 2 figures: ITD loci of two- and three-microphone systems.

Regenerates, into ``--out`` (default ``examples/out/``):

* ``fig2_3_hyperboloids.png`` -- fig. 2.3: the near-field loci (hyperboloid sheets) of a
  two-microphone system (thesis frame: m1 = [0, -r, 0], m2 = [0, r, 0], r = 7.5 cm) for several
  ITDs, with the far-field cones they approach;
* ``fig2_6_three_mic_curve.png`` -- fig. 2.6: the two hyperboloids of a three-microphone system
  and their intersection, the 3-D curve on which the source must lie (both mirror branches);
* ``table2_1_differential_time.md`` / ``.png`` -- table 2.1: the differential time
  distribution, i.e. how the measurable (whole-sample) ITDs are distributed over directions:
  for each ITD value, the azimuth sector it covers and its width. Sectors are narrow near
  broadside and wide toward the microphone axis, so the direction resolution is uneven.

Usage: ``python examples/ch2_geometry.py [--out DIR] [--fs 16000]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import cone_points, hyperboloid_points, three_mic_curve  # noqa: E402
from hearsee.geometry import unit_vector_deg  # noqa: E402


def fig_2_3(out: Path) -> Path:
    arr = MicArray.from_preset("two-mic")
    m1, m2 = arr.positions
    c = arr.speed_of_sound
    dmax = arr.max_tdoa()[0]
    fig = plt.figure(figsize=(12, 5.5))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    colors = plt.cm.coolwarm(np.linspace(0, 1, 5))
    for frac, col in zip((-0.8, -0.4, 0.0, 0.4, 0.8), colors, strict=True):
        tau = frac * dmax
        h = hyperboloid_points(tau, m1, m2, c, extent_m=1.0, n_radial=20, n_around=36)
        ax.plot_surface(h[..., 0], h[..., 1], h[..., 2], color=col, alpha=0.45, linewidth=0)
    ax.scatter(*arr.positions.T, color="k", s=40)
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]",
           title="Fig. 2.3: hyperboloids |P-m1|-|P-m2| = c dt\n(dt = -0.8 .. 0.8 of the maximum)")
    ax.set_box_aspect((1, 1, 1))
    # a horizontal cut: hyperbolas and their asymptotic cones (far field)
    ax2 = fig.add_subplot(1, 2, 2)
    for frac, col in zip((-0.8, -0.4, 0.0, 0.4, 0.8), colors, strict=True):
        tau = frac * dmax
        h = hyperboloid_points(tau, m1, m2, c, extent_m=1.2, n_radial=60, n_around=73)
        k0 = np.argmin(np.abs(np.linspace(0, 2 * np.pi, 73) - 0.0))
        k1 = np.argmin(np.abs(np.linspace(0, 2 * np.pi, 73) - np.pi))
        for k in (k0, k1):
            ax2.plot(h[:, k, 0], h[:, k, 1], color=col, lw=2)
        cone = cone_points(tau, m1, m2, c, extent_m=1.2, n_radial=2, n_around=73)
        for k in (k0, k1):
            ax2.plot(cone[:, k, 0], cone[:, k, 1], color=col, lw=1, ls="--")
        ax2.annotate(f"{tau * 1e6:+.0f} us", h[-1, k0, :2], fontsize=8, color=col)
    ax2.plot(*arr.positions[:, :2].T, "ko")
    ax2.plot([], [], color="grey", lw=2, label="hyperbola (exact, near field)")
    ax2.plot([], [], color="grey", lw=1, ls="--", label="cone line (far-field asymptote)")
    ax2.legend(fontsize=8, loc="upper center")  # (between the branches: nothing there)
    ax2.set(xlabel="x [m] (forward)", ylabel="y [m] (left)", aspect="equal",
            title="Horizontal plane: hyperbolas and their far-field\ncone lines (apart only "
            "near the pair); front/back mirror about the y axis")
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    path = out / "fig2_3_hyperboloids.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def fig_2_6(out: Path) -> Path:
    arr = MicArray.from_preset("three-mic")
    c = arr.speed_of_sound
    src = 1.5 * unit_vector_deg(40.0, 25.0)
    tau = arr.tdoa(src)
    p = arr.positions
    fig = plt.figure(figsize=(7, 6.5))
    ax = fig.add_subplot(projection="3d")
    for (i, j), col in zip([(0, 1), (0, 2)], ("tab:blue", "tab:green"), strict=True):
        t = arr.tdoa(src, [(i, j)])[0]
        h = hyperboloid_points(t, p[i], p[j], c, extent_m=2.0, n_radial=25, n_around=40)
        ax.plot_surface(h[..., 0], h[..., 1], h[..., 2], color=col, alpha=0.18, linewidth=0)
    for b, name in zip(three_mic_curve(tau, arr, ranges_m=np.linspace(0.25, 2.2, 40)),
                       ("branch above the array plane", "mirror branch below"), strict=False):
        ax.plot(b[:, 0], b[:, 1], b[:, 2], lw=3, label=name)
    ax.scatter(*src, color="r", s=60, label="source")
    ax.scatter(*p.T, color="k", s=30, label="microphones")
    ax.set(xlabel="x [m]", ylabel="y [m]", zlabel="z [m]",
           title="Fig. 2.6: three microphones -- two hyperboloids\nintersect in a 3-D curve")
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = out / "fig2_6_three_mic_curve.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def table_2_1(out: Path, fs: float) -> tuple[Path, Path]:
    """ITD (whole samples) -> azimuth sectors, for the two-mic pair and one three-mic pair."""
    az = np.linspace(-180.0, 180.0, 72001)
    u = unit_vector_deg(az, 0.0)
    lines = [
        "# Table 2.1 -- differential time distribution",
        "",
        f"Sample rate {fs:g} Hz, far field, sources in the horizontal plane. Each whole-sample ITD "
        "(what an unrefined GCC peak can report) covers an azimuth sector; its width is the "
        "direction resolution there. Front half-plane (-90..90 deg) shown; the back mirrors it.",
        "",
    ]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    for ax, (name, pair) in zip(axes, (("two-mic", (0, 1)), ("three-mic", (1, 2))), strict=True):
        arr = MicArray.from_preset(name)
        itd = arr.tdoa_far(u, [pair])[:, 0] * fs
        k = np.round(itd).astype(int)
        front = np.abs(az) <= 90
        lines += [f"## {name}, pair {pair[0]}-{pair[1]} "
                  f"({arr.pair_distance([pair])[0] * 100:.1f} cm)", "",
                  "| ITD [samples] | ITD [us] | azimuth from [deg] | to [deg] | width [deg] |",
                  "|---|---|---|---|---|"]
        for v in range(k[front].min(), k[front].max() + 1):
            sel = front & (k == v)
            if not sel.any():
                continue
            a0, a1 = az[sel].min(), az[sel].max()
            lines.append(f"| {v:+d} | {v / fs * 1e6:+.1f} | {a0:.1f} | {a1:.1f} | {a1 - a0:.1f} |")
        lines.append("")
        ax.hist(itd[front], bins=200, density=True, color="tab:blue", alpha=0.7)
        ax.set(xlabel="ITD [samples]", ylabel="density over uniform azimuths",
               title=f"{name} pair {pair[0]}-{pair[1]}: ITD distribution "
               f"(fs = {fs / 1000:g} kHz)")
        # (the boundaries between integer delays, on both sides of the extreme ones)
        for v in range(int(np.floor(itd.min())) - 1, int(np.ceil(itd.max())) + 1):
            ax.axvline(v + 0.5, color="k", lw=0.3)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    png = out / "table2_1_differential_time.png"
    fig.savefig(png, dpi=110)
    plt.close(fig)
    md = out / "table2_1_differential_time.md"
    md.write_text("\n".join(lines), encoding="utf-8")
    return md, png


def _sample_rate(text: str) -> float:
    """--fs: a finite rate > 0 (0 raised ZeroDivisionError, NaN a numpy ValueError, and a
    negative rate wrote a table whose -7 samples were +437.5 us)."""
    try:
        fs = float(text)
    except ValueError:
        fs = float("nan")
    if not (np.isfinite(fs) and fs > 0):
        raise argparse.ArgumentTypeError(f"expected a sample rate > 0 (Hz), got {text!r}")
    return fs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "out"),
                    help="output folder (default: examples/out)")
    ap.add_argument("--fs", type=_sample_rate, default=16000.0,
                    help="sample rate for table 2.1 (Hz)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ignore = out / ".gitignore"
    if out.resolve() == (Path(__file__).parent / "out").resolve() and not ignore.exists():
        ignore.write_text("*\n")  # generated files stay out of git
    for p in (fig_2_3(out), fig_2_6(out), *table_2_1(out, args.fs)):
        print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
