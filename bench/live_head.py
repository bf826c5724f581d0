"""Benchmark of the live robot loop's hearing while its head moves (`hearsee run`'s loop).

Each run puts :func:`hearsee.robot.hardware.run_robot` in a closed loop with a simulated pan
servo (:class:`hearsee.sim.servo.ServoHead`, ``--servo-dps``, default 60 deg/s) that turns
toward the loop's commands, and a talker walking a straight line (0.5-1.5 m/s, starting
1.5-3 m away within 60 deg of the robot's front, synthetic male or female voice with its
pauses, free field, sensor noise ``--snr`` dB at 2 m). Every 0.1-s audio block is rendered
while the loop runs, from the talker's path in the array's frame given the head's poses over
that block (the servo's pose is read at the block's end: a device's present); no cameras, so
the head follows the audio alone, as before a first visual fix. The array: the default
three-mic head and the thesis's masked pair (mask2-asym, rendered through the mask by
:func:`hearsee.sim.moving.simulate_moving_masked`).

Side by side on the same walks: the loop's rule (a head moving no faster than
``hardware.FOLLOW_RATE_DPS``, 50 deg/s, is heard, and the stream is told the head's pan at each
frame, ``StreamPipeline.run(array_pan=)``, so that its direction tracker turns back with the
head instead of taking the head's turning for the talker's motion), the same without telling
the stream (its ablation) and the rule before 2026-12-05 (every pose change above 0.5 deg
restarted the whole stream and withheld its audio until one frame and one block after the head
stopped: ``FOLLOW_RATE_DPS = 0``). Two more rows run the loop's rule with a device whose blocks
reach the loop ``--latency-ms`` (default 50) after their capture, so that the head's pose read
while a block is processed is that much newer than the block's end: the source telling the
second of audio it captures (``audio_time_now``, as the live DeviceSource does since
2026-12-05's evening), and not telling it (the pose timed at the newest block's end, as
before). Per run, from 1 s on:
the share of updates with a measured bearing, the bearing error of those (robot frame, against
the talker as heard at the array), and the head's pointing error |pan - talker azimuth| at
every update (its p50 / p90 and the share of updates within 10 deg).

A second part (since 2026-12-06, ``--turn-scenes``): two still people taking turns
(:func:`turns_scene`), heard by the loop's default rule; per change of talker the time from the
new talker's first words to the loop's bearing and to the head's pan within 15 deg of them
(:func:`run_turns`).

    python bench/live_head.py                # about 8-10 min on one core
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import RESULTS, markdown_table, print_table, write_markdown  # noqa: E402

FS = 16000
BLOCK = 1600  # samples: the robot file's default block_ms 100
CONTEXT = 1024  # samples rendered before each block (the sound already on its way)
MOUTH_Z_M = 1.55
#: the loop's rule, its ablation (the stream not told the head's pans), the rule before; the
#: loop's rule with a device latency, the source telling its capture clock or not
RULES = ("default", "keep", "before", "latency-clock", "latency")


def walk(rng: np.random.Generator, duration_s: float) -> tuple[object, str]:
    """A straight walk (robot frame, metres) and its voice kind."""
    from hearsee.sim.moving import Trajectory

    az = np.radians(rng.uniform(-60.0, 60.0))
    r = rng.uniform(1.5, 3.0)
    start = np.array([r * np.cos(az), r * np.sin(az), MOUTH_Z_M])
    heading = az + np.pi / 2 * rng.choice([-1.0, 1.0]) + rng.uniform(-0.5, 0.5)
    v = rng.uniform(0.5, 1.5) * np.array([np.cos(heading), np.sin(heading), 0.0])
    t = np.array([0.0, duration_s + 1.0])
    return Trajectory(t, np.stack([start, start + v * t[1]])), str(rng.choice(["male",
                                                                                "female"]))


class ClosedLoopSource:
    """The talkers' voices as the head hears them, rendered block by block while the loop runs:
    ``talkers`` a list of (path, voice) -- one walker, or people taking turns (each voice
    silent outside its turns)."""

    def __init__(self, cfg, head, talkers, noise_sigma: float, rng: np.random.Generator,
                 model=None, latency_s: float = 0.0) -> None:
        self.cfg, self.head, self.talkers = cfg, head, talkers
        self.n_samples = min(v.size for _, v in talkers)
        self.noise_sigma, self.rng, self.model = noise_sigma, rng, model
        self.fs, self.n_channels = float(FS), cfg.audio.array.n_mics
        self.latency_s = latency_s  # (a block reaches the loop this long after its end)

    def heard(self, lo: int, hi: int) -> np.ndarray:
        return sum(self._heard(path, voice, lo, hi) for path, voice in self.talkers)

    def _heard(self, path, voice: np.ndarray, lo: int, hi: int) -> np.ndarray:
        from hearsee.geometry import robot_to_array
        from hearsee.sim.moving import (
            Trajectory,
            simulate_moving_free_field,
            simulate_moving_masked,
        )

        times = np.arange(lo, hi + 160, 160) / FS  # (every 10 ms)
        pts = np.array([robot_to_array(path.at(t), (self.head.pan_at(t), 0.0),
                                       self.cfg.head.pivot_m, self.cfg.head.offset_m)
                        for t in times]).reshape(len(times), 3)
        traj = Trajectory(times - lo / FS, pts)
        seg = voice[lo:hi]
        if self.model is not None:
            return simulate_moving_masked(seg, FS, self.model, traj)
        return simulate_moving_free_field(seg, FS, self.cfg.audio.array, traj)

    def blocks(self):
        from hearsee.stream.pipeline import Block

        for seq, start in enumerate(range(0, self.n_samples - BLOCK + 1, BLOCK)):
            # (the head moved during the block, and on until the block reaches the loop)
            self.head.advance((start + BLOCK) / FS + self.latency_s)
            lo = max(start - CONTEXT, 0)
            x = self.heard(lo, start + BLOCK)[:, start - lo:start - lo + BLOCK]
            x = x + self.noise_sigma * self.rng.standard_normal(x.shape)
            yield Block(seq, start, x, time.perf_counter())


class ClockedSource(ClosedLoopSource):
    """... telling the second of audio captured now (the head's clock), as DeviceSource."""

    def audio_time_now(self) -> float:
        return self.head.t


def closed_loop(array: str, talkers: list, sigma: float, rng: np.random.Generator,
                args: argparse.Namespace, rule: str = "default") -> tuple:
    """``hardware.run_robot`` in a closed loop with a :class:`~hearsee.sim.servo.ServoHead`
    hearing ``talkers`` (see :class:`ClosedLoopSource`) under ``rule`` (one of
    :data:`RULES`): (its RunResult, the head, the robot config)."""
    import hearsee.robot.hardware as hw
    from hearsee.sim.servo import ServoHead
    from hearsee.stream.pipeline import StreamPipeline

    masked = array.startswith("mask")
    with tempfile.TemporaryDirectory() as tmp:
        cfg = hw.robot_config_from_dict(
            {"audio": {"array": array, **({"channels": [0, 1]} if masked else {})},
             "head": {"pan_limits_deg": [-180, 180]}, "output": {"report": "out"}},
            "bench.yaml", Path(tmp))
        model = None
        if masked:
            from hearsee.audio.mask import MaskModel

            model = MaskModel(cfg.audio.array)
        head = ServoHead(args.servo_dps)  # (hearsee.sim.servo)
        latency = args.latency_ms / 1000.0 if rule.startswith("latency") else 0.0
        kind_of_source = ClockedSource if rule == "latency-clock" else ClosedLoopSource
        source = kind_of_source(cfg, head, talkers, sigma, rng, model, latency)
        saved = hw.FOLLOW_RATE_DPS, StreamPipeline.run
        if rule == "before":
            hw.FOLLOW_RATE_DPS = 0.0
        elif rule == "keep":  # (the stream is not told the head's pans)
            def run(self, source, sink=None, threaded=False, array_pan=None):
                return saved[1](self, source, sink, threaded)
            StreamPipeline.run = run
        try:
            res = hw.run_robot(cfg, audio_source=source, head=head,
                               jsonl=Path(tmp) / "run.jsonl")
        finally:
            hw.FOLLOW_RATE_DPS, StreamPipeline.run = saved
    return res, head, cfg


def heard_azimuth_deg(path, t: float, pivot: np.ndarray) -> float:
    """The robot-frame azimuth (deg) from the head's ``pivot`` (metres) of where ``path``'s
    talker is heard at time ``t`` (s): its position at the emission time."""
    p = path.heard_at(t, pivot) - pivot
    return float(np.degrees(np.arctan2(p[1], p[0])))


def run_one(array: str, seed: int, args: argparse.Namespace, rule: str) -> dict:
    """One closed-loop run under ``rule`` (one of :data:`RULES`); its metrics."""
    from hearsee.audio.signals import synthetic_voice
    from hearsee.geometry import wrap_deg

    rng = np.random.default_rng([args.seed, seed])
    path, kind = walk(rng, args.duration)
    voice = synthetic_voice(kind, args.duration, FS, rng=rng)
    sigma = float(np.sqrt(np.mean(voice[np.abs(voice) > 0] ** 2))) / 2.0 / 10 ** (args.snr / 20)
    res, head, cfg = closed_loop(array, [(path, voice)], sigma, rng, args, rule)
    pivot = np.asarray(cfg.head.pivot_m, float)

    def truth(t: float) -> float:
        return heard_azimuth_deg(path, t, pivot)

    log = [r for r in res.log if r["t"] >= 1.0]
    heard = [r for r in log if r["audio"] is not None and r["audio"]["measured"]]
    bearing = [abs(float(wrap_deg(r["audio"]["azimuth_deg"] - truth(r["t"])))) for r in heard]
    pointing = [abs(float(wrap_deg(head.pan_at(r["t"]) - truth(r["t"])))) for r in log]
    return {"heard": len(heard) / max(len(log), 1), "bearing": bearing, "pointing": pointing,
            "moves": res.summary["head_moves"], "follows": res.summary["head_follows"]}


#: turn-taking part: still talkers, turns of TURN_S seconds with gaps of GAP_S between them, a
#: change of talker counted as followed when the head points within FOLLOW_DEG of the new
#: talker before the next change
TURN_S = (1.5, 3.0)
GAP_S = (0.2, 0.8)
FOLLOW_DEG = 15.0


def turns_scene(rng: np.random.Generator, duration_s: float) -> tuple[list, list, list]:
    """Two still talkers (robot frame, metres; the first within 60 deg of the front, the second
    40-120 deg from them, both 1.5-3 m away), their voices (one male, one female) and their
    turns ``(talker, start s, end s)``, alternating from the first talker."""
    from hearsee.geometry import wrap_deg
    from hearsee.sim.moving import Trajectory

    az0 = rng.uniform(-60.0, 60.0)
    az1 = float(wrap_deg(az0 + rng.choice([-1.0, 1.0]) * rng.uniform(40.0, 120.0)))
    paths = []
    for az in (az0, az1):
        r = rng.uniform(1.5, 3.0)
        p = np.array([r * np.cos(np.radians(az)), r * np.sin(np.radians(az)), MOUTH_Z_M])
        paths.append(Trajectory(np.array([0.0, duration_s + 1.0]), np.stack([p, p])))
    kinds = [str(k) for k in rng.permutation(["male", "female"])]
    turns, t, k = [], 0.0, 0
    while t < duration_s:
        end = min(t + rng.uniform(*TURN_S), duration_s)
        turns.append((k, t, end))
        t, k = end + rng.uniform(*GAP_S), 1 - k
    return paths, kinds, turns


def run_turns(array: str, seed: int, args: argparse.Namespace) -> dict:
    """Two people taking turns (:func:`turns_scene`), heard by the live loop's default rule:
    per change of talker the seconds from the new talker's first words (first sample of the
    turn above 10 % of their voice's peak) to the loop's bearing and to the head's pan within
    :data:`FOLLOW_DEG` of them (None: not before the next change), the talkers' separation
    (deg); and the share of the updates from 1 s on, while someone speaks, with the head on the
    current talker."""
    from hearsee.audio.signals import synthetic_voice
    from hearsee.geometry import wrap_deg

    rng = np.random.default_rng([args.turns_seed, seed])
    paths, kinds, turns = turns_scene(rng, args.turns_duration)
    n = int(args.turns_duration * FS)
    voices = []
    for k in (0, 1):
        v = synthetic_voice(kinds[k], args.turns_duration, FS, rng=rng)[:n]
        env = np.zeros(n)
        for kk, a, b in turns:
            if kk == k:
                i0, i1 = int(a * FS), int(b * FS)
                ramp = min(320, (i1 - i0) // 2)  # (20-ms fades)
                env[i0:i1] = 1.0
                env[i0:i0 + ramp] = np.linspace(0.0, 1.0, ramp)
                env[i1 - ramp:i1] = np.linspace(1.0, 0.0, ramp)
        v = v * env
        voices.append(v / np.sqrt(np.mean(v[np.abs(v) > 0] ** 2)))  # (equal levels)
    sigma = 1.0 / 2.0 / 10 ** (args.snr / 20)  # (the voices' level heard 2 m away)
    onsets = []
    for kk, a, b in turns:
        seg = np.abs(voices[kk][int(a * FS):int(b * FS)])
        idx = np.flatnonzero(seg > 0.1 * np.abs(voices[kk]).max())
        if idx.size:
            onsets.append((kk, a + idx[0] / FS, b))
    res, head, cfg = closed_loop(array, list(zip(paths, voices, strict=True)), sigma, rng, args)
    pivot = np.asarray(cfg.head.pivot_m, float)

    def az_of(k: int, t: float) -> float:
        return heard_azimuth_deg(paths[k], t, pivot)

    def on(angle: float, k: int, t: float) -> bool:
        return abs(float(wrap_deg(angle - az_of(k, t)))) < FOLLOW_DEG

    changes = []
    for i in range(1, len(onsets)):
        k, t0, _ = onsets[i]
        if onsets[i - 1][0] == k:
            continue
        t_next = onsets[i + 1][1] if i + 1 < len(onsets) else np.inf
        during = [r for r in res.log if t0 <= r["t"] < t_next]
        bearing = next((r["t"] - t0 for r in during if r["audio"] is not None
                        and r["audio"]["measured"] and on(r["audio"]["azimuth_deg"], k, r["t"])),
                       None)
        pointed = next((r["t"] - t0 for r in during if on(head.pan_at(r["t"]), k, r["t"])),
                       None)
        sep = abs(float(wrap_deg(head.pan_at(t0) - az_of(k, t0))))
        changes.append({"bearing": bearing, "head": pointed, "sep": sep})
    # (each update from 1 s on with the talker speaking then, if any: one pass over the turns)
    talking = [(r, next((k for k, a, b in onsets if a <= r["t"] < b), None))
               for r in res.log if r["t"] >= 1.0]
    speaking = [(r, k) for r, k in talking if k is not None]
    on_talker = np.mean([on(head.pan_at(r["t"]), k, r["t"]) for r, k in speaking])
    return {"changes": changes, "on_talker": float(on_talker)}


def turns_table(args: argparse.Namespace) -> tuple[str, str]:
    """The turn-taking part: :func:`run_turns` on ``args.turn_scenes`` scenes per array."""
    headers = ["array", "changes of talker", "bearing on the new talker: p50 / p90 s",
               "head on them (followed)", "head on them: p50 / p90 s",
               "of which the loop's own, p50 s", "updates with the head on the current talker"]
    rows = []
    for array in args.arrays.split(","):
        runs = [run_turns(array, k, args) for k in range(args.turn_scenes)]
        ch = [c for r in runs for c in r["changes"]]
        b = np.array([c["bearing"] for c in ch if c["bearing"] is not None])
        h = np.array([c["head"] for c in ch if c["head"] is not None])
        # the servo's share: turning from where the head was to FOLLOW_DEG of the new talker
        own = np.array([c["head"] - max(c["sep"] - FOLLOW_DEG, 0.0) / args.servo_dps
                        for c in ch if c["head"] is not None])
        rows.append([array, len(ch),
                     f"{np.percentile(b, 50):.2f} / {np.percentile(b, 90):.2f}" if b.size else "-",
                     f"{h.size}/{len(ch)}",
                     f"{np.percentile(h, 50):.2f} / {np.percentile(h, 90):.2f}" if h.size else "-",
                     f"{np.percentile(own, 50):.2f}" if own.size else "-",
                     f"{np.mean([r['on_talker'] for r in runs]):.2f}"])
    title = (f"Two people taking turns: {args.turn_scenes} scenes per array (seed "
             f"{args.turns_seed}, {args.turns_duration:g} s each)")
    print_table(title, headers, rows)
    text = ("Two still talkers 1.5-3 m away, the second 40-120 deg from the first, a male and a "
            f"female voice taking turns of {TURN_S[0]:g}-{TURN_S[1]:g} s with gaps of "
            f"{GAP_S[0]:g}-{GAP_S[1]:g} s (free field, sensor noise {args.snr:g} dB at 2 m), "
            f"heard by the loop's default rule with the {args.servo_dps:g} deg/s servo. Per "
            "change of talker, from the new talker's first words: the loop's bearing within "
            f"{FOLLOW_DEG:g} deg of them, and the head's pan within {FOLLOW_DEG:g} deg "
            "(followed: before the next change); the loop's own part is that time less the "
            "servo's, (separation - 15 deg) / its rate. Measured 2026-12-06 for a pause rule "
            "like the simulated robot loop's (`robot.pipeline.DIRECTION_PAUSE_S`): the stream's "
            "direction tracker takes the new talker at its first measurement already -- over a "
            "gap of 0.2 s its IMM's manoeuvre mode (`StreamConfig.direction_modes_dps2`, "
            "2000 deg/s^2) lets the predicted azimuth's sd grow to ~30 deg (0.3 s: ~70), so a "
            "talker 60 deg away passes the gate; the robot loop's single filter waited out "
            "its rejections -- so the live loop has none.\n\n" + markdown_table(headers, rows))
    return title, text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--walks", type=int, default=16)
    # (seed 220: the development walks of 2026-12-05)
    ap.add_argument("--seed", type=int, default=230)
    ap.add_argument("--duration", type=float, default=6.0)
    ap.add_argument("--servo-dps", type=float, default=60.0)
    ap.add_argument("--snr", type=float, default=20.0)
    ap.add_argument("--arrays", default="three-mic,mask2-asym")
    ap.add_argument("--latency-ms", type=float, default=50.0)
    ap.add_argument("--turn-scenes", type=int, default=12,
                    help="scenes of two people taking turns per array (0: none)")
    # (seed 240: the development scenes of 2026-12-06)
    ap.add_argument("--turns-seed", type=int, default=250)
    ap.add_argument("--turns-duration", type=float, default=10.0)
    args = ap.parse_args()

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import hearsee.robot.hardware as hw

    t0 = time.perf_counter()
    variants = [(f"heard while <= {hw.FOLLOW_RATE_DPS:g} deg/s, tracker told the pans (default)",
                 "default"),
                ("heard, tracker not told the pans (ablation)", "keep"),
                ("every move restarts, audio withheld (before 2026-12-05)", "before"),
                (f"default, device latency {args.latency_ms:g} ms, poses timed by the "
                 "device's capture clock", "latency-clock"),
                (f"default, device latency {args.latency_ms:g} ms, poses timed at the newest "
                 "block's end (before 2026-12-05's evening)", "latency")]
    headers = ["array", "rule", "updates with a bearing", "bearing error p50 / p90 deg",
               "pointing error p50 / p90 deg", "pointing within 10 deg", "turns / follows"]
    rows, curves = [], {}
    for array in args.arrays.split(","):
        for name, rule in variants:
            runs = [run_one(array, k, args, rule) for k in range(args.walks)]
            b = np.concatenate([r["bearing"] for r in runs]) if runs else np.zeros(0)
            p = np.concatenate([r["pointing"] for r in runs])
            rows.append([array, name, f"{np.mean([r['heard'] for r in runs]):.2f}",
                         (f"{np.percentile(b, 50):.1f} / {np.percentile(b, 90):.1f}" if b.size
                          else "-"),
                         f"{np.percentile(p, 50):.1f} / {np.percentile(p, 90):.1f}",
                         f"{np.mean(p <= 10.0):.2f}",
                         f"{np.mean([r['moves'] for r in runs]):.0f} / "
                         f"{np.mean([r['follows'] for r in runs]):.0f}"])
            curves[(array, name)] = np.sort(p)
    wall = time.perf_counter() - t0
    title = (f"Live loop with a {args.servo_dps:g} deg/s servo head: {args.walks} walks per "
             f"array (seed {args.seed}), from 1 s on")
    print_table(title, headers, rows)

    fig, ax = plt.subplots(figsize=(7, 4))
    for (array, name), p in curves.items():
        ax.plot(p, np.arange(1, p.size + 1) / p.size, label=f"{array}: {name}")
    ax.set_xscale("log")
    ax.set_xlabel("head pointing error |pan - talker azimuth| (deg)")
    ax.set_ylabel("share of updates")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(RESULTS / "live_head.png", dpi=110)
    cmd = " ".join(["python bench/live_head.py", *sys.argv[1:]])
    text = (f"`{cmd}`; wall time {wall:.0f} s. Each walk under each rule (the same walk, voice "
            "and noise; the closed loop then diverges with the head). 'updates with a bearing': "
            "the share of the loop's updates that measured the talker; 'turns / follows': the "
            "loop's head_moves (pose changes of turns, each restarting the stream) and "
            "head_follows per run. ![live_head](live_head.png)\n\n"
            + markdown_table(headers, rows))
    sections = [(title, text)]
    if args.turn_scenes > 0:
        sections.append(turns_table(args))
    write_markdown("live_head", sections, intro=__doc__.split("\n\n")[0])
    print(f"wrote {RESULTS / 'live_head.md'}")


if __name__ == "__main__":
    main()
