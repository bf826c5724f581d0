"""Benchmark: human detection with stereo, stereo + thermal fusion, and OpenCV's HOG (thesis ch. 7).

On ``--scenes`` generated rooms (default 300; 1-4 people, 0-2 human-like objects -- mannequin,
poster cut-out, coat on a stand --, 1-8 m) every method runs on the same images:

* **stereo**: P(y,d) + scale-adaptive filter + segmentation + head-shoulder verification
  (:mod:`hearsee.vision.humans`), no thermal camera;
* **fusion**: the same candidates confirmed by the radiometric thermal image (degC), and
  **fusion-8bit** by the 8-bit AGC (non-radiometric) thermal image (:mod:`hearsee.vision.fusion`);
* **HOG**: ``cv2.HOGDescriptor_getDefaultPeopleDetector`` on the left image (Dalal & Triggs).

Metrics: detections are matched greedily to ground-truth boxes (visible pixels of each entity,
left image) with IoU >= 0.4. People less than 50 % visible are "don't care" (neither missed nor
false when detected). Recall/precision are given for people 1-6 m away (the target band;
detections matched to people beyond 6 m, and unmatched stereo detections estimated beyond
6.5 m, are ignored there -- HOG has no range, so all its unmatched boxes count) and for all
people (1-8 m). Human-like objects count as rejected when no accepted detection matches them.
3D position error is ``|p_est - p_true| / |p_true|`` (torso centre, left camera frame).
Median box IoU (since 2026-12-03): of the matched detections of people at least half visible,
against the entity's visible pixels; the stereo boxes reach the floor under the body since
that day (:attr:`hearsee.vision.humans.BodySegment.body_box`; before, they stopped at
``min_height_m``, 0.12 m above it).
Frames per second: CPU time of one :func:`hearsee.vision.fusion.detect_humans` call (disparity
included) at 640x480 on one core: ``cv2.setNumThreads(1)`` and numpy's BLAS held to one thread
(``threadpoolctl``; with its default two threads OpenBLAS's idle worker adds CPU time to every
frame without making it faster). Fig. 7.9: detection rate vs Tm.

Pitched camera (``--pitch-scenes`` per pitch, seeds from ``--pitch-seed``; since 2026-12-03):
the same kind of rooms seen by the rig pitched -25 to +25 deg (+ = looking up, a tilting
head), detected with the floor's prior level (as every call was before that day) and with the
camera's pitch (``detect_humans(camera_pitch_deg=)``), and by HOG, on the same images.

Real data (skipped when ``../shared/data`` is absent): thermal filter + visible/thermal overlay
on the LLVIP pairs (``vision/rgb_thermal``), HOG on frames of ``vision/pedestrian_video``.

Run: ``.venv/bin/python bench/humans.py [--scenes N] [--data DIR]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, markdown_table, print_table, shared_data_dir, write_markdown  # noqa: E402

from hearsee.sim.scenes import default_rig, generate_scene  # noqa: E402
from hearsee.vision.fusion import classify_candidates, detect_humans, draw_detections  # noqa: E402
from hearsee.vision.humans import _iou, detect_people_hog  # noqa: E402
from hearsee.vision.thermal import relative_warm_mask  # noqa: E402

IOU = 0.4


def _save_png(name: str, image: np.ndarray) -> None:
    RESULTS.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(RESULTS / name), image, [cv2.IMWRITE_PNG_COMPRESSION, 9])


TMS = np.round(np.linspace(0.0, 1.0, 21), 2)


def _match(dets: list[dict], gts: list, iou_min: float = IOU) -> dict[int, int]:
    """Greedy IoU matching: detection index -> ground-truth index."""
    pairs = []
    for i, d in enumerate(dets):
        for j, g in enumerate(gts):
            if g.box is None:
                continue
            v = _iou(d["box"], g.box)
            if v >= iou_min:
                pairs.append((v, i, j))
    pairs.sort(reverse=True)
    used_d, used_g, out = set(), set(), {}
    for _, i, j in pairs:
        if i in used_d or j in used_g:
            continue
        used_d.add(i)
        used_g.add(j)
        out[i] = j
    return out


def _evaluate(dets: list[dict], scene, stats: dict, has_range: bool) -> None:
    """Accumulate counts of one method on one scene into ``stats``."""
    people = scene.people
    like = [o for o in scene.human_like if o.box is not None]
    m = _match(dets, people)
    matched_people = set(m.values())
    for i, d in enumerate(dets):
        if i in m:
            g = people[m[i]]
            if g.visible_fraction < 0.5:
                continue  # don't care
            near = g.distance_m <= 6.0
            stats["iou"].append(_iou(d["box"], g.box))
            stats["tp_all"] += 1
            stats["tp_16"] += near
            if has_range:
                err = np.linalg.norm(np.asarray(d["position_m"]) - g.position_m)
                stats["err_rel"].append(err / g.distance_m)
                stats["err_abs"].append(err)
                stats["err_range"].append(g.distance_m)
        else:
            stats["fp_all"] += 1
            far = has_range and d["distance_m"] > 6.5
            stats["fp_16"] += not far
            stats["false"].append((scene.spec.seed, d["box"], round(d["distance_m"], 2)))
    for j, g in enumerate(people):
        if g.visible_fraction < 0.5:
            continue
        stats["n_all"] += 1
        stats["n_16"] += g.distance_m <= 6.0
        if j not in matched_people:
            stats["fn_all"] += 1
            stats["fn_16"] += g.distance_m <= 6.0
            stats["missed"].append((scene.spec.seed, g.kind, round(g.distance_m, 2), g.box))
    # human-like objects: rejected when no detection matches them
    ml = _match(dets, like)
    hit = set(ml.values())
    for j, g in enumerate(like):
        if g.visible_fraction < 0.5:
            continue
        stats["like_n"] += 1
        stats["like_acc"] += j in hit
        stats[f"like_acc_{g.kind}"] = stats.get(f"like_acc_{g.kind}", 0) + (j in hit)
        stats[f"like_n_{g.kind}"] = stats.get(f"like_n_{g.kind}", 0) + 1


def _new_stats() -> dict:
    return {"tp_all": 0, "fp_all": 0, "fn_all": 0, "n_all": 0, "tp_16": 0, "fp_16": 0,
            "fn_16": 0, "n_16": 0, "like_n": 0, "like_acc": 0, "err_rel": [], "err_abs": [],
            "err_range": [], "iou": [], "missed": [], "false": []}


def _ratio(a: float, b: float) -> float:
    return a / b if b else float("nan")


def _summary(name: str, s: dict) -> list:
    rel = np.asarray(s["err_rel"])
    return [name,
            _ratio(s["tp_16"], s["tp_16"] + s["fn_16"]),
            _ratio(s["tp_16"], s["tp_16"] + s["fp_16"]),
            _ratio(s["tp_all"], s["tp_all"] + s["fn_all"]),
            _ratio(s["tp_all"], s["tp_all"] + s["fp_all"]),
            1.0 - _ratio(s["like_acc"], s["like_n"]),
            float(np.median(rel)) if rel.size else float("nan"),
            float(np.percentile(rel, 90)) if rel.size else float("nan"),
            float(np.median(s["err_abs"])) if s["err_abs"] else float("nan"),
            float(np.median(s["iou"])) if s["iou"] else float("nan")]


def _as_dets(humans) -> list[dict]:
    return [{"box": h.box, "position_m": h.position_m, "distance_m": h.distance_m}
            for h in humans]


def run_synthetic(n_scenes: int, seed0: int, hog: bool) -> tuple[list[tuple[str, str]], dict]:
    cv2.setNumThreads(1)
    with threadpool_limits(1):  # one core: the BLAS of numpy too, not only OpenCV
        return _run_synthetic(n_scenes, seed0, hog)


def _run_synthetic(n_scenes: int, seed0: int, hog: bool) -> tuple[list[tuple[str, str]], dict]:
    rig = default_rig()
    methods = ["stereo", "fusion", "fusion-8bit"] + (["HOG"] if hog else [])
    stats = {m: _new_stats() for m in methods}
    tm_rows = []  # (score, extent_ok, label, support) per candidate
    t_det, t_hog, t_gen = [], [], []
    example = None
    t0 = time.perf_counter()
    for k in range(n_scenes):
        seed = seed0 + k
        tg = time.perf_counter()
        sc = generate_scene(seed, rig)  # one rig, as on a robot (rectification maps cached)
        t_gen.append(time.perf_counter() - tg)
        c0 = time.process_time()
        res = detect_humans(sc.left, sc.right, sc.rig, sc.thermal_c)
        t_det.append(time.process_time() - c0)
        rect = res.frame.rectification
        stereo_h, _ = classify_candidates(res.stereo, sc.rig, rect, None)
        warm8 = relative_warm_mask(sc.thermal_8bit)
        f8_h, _ = classify_candidates(res.stereo, sc.rig, rect, warm8)
        _evaluate(_as_dets(stereo_h), sc, stats["stereo"], True)
        _evaluate(_as_dets(res.humans), sc, stats["fusion"], True)
        _evaluate(_as_dets(f8_h), sc, stats["fusion-8bit"], True)
        if hog:
            c0 = time.process_time()
            hb = detect_people_hog(sc.left)
            t_hog.append(time.process_time() - c0)
            _evaluate([{"box": b, "distance_m": 0.0} for b, _ in hb], sc, stats["HOG"], False)
        # fig. 7.9 material: every segmented candidate with its label
        cands = [c for c in res.stereo.candidates if c.segment is not None
                 and not c.reason.startswith("duplicate")]
        dets = [{"box": c.segment.body_box} for c in cands]
        mp = _match(dets, sc.people)
        ml = _match(dets, [o for o in sc.human_like])
        humans_all = res.humans + res.rejected
        sup = {tuple(h.box): h.thermal_support for h in humans_all}
        for i, c in enumerate(cands):
            ext = c.accepted or c.reason.startswith("head-shoulder")
            if i in mp:
                g = sc.people[mp[i]]
                label = "person" if g.visible_fraction >= 0.5 and g.distance_m <= 6 else "dontcare"
            elif i in ml:
                label = "human_like"
            else:
                label = "other"
            tm_rows.append((c.score, ext, label, sup.get(tuple(c.segment.body_box))))
        if example is None and len(sc.people) >= 2 and sc.human_like:
            example = (sc, res)
        if (k + 1) % 25 == 0:
            print(f"  {k + 1}/{n_scenes} scenes, {time.perf_counter() - t0:.0f} s", flush=True)
    n_people_tm = sum(st for st in [stats["stereo"]["n_16"]])
    # ------------------------------------------------------------------ tables
    headers = ["method", "recall 1-6 m", "precision 1-6 m", "recall 1-8 m", "precision 1-8 m",
               "human-like rejected", "median 3D err / range", "p90 3D err / range",
               "median 3D err (m)", "median box IoU"]
    rows = [_summary(m, stats[m]) for m in methods]
    print_table(f"Human detection on {n_scenes} generated scenes", headers, rows)
    kinds = ["mannequin", "poster", "coat_stand"]
    like_rows = []
    for m in methods:
        s = stats[m]
        like_rows.append([m] + [1.0 - _ratio(s.get(f"like_acc_{k}", 0), s.get(f"like_n_{k}", 0))
                                for k in kinds] + [s["like_n"]])
    print_table("Human-like objects rejected, by kind", ["method", *kinds, "n objects"], like_rows)
    fps_det = 1.0 / float(np.mean(t_det))
    timing_rows = [["stereo + thermal detection incl. SGBM disparity", float(np.mean(t_det)) * 1e3,
                    fps_det]]
    if hog:
        timing_rows.append(["HOG people detector", float(np.mean(t_hog)) * 1e3,
                            1.0 / float(np.mean(t_hog))])
    timing_rows.append(["scene generation (not part of detection)",
                        float(np.mean(t_gen)) * 1e3, 1.0 / float(np.mean(t_gen))])
    print_table("Speed at 640x480, one core (CPU time per frame)", ["what", "ms / frame", "fps"],
                timing_rows)
    # range breakdown of the fusion position error
    s = stats["fusion"]
    rng_rows = []
    er = np.asarray(s["err_range"])
    rel = np.asarray(s["err_rel"])
    for lo, hi in [(1, 2), (2, 4), (4, 6), (6, 8.5)]:
        sel = (er >= lo) & (er < hi)
        rng_rows.append([f"{lo}-{hi} m", int(sel.sum()),
                         float(np.median(rel[sel])) if sel.any() else float("nan")])
    print_table("Fusion: median relative 3D error by range", ["range", "n", "median err/range"],
                rng_rows)
    # fig. 7.9: detection rate vs Tm
    tm = np.array([r[0] for r in tm_rows])
    ext = np.array([r[1] for r in tm_rows])
    lab = np.array([r[2] for r in tm_rows])
    sp = np.array([np.nan if r[3] is None else r[3] for r in tm_rows], float)
    det_rate, fp_per_frame, like_acc_rate, det_rate_f = [], [], [], []
    n_like = max(1, stats["stereo"]["like_n"])
    for t in TMS:
        ok = ext & (tm >= t)
        okf = ok & (sp >= 0.3)
        det_rate.append(_ratio((ok & (lab == "person")).sum(), n_people_tm))
        det_rate_f.append(_ratio((okf & (lab == "person")).sum(), n_people_tm))
        fp_per_frame.append((ok & (lab == "other")).sum() / n_scenes)
        like_acc_rate.append((ok & (lab == "human_like")).sum() / n_like)
    tm_table = [[float(t), det_rate[i], det_rate_f[i], fp_per_frame[i], like_acc_rate[i]]
                for i, t in enumerate(TMS) if i % 2 == 0]
    print_table("Fig. 7.9: detection rate vs Tm (people 1-6 m)",
                ["Tm", "detection rate (stereo)", "detection rate (fusion)",
                 "other false accepts / frame (stereo)", "human-like accepted (stereo)"], tm_table)
    # ------------------------------------------------------------------ plots
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    ax[0].plot(TMS, det_rate, "o-", label="detection rate, stereo")
    ax[0].plot(TMS, det_rate_f, "s-", label="detection rate, stereo + thermal")
    ax[0].plot(TMS, like_acc_rate, "^--", label="human-like objects accepted, stereo")
    ax[0].plot(TMS, fp_per_frame, "x:", label="other false accepts / frame, stereo")
    ax[0].set_xlabel("head-shoulder threshold Tm")
    ax[0].set_ylabel("rate")
    ax[0].set_title("Fig. 7.9 (reconstruction): detection rate vs Tm")
    ax[0].legend(fontsize=7)
    ax[0].grid(alpha=0.3)
    x = np.arange(len(methods))
    for i, (col, lbl) in enumerate([(1, "recall 1-6 m"), (2, "precision 1-6 m"),
                                    (5, "human-like rejected")]):
        ax[1].bar(x + (i - 1) * 0.25, [r[col] for r in rows], 0.25, label=lbl)
    ax[1].axhline(0.95, color="k", lw=0.8, ls="--")
    ax[1].set_xticks(x, methods)
    ax[1].set_ylim(0, 1.05)
    ax[1].legend(fontsize=7)
    ax[1].set_title(f"{n_scenes} generated scenes")
    fig.tight_layout()
    RESULTS.mkdir(parents=True, exist_ok=True)
    fig.savefig(RESULTS / "humans.png", dpi=110)
    plt.close(fig)
    if example is not None:
        sc, res = example
        th = cv2.applyColorMap(sc.thermal_8bit, cv2.COLORMAP_INFERNO)
        th = cv2.resize(th, (sc.left.shape[1], sc.left.shape[0]), interpolation=cv2.INTER_NEAREST)
        disp = res.frame.disparity
        dv = cv2.applyColorMap(np.nan_to_num(disp * 4, nan=0).clip(0, 255).astype(np.uint8),
                               cv2.COLORMAP_TURBO)
        top = np.hstack([draw_detections(sc.left, res), th])
        psi = res.stereo.psi
        pv = cv2.resize((np.clip(psi / max(psi.max(), 1e-6), 0, 1) * 255).astype(np.uint8),
                        (640, 480), interpolation=cv2.INTER_NEAREST)
        bot = np.hstack([dv, cv2.applyColorMap(pv, cv2.COLORMAP_VIRIDIS)])
        _save_png("humans_example.png", np.vstack([top, bot]))
    sections = [
        ("Detection on generated scenes", markdown_table(headers, rows)),
        ("Human-like objects rejected, by kind", markdown_table(["method", *kinds, "n objects"],
                                                                 like_rows)),
        ("Speed (640x480, one core, CPU time)", markdown_table(["what", "ms / frame", "fps"],
                                                               timing_rows)),
        ("Fusion: 3D error by range", markdown_table(["range", "n", "median err/range"],
                                                     rng_rows)),
        ("Fig. 7.9: detection rate vs Tm", markdown_table(
            ["Tm", "detection rate (stereo)", "detection rate (fusion)",
             "other false accepts / frame (stereo)", "human-like accepted (stereo)"], tm_table)),
    ]
    return sections, {"rows": rows, "fps": fps_det, "stats": stats}


PITCHES_DEG = (-25.0, -15.0, -8.0, 0.0, 8.0, 15.0, 25.0)


def run_pitched(n_scenes: int, seed0: int, hog: bool) -> list[tuple[str, str]]:
    """A pitched camera (a head tilted up or down, :data:`PITCHES_DEG`): the random rooms of
    ``random_spec(seed0 + k)`` seen by the default rig pitched about its x axis, detected by
    the fusion with the floor's prior taken as level (``camera_pitch_deg=0``: every call
    before 2026-12-03) and with the camera's true pitch as the prior, and by HOG, all on the
    same images. People cut by the view's top or bottom lose what the detector and HOG need
    (the head, or the floor under the feet): rows at +-25 deg show the view's limits."""
    from hearsee.sim.scenes import pitched_view, random_spec, render_scene

    cv2.setNumThreads(1)
    rig = default_rig()
    rows = []
    t0 = time.perf_counter()
    with threadpool_limits(1):
        for pitch in PITCHES_DEG:
            st = {"level prior": _new_stats(), "pitch prior": _new_stats()}
            if hog:
                st["HOG"] = _new_stats()
            fell_back = {"level prior": 0, "pitch prior": 0}
            for k in range(n_scenes):
                sc = render_scene(random_spec(seed0 + k), rig, view=pitched_view(pitch))
                for name, prior in (("level prior", 0.0), ("pitch prior", pitch)):
                    res = detect_humans(sc.left, sc.right, sc.rig, sc.thermal_c,
                                        camera_pitch_deg=prior)
                    fell_back[name] += res.info["floor"]["source"] == "prior"
                    _evaluate(_as_dets(res.humans), sc, st[name], True)
                if hog:
                    hb = detect_people_hog(sc.left)
                    _evaluate([{"box": b, "distance_m": 0.0} for b, _ in hb], sc, st["HOG"],
                              False)
            for name, s in st.items():
                summ = _summary(name, s)
                rows.append([f"{pitch:+.0f}", name, s["n_16"], summ[1], summ[2], summ[6],
                             "-" if name == "HOG" else f"{fell_back[name]}/{n_scenes}"])
            print(f"  pitch {pitch:+.0f} deg: {time.perf_counter() - t0:.0f} s", flush=True)
    headers = ["pitch deg (+ = up)", "method", "people 1-6 m", "recall 1-6 m",
               "precision 1-6 m", "median 3D err / range", "floor from the prior (no fit)"]
    title = (f"Pitched camera: fusion with the floor's prior level vs the camera's pitch, and "
             f"HOG ({n_scenes} scenes, seeds {seed0}-{seed0 + n_scenes - 1})")
    print_table(title, headers, rows)
    return [(title, markdown_table(headers, rows))]


def run_real(data: Path | None) -> list[tuple[str, str]]:
    """Thermal filter + overlay on LLVIP pairs; HOG on the pedestrian video."""
    from hearsee.vision.io import read_image, read_thermal
    from hearsee.vision.thermal import overlay_thermal

    out: list[tuple[str, str]] = []
    if data is None:
        print("real data absent: skipping the LLVIP and pedestrian-video parts")
        return [("Real images", "skipped: ../shared/data not present")]
    pairs = data / "vision" / "rgb_thermal"
    if pairs.is_dir():
        rows, tiles = [], []
        for ir in sorted((pairs / "infrared").glob("*.jpg")):
            vis_p = pairs / "visible" / ir.name
            if not vis_p.is_file():
                continue
            th = read_thermal(ir)
            vis = read_image(vis_p, "bgr")
            warm = relative_warm_mask(th, background_px=151, open_px=5, close_px=9)
            hog = detect_people_hog(cv2.resize(vis, (640, 512)))
            sup = []
            for (x, y, w, h), _ in hog:  # registered pair: same pixels (scale 2)
                m = warm[2 * y: 2 * (y + h), 2 * x: 2 * (x + w)]
                sup.append(float(m.mean()) if m.size else 0.0)
            rows.append([ir.stem, float(warm.mean()), len(hog),
                         float(np.mean(sup)) if sup else float("nan")])
            ov = overlay_thermal(vis, th, warm)
            for (x, y, w, h), _ in hog:
                cv2.rectangle(ov, (2 * x, 2 * y), (2 * (x + w), 2 * (y + h)), (0, 255, 0), 4)
            tiles.append(cv2.resize(ov, (320, 256)))
        if tiles:
            while len(tiles) % 4:
                tiles.append(np.zeros_like(tiles[0]))
            grid = np.vstack([np.hstack(tiles[i: i + 4]) for i in range(0, len(tiles), 4)])
            _save_png("humans_rgb_thermal.png", grid)
        hdr = ["pair", "warm fraction", "HOG boxes (visible)", "mean warm fraction in HOG boxes"]
        print_table("LLVIP visible/thermal pairs: relative thermal filter", hdr, rows)
        out.append(("LLVIP pairs (8-bit, non-radiometric): thermal filter and HOG",
                    markdown_table(hdr, rows) + "\n\nOverlay: `humans_rgb_thermal.png` (warm "
                    "pixels tinted by the thermal colour map, HOG boxes in green)."))
    video = data / "vision" / "pedestrian_video" / "vtest.avi"
    if video.is_file():
        cap = cv2.VideoCapture(str(video))
        frames, rows, tiles = 0, [], []
        idx = 0
        while True:
            ok, fr = cap.read()
            if not ok:
                break
            if idx % 80 == 0:
                c0 = time.process_time()
                hb = detect_people_hog(fr)
                dt = time.process_time() - c0
                rows.append([idx, len(hb), dt * 1e3])
                vis = fr.copy()
                for (x, y, w, h), _ in hb:
                    cv2.rectangle(vis, (x, y), (x + w, y + h), (0, 255, 0), 2)
                tiles.append(cv2.resize(vis, (320, 240)))
                frames += 1
            idx += 1
        cap.release()
        if tiles:
            while len(tiles) % 5:
                tiles.append(np.zeros_like(tiles[0]))
            grid = np.vstack([np.hstack(tiles[i: i + 5]) for i in range(0, len(tiles), 5)])
            _save_png("humans_hog_video.png", grid)
        hdr = ["frame", "HOG people", "ms"]
        print_table("Pedestrian video: HOG people detector", hdr, rows)
        out.append(("Pedestrian video (480x360): HOG people detector (no ground truth)",
                    markdown_table(hdr, rows) + "\n\nFrames: `humans_hog_video.png`."))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", type=int, default=300, help="number of generated scenes")
    ap.add_argument("--seed", type=int, default=1000, help="seed of the first scene")
    ap.add_argument("--data", default=None, help="real-data folder (default ../shared/data)")
    ap.add_argument("--no-hog", action="store_true", help="skip the HOG baseline")
    ap.add_argument("--pitch-scenes", type=int, default=40,
                    help="scenes per pitch of the pitched-camera table (0: skip it)")
    ap.add_argument("--pitch-seed", type=int, default=9100,
                    help="seed of the first scene of the pitched-camera table")
    args = ap.parse_args(argv)
    if args.scenes < 1:
        ap.error("--scenes must be >= 1")
    if args.pitch_scenes < 0:
        ap.error("--pitch-scenes must be >= 0")
    sections, res = run_synthetic(args.scenes, args.seed, not args.no_hog)
    if args.pitch_scenes:
        sections += run_pitched(args.pitch_scenes, args.pitch_seed, not args.no_hog)
    sections += run_real(shared_data_dir(args.data))
    described = "\n\n".join(__doc__.split("\n\n")[1:-1])
    # (the run writes the same files whatever its scenes: say which ones it was)
    ran = (f"Produced by `python bench/humans.py --scenes {args.scenes} --seed {args.seed}"
           f" --pitch-scenes {args.pitch_scenes} --pitch-seed {args.pitch_seed}"
           f"{' --no-hog' if args.no_hog else ''}`.")
    intro = (ran + "\n\n" + described + "\n\nTargets (fusion, people 1-6 m): recall and precision "
             ">= 0.95; >= 95 % of human-like objects rejected; median 3D error <= 5 % of range; "
             ">= 10 frames/s at 640x480 including disparity on one core.\n\nPlots: `humans.png` "
             "(fig. 7.9 and the method comparison), `humans_example.png` (detections, thermal, "
             "disparity, Psi-hat).")
    path = write_markdown("humans", sections, intro)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
