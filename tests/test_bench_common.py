"""The benchmarks' shared plumbing (bench/_common.py): what a results file records."""

import importlib.util
import platform
from importlib.metadata import version
from pathlib import Path

BENCH = Path(__file__).resolve().parents[1] / "bench"


def _common():
    spec = importlib.util.spec_from_file_location("bench_common", BENCH / "_common.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_results_file_ends_with_the_environment_it_was_produced_in(tmp_path, monkeypatch):
    common = _common()
    monkeypatch.setattr(common, "RESULTS", tmp_path / "results")
    path = common.write_markdown("demo", [("Table", "| a |\n|---|\n| 1 |")], intro="Produced.")
    assert path == tmp_path / "results" / "demo.md"
    text = path.read_text(encoding="utf-8")
    assert text.index("## Table") < text.index("## Environment")
    env = text.split("## Environment", 1)[1]
    # the versions actually installed, Python's, and a package that is not installed
    assert f"numpy {version('numpy')}," in env
    assert f"opencv-python-headless {version('opencv-python-headless')}," in env
    assert f"Python {platform.python_version()};" in env
    monkeypatch.setattr(common, "ENV_PACKAGES", ("numpy", "no-such-package-hearsee"))
    assert common.environment().endswith("no-such-package-hearsee not installed.")


def test_environment_without_git_says_so(monkeypatch):
    common = _common()
    monkeypatch.setattr(common, "_git", lambda *args: None)
    assert common.environment().startswith("hearsee at unknown (no git checkout)")


def test_environment_names_a_package_imported_from_elsewhere(tmp_path, monkeypatch):
    """A benchmark run from one checkout with hearsee imported from another (an editable
    install elsewhere) says so: the commit is the checkout's, the code the package's."""
    import hearsee

    common = _common()
    elsewhere = Path(hearsee.__file__).resolve().parents[1] != common.REPO.resolve() / "src"
    assert ("imported from" in common.environment()) == elsewhere
    monkeypatch.setattr(common, "REPO", tmp_path)
    env = common.environment()
    assert env.startswith("hearsee at unknown (no git checkout) (the hearsee package imported "
                          f"from {Path(hearsee.__file__).resolve().parents[1]});")
