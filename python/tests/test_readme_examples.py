"""The Python examples of the documents run as written: every fenced block whose info string is
`python runnable` in README.md, CONTRIBUTING.md, docs/CLI.md and docs/PYTHON.md is executed, each
in a fresh temporary working folder, with the installed contour_track package."""

import os
import re

import pytest

from conftest import REPO

DOCUMENTS = ["README.md", "CONTRIBUTING.md", "docs/CLI.md", "docs/PYTHON.md"]
FENCE = re.compile(r"^[ \t]*```([^\n`]*)\n(.*?)^[ \t]*```", re.MULTILINE | re.DOTALL)


def runnable_blocks(text):
    """The bodies of the blocks marked `python runnable`."""
    return [body for info, body in FENCE.findall(text) if info.split()[:1] == ["python"] and "runnable" in info.split()]


def cases():
    found = []
    for name in DOCUMENTS:
        path = REPO / name
        if path.is_file():
            for k, body in enumerate(runnable_blocks(path.read_text(encoding="utf-8"))):
                found.append(pytest.param(body, id=f"{name}#{k + 1}"))
    return found


def test_the_fence_reader_finds_marked_blocks_only():
    text = "```python runnable\nx = 1\n```\n```python\ny = 2\n```\n```sh runnable\ntrack demo\n```\n"
    assert runnable_blocks(text) == ["x = 1\n"]


def test_the_readme_has_a_runnable_python_example():
    assert runnable_blocks((REPO / "README.md").read_text(encoding="utf-8"))


@pytest.mark.parametrize("body", cases())
def test_runnable_python_block(body, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code = compile(body, "<runnable block>", "exec")
    exec(code, {"__name__": "__main__"})
    capsys.readouterr()
    assert os.getcwd() == str(tmp_path)
