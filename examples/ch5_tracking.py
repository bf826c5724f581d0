"""Thesis ch. 5 regenerated: tracking a moving speaker, camera + microphone fusion, motion.

Figures and tables (thesis numbering; reconstruction from the literature cited in
``hearsee.audio.tracking`` and ``hearsee.fusion.audiovisual``):

* fig. 5.1   far-field direction error as d0/r shrinks (d0 = microphone spacing, r = range)
* table 5.1  + figs. 5.3-5.6  cases I-III: white noise / male / female voice as the moving
             primary source with a static interfering source; azimuth and elevation per frame
             and tracked with the Kalman filter (fig. 5.6: without vs with the filter)
* figs. 5.10-5.11  5.3 without calibration: an MLP from (ITDs, image point) to the 3D position,
             against the calibrated fix
* figs. 5.14-5.16  F1^2 + F2^2 (+ F3^2) along the camera ray, without and with ITD noise
* fig. 5.17  position estimates with sound (ITD) and video (pixel) noise
* figs. 5.18-5.20  position, velocity and acceleration by the constant-acceleration Kalman filter
* tables 5.2 / 5.3  effect of the sampling rate and of the frame length on the 3D fix, in free
             field (5.2, "simulation") and in a room with RT60 0.3 s (5.3, "tests")

Run: ``python examples/ch5_tracking.py [--out DIR] [--quick]`` (default folder examples/out; about
2-4 min; --quick shortens the signals and tables).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hearsee.audio.arrays import MicArray  # noqa: E402
from hearsee.audio.localize import localize_tdoa  # noqa: E402
from hearsee.audio.signals import synthetic_voice, white_noise  # noqa: E402
from hearsee.audio.tracking import track_positions  # noqa: E402
from hearsee.fusion.audiovisual import AudioVisualRig, locate_on_ray, ray_residuals  # noqa: E402
from hearsee.geometry import direction_deg, sph_to_cart, wrap_deg  # noqa: E402
from hearsee.sim.moving import (  # noqa: E402
    Trajectory,
    simulate_moving_free_field,
    simulate_moving_room,
)
from hearsee.stream.pipeline import ArraySource, StreamConfig, StreamPipeline  # noqa: E402
from hearsee.vision.camera import Camera  # noqa: E402


def _tri(side: float) -> MicArray:
    r = side / np.sqrt(3)
    a = np.radians([0.0, 120.0, 240.0])
    return MicArray(np.c_[r * np.cos(a), r * np.sin(a), np.zeros(3)], name=f"triangle-{side}m")


def _sig(kind: str, dur: float, fs: float, rng: np.random.Generator) -> np.ndarray:
    x = white_noise(dur, fs, rng) if kind == "noise" else synthetic_voice(kind, dur, fs, rng)
    return 0.05 * x / np.std(x)


# ------------------------------------------------------------------------------ fig. 5.1
def fig_5_1(out: Path) -> None:
    """Far-field solver fed exact near-field TDOAs: error vs d0/r."""
    arr = MicArray.from_preset("three-mic")
    d0 = arr.aperture
    ratios = np.geomspace(0.01, 1.0, 30)
    rng = np.random.default_rng(0)
    dirs = [(rng.uniform(-180, 180), rng.uniform(-40, 40)) for _ in range(60)]
    e_az, e_el = [], []
    for q in ratios:
        ea, ee = [], []
        for az, el in dirs:
            p = sph_to_cart(np.radians(az), np.radians(el), d0 / q)
            loc = localize_tdoa(arr.tdoa(p), arr, near_field=False)
            # the planar array cannot tell +el from -el: score the candidate nearest the truth
            best = min(loc.candidates, key=lambda c: abs(wrap_deg(c[0] - az)) + abs(c[1] - el))
            ea.append(abs(wrap_deg(best[0] - az)))
            ee.append(abs(abs(best[1]) - abs(el)))
        e_az.append(np.mean(ea))
        e_el.append(np.mean(ee))
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(ratios, e_az, "o-", label="azimuth alpha")
    ax.loglog(ratios, e_el, "s-", label="elevation beta (|beta|)")
    ax.set(xlabel="d0 / r", ylabel="mean error [deg]",
           title="fig. 5.1: far-field approximation error (three-mic, d0 = 15 cm)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "fig5_1_farfield_error.png", dpi=110)
    plt.close(fig)
    for q, a, e in zip(ratios[::6], e_az[::6], e_el[::6], strict=True):
        print(f"  d0/r = {q:5.3f} (r = {d0 / q:6.2f} m): azimuth error {a:6.3f} deg, "
              f"elevation error {e:6.3f} deg")


# ------------------------------------------------------------------------------ cases I-III
def cases_5_1(out: Path, dur: float) -> None:
    """Table 5.1 / figs. 5.3-5.6: moving distant primary source + static interferer."""
    fs = 16000
    arr = MicArray.from_preset("three-mic")
    rng = np.random.default_rng(1)
    # primary: 4 m away, walking an arc from -60 to +60 deg azimuth, 15 deg elevation
    t_knots = np.linspace(0, dur, 40)
    az = np.radians(np.linspace(-60, 60, 40))
    traj = Trajectory(t_knots, sph_to_cart(az, np.radians(15.0), 4.0))
    interferer = sph_to_cart(np.radians(150.0), np.radians(0.0), 3.0)
    cases = [("I", "noise", "male"), ("II", "male", "female"), ("III", "female", "male")]
    rows = []
    fig, axes = plt.subplots(2, 3, figsize=(15, 7), sharex=True)
    for col, (name, prim, intf) in enumerate(cases):
        x = _sig(prim, dur, fs, rng)
        y = simulate_moving_free_field(x, fs, arr, traj, rng=rng)
        yi = simulate_moving_free_field(0.25 * _sig(intf, dur, fs, rng), fs, arr,
                                        Trajectory([0.0], [interferer]), rng=rng)
        rec = y + yi  # signal-to-interference ratio about +10 dB at the microphones
        rec = rec + 1e-3 * rng.standard_normal(rec.shape)
        ups = StreamPipeline(arr, StreamConfig()).run(ArraySource(rec, fs, 2048))
        t = np.array([u.t for u in ups])
        ta, te = direction_deg(traj.heard_at(t, (0.0, 0.0, 0.0), arr.speed_of_sound))
        raw_a = np.array([np.nan if u.raw_azimuth_deg is None else u.raw_azimuth_deg
                          for u in ups])
        raw_e = np.array([np.nan if u.raw_elevation_deg is None else abs(u.raw_elevation_deg)
                          for u in ups])
        trk_a = np.array([np.nan if u.azimuth_deg is None else u.azimuth_deg for u in ups])
        trk_e = np.array([np.nan if u.elevation_deg is None else abs(u.elevation_deg)
                          for u in ups])

        def rms(e: np.ndarray) -> float:
            return float(np.sqrt(np.nanmean(e**2)))

        # the frames whose own direction is nearer the interferer (150 deg) than the talker:
        # RMSEs over all frames are dominated by them, a median is not
        ia = float(np.degrees(np.arctan2(interferer[1], interferer[0])))
        ok = np.isfinite(raw_a)
        on_i = np.abs(wrap_deg(raw_a[ok] - ia)) < np.abs(wrap_deg(raw_a[ok] - ta[ok]))
        rows.append((name, prim, intf, rms(wrap_deg(raw_a - ta)), rms(raw_e - te),
                     rms(wrap_deg(trk_a - ta)), rms(trk_e - te),
                     float(np.mean(ok)) * 100, float(np.nanmedian(np.abs(wrap_deg(raw_a - ta)))),
                     100.0 * float(np.mean(on_i)) if ok.any() else float("nan")))
        for r, (truth, raw, trk, lab) in enumerate(((ta, raw_a, trk_a, "azimuth"),
                                                    (te, raw_e, trk_e, "|elevation|"))):
            ax = axes[r, col]
            ax.plot(t, truth, "k-", lw=2, label="truth")
            ax.plot(t, raw, ".", ms=4, label="without filter (per frame)")
            ax.plot(t, trk, "-", label="with Kalman filter")
            ax.set(ylabel=f"{lab} [deg]", title=f"case {name}: {prim} + interfering {intf}")
            if r == 1:
                ax.set(xlabel="t [s]")
    axes[0, 0].legend(fontsize=7)
    fig.suptitle("figs. 5.3-5.6: distant moving source, azimuth/elevation without and with KF")
    fig.tight_layout()
    fig.savefig(out / "fig5_6_tracking_with_without_kf.png", dpi=110)
    plt.close(fig)
    print("  table 5.1 (cases) -- RMSE in degrees (and the per-frame azimuth's median absolute "
          "error, and the share of frames nearer the interferer than the talker):")
    print("  case | primary | interferer | az per-frame | |el| per-frame | az tracked | "
          "|el| tracked | coverage % | az per-frame median | on interferer %")
    for r in rows:
        print(f"  {r[0]:4s} | {r[1]:7s} | {r[2]:10s} | {r[3]:12.2f} | {r[4]:14.2f} | "
              f"{r[5]:10.2f} | {r[6]:12.2f} | {r[7]:10.0f} | {r[8]:19.2f} | {r[9]:15.0f}")


# ------------------------------------------------------------------------------ 5.14-5.17
def _rig(arr: MicArray) -> AudioVisualRig:
    return AudioVisualRig.mounted(arr, Camera.from_fov(70.0, 640, 480), (0.3, 0.0, 0.0))


def figs_5_14_17(out: Path) -> None:
    rig = _rig(_tri(0.5))
    arr = rig.array
    rng = np.random.default_rng(2)
    src = np.array([1.4, 0.35, 0.1])
    uv = rig.project(src)[0]
    o, d = rig.rays(uv[None])
    d = d[0]
    s_true = float(np.linalg.norm(src - o))
    s = np.linspace(0.2, 4.0, 800)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4))
    F = ray_residuals(arr, o, d, s, arr.tdoa(src))
    for k, lab in enumerate(arr.pair_labels):
        ax[0].plot(s, F[:, k] * 1e6, label=f"F{k + 1} (pair {lab})")
    ax[0].axvline(s_true, color="k", ls="--")
    ax[0].set(xlabel="range along the ray s [m]", ylabel="residual [us]",
              title="fig. 5.14: ITD residuals along the ray (no noise)")
    ax[0].legend(fontsize=7)
    J0 = np.sum(F**2, axis=1)
    ax[1].semilogy(s, J0, "k-", label="no noise (fig. 5.16)")
    for trial in range(3):
        z = arr.tdoa(src) + 10e-6 * rng.standard_normal(3)
        Jn = np.sum(ray_residuals(arr, o, d, s, z) ** 2, axis=1)
        ax[1].semilogy(s, Jn, alpha=0.7, label=f"ITD noise 10 us, trial {trial + 1} (fig. 5.15)")
    ax[1].axvline(s_true, color="k", ls="--")
    ax[1].set(xlabel="s [m]", ylabel="F1^2 + F2^2 + F3^2 [s^2]",
              title="figs. 5.15-5.16: sum of squares, minimum at the source")
    ax[1].legend(fontsize=7)
    # fig 5.17: position estimates under sound and video noise, several sources
    rows = []
    for sig_t in (2e-6, 5e-6, 10e-6, 20e-6):
        errs = []
        for _ in range(100):
            r = rng.uniform(0.5, 2.0)
            p = sph_to_cart(np.radians(rng.uniform(-25, 25)), np.radians(rng.uniform(-8, 8)), r)
            uvn = rig.project(p)[0] + 1.0 * rng.standard_normal(2)
            z = arr.tdoa(p) + sig_t * rng.standard_normal(3)
            f = locate_on_ray(rig, uvn, z, sigma_tdoa_s=sig_t)
            errs.append(np.linalg.norm(f.position_m - p))
        rows.append((sig_t, float(np.median(errs)), float(np.percentile(errs, 90))))
    st = [r[0] * 1e6 for r in rows]
    ax[2].plot(st, [r[1] * 100 for r in rows], "o-", label="median")
    ax[2].plot(st, [r[2] * 100 for r in rows], "s--", label="90th percentile")
    ax[2].set(xlabel="ITD noise std [us] (pixel noise 1 px)", ylabel="3D error [cm]",
              title="fig. 5.17 / 5.4.2: sensitivity to ITD noise (0.5-2 m)")
    ax[2].legend()
    fig.tight_layout()
    fig.savefig(out / "fig5_14-17_ray_fusion.png", dpi=110)
    plt.close(fig)
    print("  5.4.2 sensitivity (0.5 m triangle, camera 0.3 m ahead, 1 px pixel noise):")
    for sig_t, med, p90 in rows:
        print(f"  ITD noise {sig_t * 1e6:5.1f} us ({sig_t * 16000:.2f} samples at 16 kHz): "
              f"median {med * 100:5.1f} cm, p90 {p90 * 100:5.1f} cm")


# ------------------------------------------------------------------------------ 5.3
def section_5_3(out: Path, quick: bool) -> None:
    """Without calibration: an MLP maps (ITDs, image point) -> 3D position (figs. 5.10-5.11)."""
    from hearsee.fusion.audiovisual import AudioVisualRegressor, simulate_av_samples

    rig = _rig(_tri(0.5))
    n = 800 if quick else 3000
    sig_t = 5e-6
    X, Y = simulate_av_samples(rig, n, (0.5, 2.0), sigma_tdoa_s=sig_t, sigma_px=1.0, rng=10)
    Xt, Yt = simulate_av_samples(rig, 300, (0.5, 2.0), sigma_tdoa_s=sig_t, sigma_px=1.0, rng=11)
    model = AudioVisualRegressor(hidden_layer_sizes=(32, 32), max_iter=300).fit(X, Y)
    e_mlp = np.linalg.norm(model.predict(Xt) - Yt, axis=1)
    e_cal = np.array([np.linalg.norm(locate_on_ray(rig, x[3:], x[:3], sigma_tdoa_s=sig_t)
                                     .position_m - y) for x, y in zip(Xt, Yt, strict=True)])
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.hist([e_mlp * 100, e_cal * 100], bins=30, range=(0, 40),
            label=["MLP, no calibration (5.3)", "camera ray + ITDs, calibrated (5.4)"])
    ax.set(xlabel="3D error [cm]", ylabel="test points",
           title="figs. 5.10-5.11: learned vs calibrated fusion")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "fig5_11_mlp_vs_calibrated.png", dpi=110)
    plt.close(fig)
    print(f"  {n} training points, ITD noise {sig_t * 1e6:.0f} us, 1 px: median 3D error MLP "
          f"{np.median(e_mlp) * 100:.1f} cm (R^2 {model.score(Xt, Yt):.3f}), calibrated "
          f"{np.median(e_cal) * 100:.1f} cm")


# ------------------------------------------------------------------------------ 5.18-5.20
def figs_5_18_20(out: Path) -> None:
    """Constant-acceleration KF on camera+ITD fixes of a source walking a circle."""
    rig = _rig(_tri(0.5))
    rng = np.random.default_rng(3)
    dt = 0.032
    t = np.arange(0, 6.0, dt)
    w = 2 * np.pi / 6.0  # one turn in 6 s, radius 0.4 m around (1.3, 0, 0)
    c = np.array([1.3, 0.0, 0.0])
    p = c + 0.4 * np.c_[np.cos(w * t), np.sin(w * t), np.zeros_like(t)]
    v = 0.4 * w * np.c_[-np.sin(w * t), np.cos(w * t), np.zeros_like(t)]
    a = -0.4 * w**2 * np.c_[np.cos(w * t), np.sin(w * t), np.zeros_like(t)]
    fixes, covs = [], []
    for pk in p:
        f = locate_on_ray(rig, rig.project(pk)[0] + rng.standard_normal(2),
                          rig.array.tdoa(pk) + 5e-6 * rng.standard_normal(3), sigma_tdoa_s=5e-6)
        fixes.append(f.position_m)
        covs.append(f.covariance)
    tr = track_positions(t, np.array(fixes), np.array(covs), sigma_jerk=0.2)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4))
    for k, lab in enumerate("xy"):
        ax[0].plot(t, p[:, k], "k-", lw=2)
        ax[0].plot(t, np.array(fixes)[:, k], ".", ms=3, label=f"{lab} fix")
        ax[0].plot(t, tr.position[:, k], "-", label=f"{lab} KF")
        ax[1].plot(t, v[:, k], "k-", lw=2)
        ax[1].plot(t, tr.velocity[:, k], "-", label=f"v{lab} KF")
        ax[2].plot(t, a[:, k], "k-", lw=2)
        ax[2].plot(t, tr.acceleration[:, k], "-", label=f"a{lab} KF")
    for axx, ttl, yl in ((ax[0], "fig. 5.18: position", "m"), (ax[1], "fig. 5.19: velocity",
                                                               "m/s"),
                         (ax[2], "fig. 5.20: acceleration", "m/s^2")):
        axx.set(xlabel="t [s]", ylabel=yl, title=ttl + " (truth black)")
        axx.legend(fontsize=7)
    ax[2].set_ylim(-1.5, 1.5)
    fig.tight_layout()
    fig.savefig(out / "fig5_18-20_motion_kf.png", dpi=110)
    plt.close(fig)
    s = slice(30, None)
    print(f"  circle walk (0.42 m/s, |a| = {0.4 * w**2:.2f} m/s^2): position RMSE fixes "
          f"{np.sqrt(np.mean(np.sum((np.array(fixes) - p) ** 2, 1))) * 100:.1f} cm, KF "
          f"{np.sqrt(np.mean(np.sum((tr.position - p)[s] ** 2, 1))) * 100:.1f} cm; velocity "
          f"RMSE {np.sqrt(np.mean(np.sum((tr.velocity - v)[s] ** 2, 1))):.3f} m/s; acceleration "
          f"RMSE {np.sqrt(np.mean(np.sum((tr.acceleration - a)[s] ** 2, 1))):.3f} m/s^2")


# ------------------------------------------------------------------------------ tables
def tables_5_2_3(quick: bool) -> None:
    rig0 = _rig(_tri(0.5))
    rates = (8000, 16000, 48000) if quick else (8000, 16000, 32000, 48000)
    frames_ms = (32.0, 64.0) if quick else (16.0, 32.0, 64.0, 128.0)
    dur = 1.0 if quick else 1.5
    for title, room in (("table 5.2: free field (simulation)", False),
                        ("table 5.3: room, RT60 0.3 s, SNR 20 dB (tests)", True)):
        print(f"  {title}: median 3D error of the per-frame fix [cm] (coverage %), "
              "CPU ms per frame")
        print("  fs [Hz] | " + " | ".join(f"frame {f:5.0f} ms" for f in frames_ms))
        for fs in rates:
            rng = np.random.default_rng(fs)
            traj = Trajectory([0.0, dur], [[1.0, -0.3, 0.05], [1.3, 0.3, 0.05]])
            x = _sig("male", dur, fs, rng)
            if room:
                y = simulate_moving_room(x, fs, rig0.array, traj, [7, 6, 3], 0.3,
                                         [3.5, 3.0, 1.2], snr_db=20.0, rng=rng, block_s=0.1)
            else:
                y = simulate_moving_free_field(x, fs, rig0.array, traj, snr_db=20.0, rng=rng)
            cells = []
            for fm in frames_ms:
                cfg = StreamConfig(frame_ms=fm, hop_ms=fm / 2, sigma_tdoa_s=1.0 / fs)

                def pts(t: float, traj: Trajectory = traj) -> tuple[float, float]:
                    u, v = rig0.project(traj.at(t))[0]
                    return float(u), float(v)

                pipe = StreamPipeline(rig0.array, cfg, rig=rig0, image_points=pts)
                ups = pipe.run(ArraySource(y, fs, 4096))
                tt = np.array([u.t for u in ups])
                raw = np.array([u.raw_position_m if u.raw_position_m is not None
                                else [np.nan] * 3 for u in ups], float)
                e = np.linalg.norm(raw - traj.at(tt), axis=1)
                cpu = pipe.stats.cpu_s / max(len(ups), 1) * 1e3
                cells.append(f"{np.nanmedian(e) * 100:5.1f} ({np.mean(np.isfinite(e)) * 100:3.0f}"
                             f"%) {cpu:4.1f}ms")
            print(f"  {fs:7d} | " + " | ".join(cells))
    print("  (synthetic male voice, whose aspiration noise fills the band up to fs/2; real speech "
          "has far less above 8 kHz and gains little from higher rates: bench/tracking.py "
          "part B)")


def main() -> None:
    ap = argparse.ArgumentParser(description="Regenerate the thesis's ch. 5 figures and tables.")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "out",
                    help="output folder (default: examples/out)")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    t0 = time.time()
    print("fig. 5.1"); fig_5_1(args.out)  # noqa: E702
    print("table 5.1, figs. 5.3-5.6"); cases_5_1(args.out, 3.0 if args.quick else 5.0)  # noqa: E702
    print("5.3 (figs. 5.10-5.11)"); section_5_3(args.out, args.quick)  # noqa: E702
    print("figs. 5.14-5.17"); figs_5_14_17(args.out)  # noqa: E702
    print("figs. 5.18-5.20"); figs_5_18_20(args.out)  # noqa: E702
    print("tables 5.2 / 5.3"); tables_5_2_3(args.quick)  # noqa: E702
    print(f"figures in {args.out}/ ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
