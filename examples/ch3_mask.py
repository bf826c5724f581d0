"""Thesis ch. 3 regenerated: the mask2 diffraction model, its ITD/IID responses and 360-degree
azimuth estimates (figs. 3.6-3.17, tables 3.3/3.4).

    python examples/ch3_mask.py                  # figures and tables in examples/out/
    python examples/ch3_mask.py --array mask2-asym --out ch3_asym   # the asymmetric design

Also writes ``front_back_margin.png``: the design measure
:func:`hearsee.audio.mask.front_back_margin` over azimuth for mask2 (left/right symmetric: zero at
0 and 180 deg) and mask2-asym (turned, blunter egg: positive everywhere).

The first run solves the BEM of the mask (about 3 minutes on 2 cores; cached afterwards in
``~/.cache/hearsee/mask``, see ``hearsee.audio.mask``). Writes PNG figures and
``tables_3_3_3_4.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hearsee.audio.mask import (  # noqa: E402
    MaskModel,
    front_back_margin,
    localize_mask,
    simulate_masked,
)
from hearsee.audio.signals import synthetic_voice, white_noise  # noqa: E402

FS = 16000


def _u(az_deg: float) -> np.ndarray:
    return np.array([np.cos(np.radians(az_deg)), np.sin(np.radians(az_deg)), 0.0])


def fig_mask(m: MaskModel, out: Path) -> None:
    """Fig. 3.2: the mask (BEM mesh) and the two microphones."""
    fig = plt.figure(figsize=(6, 5))
    ax = fig.add_subplot(projection="3d")
    v, f = m.mesh.vertices, m.mesh.faces
    ax.plot_trisurf(v[:, 0], v[:, 1], v[:, 2], triangles=f, color="lightgrey", edgecolor="grey",
                    linewidth=0.2, alpha=0.6)
    p = m.array.positions
    ax.scatter(p[:, 0], p[:, 1], p[:, 2], color="red", s=40, depthshade=False)
    ax.quiver(0.16, 0, 0, 0.05, 0, 0, color="k")
    ax.set_xlabel("x (m, front)")
    ax.set_ylabel("y (m, left)")
    ax.set_zlabel("z (m)")
    ax.set_box_aspect(np.ptp(v, axis=0))
    ax.set_title(f"fig. 3.2: {m.array.name}, {m.mesh.n_panels} panels, microphones in red")
    fig.tight_layout()
    fig.savefig(out / "fig3_02_mask.png", dpi=110)
    plt.close(fig)


def fig_sphere_validation(out: Path) -> None:
    """Validation: the same BEM on a rigid sphere vs the Rayleigh series (Duda & Martens 1998)."""
    from hearsee.audio import bem

    a = 0.0875
    mesh = bem.sphere_mesh(a, 6)
    mics = np.array([[0.0, -a, 0.0], [0.0, a, 0.0]])
    freqs = np.array([500.0, 1500.0, 3000.0])
    sol = bem.solve_adjoint(mesh, freqs, mics, on_surface_tol=1e-3)
    az = np.arange(0, 361, 5.0)
    u = np.stack([_u(x) for x in az])
    h = bem.transfer_functions(sol, u, far_field=True)
    e0 = bem.sphere_transfer(freqs, a, u @ (mics[0] / a)).T
    e1 = bem.sphere_transfer(freqs, a, u @ (mics[1] / a)).T
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for k, f in enumerate(freqs):
        ax[0].plot(az, 20 * np.log10(np.abs(e0[:, k] / e1[:, k])), color=f"C{k}",
                   label=f"series {f:.0f} Hz")
        ax[0].plot(az, 20 * np.log10(np.abs(h[:, 0, k] / h[:, 1, k])), "o", ms=3,
                   color=f"C{k}", label=f"BEM {f:.0f} Hz")
        w = 2 * np.pi * f
        ax[1].plot(az, 1e6 * np.angle(e0[:, k] * np.conj(e1[:, k])) / w, color=f"C{k}")
        ax[1].plot(az, 1e6 * np.angle(h[:, 0, k] * np.conj(h[:, 1, k])) / w, "o", ms=3,
                   color=f"C{k}")
    ax[0].set_ylabel("IID (dB)")
    ax[1].set_ylabel("interaural phase delay (us)")
    for x in ax:
        x.set_xlabel("azimuth (deg)")
        x.grid(alpha=0.3)
    ax[0].legend(fontsize=7, ncol=2)
    fig.suptitle(f"rigid sphere r = {a} m: BEM ({mesh.n_panels} panels) vs Rayleigh series")
    fig.tight_layout()
    fig.savefig(out / "validation_sphere.png", dpi=110)
    plt.close(fig)


def fig_waveforms(m: MaskModel, out: Path) -> None:
    """Figs. 3.6-3.8: computed impulse responses and a 500 Hz tone burst at both microphones."""
    fig, ax = plt.subplots(2, 2, figsize=(11, 6), sharex="col")
    n = 96
    t = 1000 * np.arange(n) / FS
    burst_t = np.arange(int(0.012 * FS)) / FS
    burst = np.sin(2 * np.pi * 500 * burst_t) * np.hanning(len(burst_t))
    for row, (az, name) in enumerate(((30.0, "front, 30 deg"), (150.0, "back, 150 deg"))):
        ir = m.impulse_responses(_u(az), FS, n, far_field=True)
        ax[row, 0].plot(t, ir[0], label="mic 0 (right)")
        ax[row, 0].plot(t, ir[1], label="mic 1 (left)")
        ax[row, 0].set_title(f"impulse responses, {name} (figs. 3.6-3.7)", fontsize=10)
        y = simulate_masked(np.concatenate([burst, np.zeros(200)]), FS, m, _u(az), far_field=True)
        tt = 1000 * np.arange(y.shape[1]) / FS
        for k in range(2):
            ax[row, 1].plot(tt, y[k], label=f"mic {k}")
            on = np.argmax(np.abs(y[k]) > 0.05 * np.abs(y[k]).max())
            ax[row, 1].axvline(tt[on], color=f"C{k}", ls=":")
            ax[row, 1].axhline(np.abs(y[k]).max(), color=f"C{k}", lw=0.6)
        ax[row, 1].set_title(f"500 Hz burst, onsets and amplitudes, {name} (fig. 3.8)",
                             fontsize=10)
    for a in ax.ravel():
        a.legend(fontsize=7)
    ax[1, 0].set_xlabel("time (ms)")
    ax[1, 1].set_xlabel("time (ms)")
    for a in ax.ravel():
        a.set_ylabel("pressure (a.u.)")  # (simulated, relative to the free-field source)
    fig.tight_layout()
    fig.savefig(out / "fig3_06-08_waveforms.png", dpi=110)
    plt.close(fig)


def fig_itd_iid_derivation(m: MaskModel, out: Path) -> None:
    """Fig. 3.9: ITD from the cross-correlation peak and IID from the energy ratio."""
    x = simulate_masked(white_noise(0.25, FS, 1), FS, m, _u(30.0), far_field=True)
    n = x.shape[1]
    r = np.fft.irfft(np.fft.rfft(x[0], 2 * n) * np.conj(np.fft.rfft(x[1], 2 * n)))
    lags = np.arange(-40, 41)
    cc = r[lags % (2 * n)]
    itd = lags[np.argmax(cc)] / FS
    iid = 10 * np.log10(np.mean(x[0] ** 2) / np.mean(x[1] ** 2))
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(1e3 * lags / FS, cc / cc.max())
    ax.axvline(1e3 * itd, color="k", ls=":")
    ax.set_xlabel("lag t_0 - t_1 (ms)")
    ax.set_ylabel("cross-correlation (normalised)")
    ax.set_title(f"alpha = 30 deg: ITD = {itd * 1e6:.0f} us, IID = {iid:.1f} dB (fig. 3.9)")
    fig.tight_layout()
    fig.savefig(out / "fig3_09_itd_iid.png", dpi=110)
    plt.close(fig)


def fig_responses(m: MaskModel, out: Path) -> None:
    """Figs. 3.10-3.11 (far field), 3.14-3.17 (d0 = 1 m and 0.5 m): ITD and band IIDs, front and
    back, over the lateral angle."""
    names = {None: ("3_10", "3_11", "far field"), 1.0: ("3_14", "3_15", "d0 = 1 m"),
             0.5: ("3_16", "3_17", "d0 = 0.5 m")}
    for dist, (ff, fb, label) in names.items():
        r = m.responses(dist)
        az = r.azimuth_deg
        for fig_id, half, sel in ((ff, "front", (az <= 90) | (az >= 270)),
                                  (fb, "back", (az >= 90) & (az <= 270))):
            a = az[sel]
            order = np.argsort(((a + 90) % 360) if half == "front" else a)
            a = a[order]
            fig, ax = plt.subplots(1, 2, figsize=(11, 4))
            ax[0].plot(a if half == "back" else ((a + 180) % 360) - 180,
                       1e6 * r.itd_s[sel][order])
            ax[0].set_ylabel("ITD t_0 - t_1 (us)")
            for b in range(r.iid_db.shape[1]):
                lo, hi = r.band_edges_hz[b], r.band_edges_hz[b + 1]
                ax[1].plot(a if half == "back" else ((a + 180) % 360) - 180,
                           r.iid_db[sel][order, b], label=f"{lo:.0f}-{hi:.0f} Hz")
            ax[1].set_ylabel("IID 10 log10(E_0/E_1) (dB)")
            ax[1].legend(fontsize=7, ncol=2)
            for x in ax:
                x.set_xlabel("azimuth (deg)")
                x.grid(alpha=0.3)
            fig.suptitle(f"fig. {fig_id.replace('_', '.')}: ITD and IID response, {half}, {label}")
            fig.tight_layout()
            fig.savefig(out / f"fig{fig_id}_response_{half}_{label.replace(' ', '')}.png",
                        dpi=110)
            plt.close(fig)


def fig_front_back(m: MaskModel, out: Path) -> None:
    """Fig. 3.12: IID(alpha) vs IID(180 - alpha) at w = 1000 pi rad/s (500 Hz) and band 2-4 kHz."""
    alpha = np.arange(-90, 91, 2.0)
    src = np.stack([_u(a) for a in alpha])
    mir = np.stack([_u(180 - a) for a in alpha])
    k500 = int(np.argmin(np.abs(m.freqs - 500.0)))
    hf, hb = m.transfer(src, far_field=True), m.transfer(mir, far_field=True)
    iid = lambda h, sel: 10 * np.log10(np.sum(np.abs(h[:, 0, sel]) ** 2, -1)  # noqa: E731
                                       / np.sum(np.abs(h[:, 1, sel]) ** 2, -1))
    hiband = (m.freqs >= 2000) & (m.freqs <= 4000)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    for a_, sel, title in ((ax[0], np.arange(len(m.freqs)) == k500, "500 Hz (w = 1000 pi)"),
                           (ax[1], hiband, "2-4 kHz band")):
        a_.plot(alpha, iid(hf, sel), label="front: alpha")
        a_.plot(alpha, iid(hb, sel), label="back: 180 - alpha")
        a_.set_xlabel("alpha (deg)")
        a_.set_ylabel("IID (dB)")
        a_.set_title(title)
        a_.legend()
        a_.grid(alpha=0.3)
    fig.suptitle("fig. 3.12: front/back discrimination (same ITD, different IID)")
    fig.tight_layout()
    fig.savefig(out / "fig3_12_front_back.png", dpi=110)
    plt.close(fig)


def fig_estimation(m: MaskModel, out: Path) -> None:
    """Fig. 3.13: azimuth estimation, cost over 360 degrees for a source at 150 deg."""
    x = simulate_masked(white_noise(1.0, FS, 5), FS, m, _u(150.0), snr_db=20, rng=6,
                        far_field=True)
    est = localize_mask(x, FS, m)
    az = np.arange(0, 360, 1.0)
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(az, est.score - est.score.min() + 1e-2)
    ax.axvline(150, color="k", ls=":", label="true 150 deg")
    ax.axvline(est.azimuth_deg, color="C1", ls="--", label=f"estimate {est.azimuth_deg:.1f}")
    ax.axvline(est.runner_up_deg, color="C2", ls="--",
               label=f"runner-up (other half) {est.runner_up_deg:.0f}")
    ax.set_xlabel("azimuth (deg)")
    ax.set_ylabel("cost J - min J")
    ax.set_title(f"fig. 3.13: estimation of azimuth (P(front) = {est.front_probability:.3f})")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "fig3_13_estimation.png", dpi=110)
    plt.close(fig)


def fig_margin(out: Path) -> None:
    """Design measure: worst-case front/back separability over azimuth, mask2 vs mask2-asym."""
    fig, ax = plt.subplots(figsize=(8, 4))
    for preset in ("mask2", "mask2-asym"):
        m = MaskModel(preset)
        for dist, ls in ((None, "-"), (0.5, "--")):
            az, mg, _ = front_back_margin(m, dist)
            ax.semilogy(az, np.maximum(mg, 1e-2), ls,
                        label=f"{preset}, {'far field' if dist is None else f'{dist} m'}")
    ax.set_xlabel("source azimuth (deg)")
    ax.set_ylabel("cost of the nearest confusable azimuth")
    ax.set_title("front/back separability (hearsee.audio.mask.front_back_margin)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "front_back_margin.png", dpi=110)
    plt.close(fig)


def tables(m: MaskModel, out: Path, trials: int) -> str:
    """Tables 3.3/3.4: estimates at alpha = 30 and 150 deg under several SNRs."""
    parts = []
    for tab, alpha in (("3.3", 30.0), ("3.4", 150.0)):
        lines = [f"### Table {tab}: location estimates (deg), alpha = {alpha:.0f} deg, far field",
                 "", "| signal | SNR dB | estimates | mean | front/back correct |",
                 "|---|---|---|---|---|"]
        for kind in ("noise", "male"):
            for snr in (0, 5, 10, 20, 30):
                rng = np.random.default_rng([int(alpha), snr, len(kind)])
                ests = []
                for _ in range(trials):
                    sig = (white_noise(1.0, FS, rng) if kind == "noise"
                           else synthetic_voice("male", 1.0, FS, rng))
                    x = simulate_masked(sig, FS, m, _u(alpha), snr, rng, far_field=True)
                    ests.append(localize_mask(x, FS, m).azimuth_deg)
                e = np.array(ests)
                ok = np.abs((e - alpha + 180) % 360 - 180) < 90
                mean = np.degrees(np.angle(np.mean(np.exp(1j * np.radians(e))))) % 360
                lines.append(f"| {kind} | {snr} | {', '.join(f'{v:.1f}' for v in e)} | "
                             f"{mean:.1f} | {ok.sum()}/{len(e)} |")
        parts.append("\n".join(lines))
    text = "\n\n".join(parts) + "\n"
    (out / "tables_3_3_3_4.md").write_text(text, encoding="utf-8")
    return text


def _trials(text: str) -> int:
    """--trials: a whole number >= 1 (0 or fewer wrote tables of nan means and 0/0)."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description="Regenerate thesis ch. 3 figures and tables.")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "out"),
                    help="output folder (default: examples/out)")
    ap.add_argument("--trials", type=_trials, default=5, help="recordings per table cell (>= 1)")
    ap.add_argument("--array", default="mask2", help="masked array preset or YAML path")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    m = MaskModel(a.array)
    print(f"{m.array.name}: {m.mesh.n_panels} panels, {len(m.freqs)} frequencies up to "
          f"{m.f_max:.0f} Hz")
    fig_mask(m, out)
    fig_sphere_validation(out)
    fig_waveforms(m, out)
    fig_itd_iid_derivation(m, out)
    fig_responses(m, out)
    fig_front_back(m, out)
    fig_estimation(m, out)
    fig_margin(out)
    print(tables(m, out, a.trials))
    print(f"figures and tables written to {out}/")


if __name__ == "__main__":
    main()
