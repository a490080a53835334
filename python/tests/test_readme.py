"""The README's Python example runs as written, from the repository's root."""

import os
import re

from conftest import ROOT


def test_the_readme_example_runs(capsys):
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README has a Python example"
    here = os.getcwd()
    try:
        os.chdir(ROOT)
        exec(compile(blocks[0], "README.md", "exec"), {})
    finally:
        os.chdir(here)
    idf1 = float(capsys.readouterr().out.strip().splitlines()[-1])
    assert 0.9 < idf1 <= 1.0
