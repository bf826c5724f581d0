"""Every ``>>>`` example in hearsee's docstrings runs as written and prints what it shows.

The examples are users' first contact with a function; until this test only one of them
(``u_disparity``'s, tests/vision) was ever run, and that one had been refusing its own input.
Modules are found by walking the package, so a new example is checked without listing it here.
"""

import doctest
import importlib
import pkgutil

import numpy as np
import pytest

import hearsee


def _modules() -> list[str]:
    # (``hearsee.__main__`` runs the command line when imported)
    return sorted(m.name for m in pkgutil.walk_packages(hearsee.__path__, "hearsee.")
                  if not m.name.endswith("__main__"))


def _examples(name: str) -> list[doctest.DocTest]:
    module = importlib.import_module(name)
    return [t for t in doctest.DocTestFinder().find(module) if t.examples]


MODULES_WITH_EXAMPLES = [m for m in _modules() if _examples(m)]


def test_the_package_has_examples():
    # (a walk that found no module would let every parametrised case below vanish)
    assert len(_modules()) >= 40
    assert len(MODULES_WITH_EXAMPLES) >= 10


@pytest.mark.parametrize("name", MODULES_WITH_EXAMPLES)
def test_docstring_examples_run(name):
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    with np.printoptions(legacy=False):
        for test in _examples(name):
            runner.run(test, out=report.append)
    result = runner.summarize(verbose=False)
    assert result.attempted > 0
    assert result.failed == 0, "".join(report)
