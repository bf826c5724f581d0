"""The robot report (hearsee.robot.report.write_report) opened in a real headless Chromium.

Skipped when no Chromium is installed (Debian: ``apt-get install chromium``). The log is a small
synthetic one built here (a person walking on a straight line, a track converging to it), so the
numbers the page must show are known.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

_BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def _browser() -> str | None:
    for name in _BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


BROWSER = _browser()
pytestmark = pytest.mark.skipif(BROWSER is None, reason="no headless Chromium installed "
                                "(apt-get install chromium)")


def _chromium(args: list[str], profile: Path, timeout: float = 60.0) -> subprocess.CompletedProcess:
    cmd = [BROWSER, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
           "--no-first-run", "--disable-background-networking", "--disable-component-update",
           "--disable-sync", "--disable-dev-shm-usage", f"--user-data-dir={profile}", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)


def _synthetic_run(n: int = 25) -> tuple[dict, list[dict], dict, dict]:
    """A scenario dict, a log, a summary and two overlay images with known numbers."""
    rng = np.random.default_rng(3)
    robot = np.array([3.5, 2.6])
    t = np.arange(n) * 0.2
    truth = np.stack([1.6 + 0.1 * t, 4.3 + 0.1 * t, np.full(n, 1.2)], axis=1)
    err = 0.5 * np.exp(-t) + 0.03
    track = truth + err[:, None] * rng.normal(size=(n, 3)) / np.sqrt(3)
    az = np.degrees(np.arctan2(truth[:, 1] - robot[1], truth[:, 0] - robot[0]))
    log = []
    for k in range(n):
        log.append({
            "t": float(t[k]),
            "truth": {"position_m": truth[k].tolist(), "azimuth_robot_deg": float(az[k])},
            "track": {"position_m": track[k].tolist()},
            "error_m": float(np.linalg.norm(track[k] - truth[k])),
            "head_pan_deg": float(min(az[k], 40.0 * t[k])),
            "audio": {"azimuth_deg": float(az[k] + rng.normal(0, 2))},
        })
    errors = np.array([r["error_m"] for r in log])
    summary = {"success": True, "position_error_median_m": float(np.median(errors)),
               "updates": n, "time_to_verify_s": 1.4}
    scenario = {"name": "browser-check", "seed": 11, "room": {"size_m": [7.0, 6.0, 3.0]},
                "robot": {"position_m": robot.tolist(), "heading_deg": 0.0,
                          "head_height_m": 1.25},
                "objects": [{"kind": "mannequin", "position_m": [2.3, 3.9]}]}
    overlay = np.zeros((90, 120, 3), np.uint8)
    overlay[:, :, 1] = np.linspace(0, 255, 120, dtype=np.uint8)[None, :]
    overlay[20:70, 40:80] = (0, 200, 0)
    thermal = np.tile(np.linspace(0, 255, 60, dtype=np.uint8)[:, None], (1, 80))
    return scenario, log, summary, {"overlay_0": overlay, "thermal_0": thermal}


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from hearsee.robot.report import write_report

    folder = tmp_path_factory.mktemp("report")
    scenario, log, summary, images = _synthetic_run()
    index = write_report(folder, scenario, log, summary, images,
                         {"overlay_0": "left camera", "thermal_0": "thermal view"})
    return index, summary


def test_summary_numbers_in_dom_and_images_load(report, tmp_path):
    index, summary = report
    folder = index.parent
    # A harness page next to the report loads it in an iframe (same folder, file access allowed)
    # and writes what the browser actually rendered into its own DOM for --dump-dom.
    harness = folder / "_harness.html"
    harness.write_text("""<!doctype html><html><body>
<iframe id="f" src="index.html" style="width:1200px;height:3000px"></iframe>
<pre id="out">pending</pre>
<script>
document.getElementById('f').addEventListener('load', function () {
  var d = this.contentDocument;
  var imgs = Array.prototype.map.call(d.images, function (im) {
    return {src: im.getAttribute('src'), complete: im.complete, w: im.naturalWidth,
            h: im.naturalHeight};
  });
  var rows = Array.prototype.map.call(d.querySelectorAll('#summary tr'), function (tr) {
    return Array.prototype.map.call(tr.children, function (c) { return c.textContent; });
  });
  document.getElementById('out').textContent =
      'RESULT' + JSON.stringify({images: imgs, rows: rows, title: d.title}) + 'END';
});
</script></body></html>""", encoding="utf-8")
    proc = _chromium(["--allow-file-access-from-files", "--virtual-time-budget=10000",
                      "--dump-dom", harness.as_uri()], tmp_path / "profile")
    assert proc.returncode == 0, proc.stderr[-2000:]
    m = re.search(r"RESULT(.*?)END", proc.stdout, re.S)
    assert m, f"harness did not report (DOM: {proc.stdout[:500]!r})"
    res = json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))
    assert "browser-check" in res["title"]
    rows = {r[0]: r[1] for r in res["rows"] if len(r) == 2}
    # the numbers the page shows are the run's own, formatted to 3 significant digits
    assert rows["updates"] == str(summary["updates"])
    assert float(rows["position_error_median_m"]) == pytest.approx(
        summary["position_error_median_m"], rel=5e-3)
    assert rows["success"] == "yes"
    srcs = [im["src"] for im in res["images"]]
    assert {"plots/top_view.png", "plots/error.png", "plots/head.png",
            "frames/overlay_0.png", "frames/thermal_0.png"} <= set(srcs)
    for im in res["images"]:  # every image decoded by the browser, at its file's size
        assert im["complete"] and im["w"] > 0 and im["h"] > 0, im
    sizes = {im["src"]: (im["w"], im["h"]) for im in res["images"]}
    assert sizes["frames/overlay_0.png"] == (120, 90)
    assert sizes["frames/thermal_0.png"] == (80, 60)


def test_page_renders_non_blank(report, tmp_path):
    import cv2

    index, _ = report
    shot = tmp_path / "shot.png"
    proc = _chromium(["--window-size=1200,1600", "--hide-scrollbars",
                      f"--screenshot={shot}", index.as_uri()], tmp_path / "profile")
    assert proc.returncode == 0, proc.stderr[-2000:]
    img = cv2.imread(str(shot))
    assert img is not None and img.shape[:2] == (1600, 1200)
    # not a blank page: plenty of non-white pixels and real colour (the plots' lines)
    non_white = np.mean(np.any(img < 240, axis=2))
    assert non_white > 0.02
    hsv = cv2.cvtColor(img, cv2.COLOR_BGR2HSV)
    assert np.count_nonzero(hsv[:, :, 1] > 80) > 500
