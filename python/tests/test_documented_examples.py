"""The Python examples of the README and docs/python.md run, and print what they should.

Each is the first ```python block under its heading, run from the repository root; what it
prints must match the pattern given here, which the block's comment states where it can.
"""

import contextlib
import io
import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def example(document, heading):
    text = (ROOT / document).read_text()
    after = text[text.index(heading):]
    return re.search(r"```python\n(.*?)```", after, re.S).group(1)


@pytest.mark.parametrize(
    "document, heading, printed",
    [
        ("README.md", "## Python", r"^25\.0 1\.0$"),
        ("docs/python.md", "## A first session", r"^0\.\d\d of the poses score above 0\.5$"),
        ("docs/python.md", "## Entry points", r"^\[1\.\s+0\.508\d*\] \['' ''\]$"),
    ],
)
def test_the_documented_example_prints_what_it_says(document, heading, printed, monkeypatch):
    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(example(document, heading), f"{document} {heading}", "exec"), {})
    assert re.match(printed, out.getvalue().strip()), out.getvalue()
