"""The documentation is executed (issue 11, item 8).

Every ``bash``/``sh``/``console`` command and every ``python`` snippet in README.md and docs/
runs, in order, per document, in a scratch directory holding a copy of ``examples/`` (so
outputs such as ``assembled.yaml`` chain from one command to the next as the doc says). In a
``console`` block, the lines after a ``$ command`` are its expected output: every number on them
(ignoring a trailing ``<- note``) must appear in what the command printed, and ``$ echo $?``
states the expected exit code (otherwise 0).

``kinprop`` commands run in this process (``typer``'s CliRunner in the scratch directory, the
kernels compiled once for the whole test run; a new process per command would import the
library and load the kernels again, ~1.5 s each); ``python`` commands and snippets run in a new
process.

A block that must not run in CI is marked, on the line before its fence, with
``<!-- doc-test: skip REASON -->`` (e.g. ``scripts/paper.sh`` builds a virtualenv, a benchmark
takes minutes, ``--scheduler tcp://HOST`` needs a cluster).

Numbers a doc states outside console blocks — a Markdown table of results, a paragraph — are
checked too when marked ``<!-- doc-test: numbers -->`` on the line before the table or
paragraph: every number in it (a table's header row aside) must be among what the code block
above it printed (all its commands), to the doc's precision, sign included.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
SKIP = re.compile(r"<!--\s*doc-test:\s*skip\b(?P<why>[^>]*)-->")
NUMBERS = re.compile(r"^\s*<!--\s*doc-test:\s*numbers\s*-->\s*$")
FENCE = re.compile(r"^```(?P<lang>[a-z]*)\s*$")
NUMBER = re.compile(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?![\w.])", re.IGNORECASE)
CLI = [sys.executable, "-c", "from kinprop.cli import main; main()"]
TIMEOUT = 600


@dataclass
class Command:
    text: str
    expected: list[str] = field(default_factory=list)
    exit_code: int = 0


@dataclass
class Block:
    doc: Path
    line: int
    lang: str
    body: list[str]
    skip: str | None

    def commands(self) -> list[Command]:
        """Shell commands (``\\`` continuations joined), with expected output for console blocks."""
        out: list[Command] = []
        lines = list(self.body)
        k = 0
        while k < len(lines):
            raw = lines[k]
            if self.lang == "console" and not raw.startswith("$ "):
                if out:
                    out[-1].expected.append(raw)
                k += 1
                continue
            text = raw[2:] if self.lang == "console" else raw
            while text.rstrip().endswith("\\") and k + 1 < len(lines):
                k += 1
                text = text.rstrip()[:-1] + " " + lines[k].strip()
            k += 1
            if text.strip() in ("echo $?",) and out:
                code = next((x.strip() for x in lines[k:] if x.strip()), "0")
                out[-1].exit_code = int(code)
                k += 1
                continue
            if shlex.split(text, comments=True):
                out.append(Command(text))
        return out


def blocks(doc: Path) -> list[Block]:
    out: list[Block] = []
    lines = doc.read_text(encoding="utf-8").splitlines()
    k = 0
    while k < len(lines):
        if NUMBERS.match(lines[k]):  # the table or paragraph below: its numbers are outputs
            start = k + 1
            k += 1
            while k < len(lines) and lines[k].strip():
                k += 1
            body = lines[start:k]
            if body and body[0].startswith("|"):
                body = body[2:]  # a table's header row and rule
            out.append(Block(doc, start + 1, "numbers", body, None))
            continue
        m = FENCE.match(lines[k])
        if not m or not m.group("lang"):
            if m:  # an unlabelled block: skip to its end
                k += 1
                while k < len(lines) and not lines[k].startswith("```"):
                    k += 1
            k += 1
            continue
        lang, start = m.group("lang"), k
        k += 1
        body = []
        while k < len(lines) and not lines[k].startswith("```"):
            body.append(lines[k])
            k += 1
        k += 1
        prev = next((x for x in reversed(lines[:start]) if x.strip()), "")
        skip = SKIP.search(prev)
        if lang in ("bash", "sh", "console", "python"):
            out.append(Block(doc, start + 1, lang, body, skip.group("why").strip() if skip else None))
    return out


def _argv(text: str) -> list[str] | None:
    words = shlex.split(text, comments=True)
    head, rest = words[0], words[1:]
    if head in ("kinprop", ".venv/bin/kinprop"):
        return [*CLI, *rest]
    if head in ("python", "python3", ".venv/bin/python"):
        return [sys.executable, *rest]
    return None


def _run_command(argv: list[str], cwd: Path) -> tuple[int, str]:
    """(exit code, stdout + stderr) of one doc command: ``kinprop`` in this process, else a new one."""
    if argv[: len(CLI)] != CLI:
        p = subprocess.run(argv, capture_output=True, text=True, cwd=cwd, timeout=TIMEOUT)
        return p.returncode, p.stdout + p.stderr
    from typer.testing import CliRunner

    from kinprop.cli import app

    here = Path.cwd()
    os.chdir(cwd)
    try:
        r = CliRunner().invoke(app, argv[len(CLI) :], prog_name="kinprop")
    finally:
        os.chdir(here)
    printed = r.stdout + r.stderr
    if r.exception is not None and not isinstance(r.exception, SystemExit):
        printed += "".join(traceback.format_exception(*r.exc_info))  # type: ignore[misc]
    return r.exit_code, printed


def _printed(expected: str, printed: list[float]) -> bool:
    """``expected`` (as the doc prints it) is among the numbers the command printed, to the
    doc's precision: within two units of its last printed digit or 1e-5 relative."""
    e = float(expected)
    digits = expected.lower().split("e")[0]
    ulp = 10.0 ** -(len(digits.split(".")[1]) if "." in digits else 0)
    if "e" in expected.lower():
        ulp *= 10.0 ** int(expected.lower().split("e")[1])
    tol = max(2 * ulp, 1e-5 * abs(e))
    return any(abs(a - e) <= tol for a in printed)


def _numbers(lines: list[str]) -> list[str]:
    nums: list[str] = []
    for line in lines:
        line = line.split("<-")[0]
        nums += NUMBER.findall(line.replace("│", " ").replace("┃", " "))
    return nums


def _check_numbers(block: Block, printed: str) -> None:
    """Every number of a marked table or paragraph is among the numbers ``printed``."""
    where = f"{block.doc.relative_to(ROOT)}:{block.line}"
    assert printed, f"{where}: numbers marked for checking, but no code block above printed anything"
    values = [float(x) for x in _numbers(printed.splitlines())]
    stated = _numbers([line.replace("|", " ") for line in block.body])
    assert stated, f"{where}: a doc-test: numbers mark on a table or paragraph without numbers"
    missing = [x for x in stated if not _printed(x, values)]
    assert not missing, f"{where}: the commands above did not print {missing} (the doc says so):\n{printed[-3000:]}"


def _run_block(block: Block, cwd: Path) -> str:
    """Run a code block; returns what its commands printed (a snippet: stdout and stderr)."""
    where = f"{block.doc.relative_to(ROOT)}:{block.line}"
    if block.lang == "python":
        p = subprocess.run([sys.executable, "-c", "\n".join(block.body)], capture_output=True, text=True, cwd=cwd,
                           timeout=TIMEOUT)  # fmt: skip
        assert p.returncode == 0, f"{where}: python snippet failed:\n{p.stderr[-3000:]}"
        return p.stdout + p.stderr
    outputs = []
    for cmd in block.commands():
        argv = _argv(cmd.text)
        assert argv is not None, f"{where}: cannot run {cmd.text!r} here; mark the block <!-- doc-test: skip ... -->"
        code, printed = _run_command(argv, cwd)
        assert code == cmd.exit_code, f"{where}: {cmd.text!r} exited {code}:\n{printed[-3000:]}"
        values = [float(x) for x in _numbers(printed.splitlines())]
        missing = [x for x in _numbers(cmd.expected) if not _printed(x, values)]
        assert not missing, f"{where}: {cmd.text!r} did not print {missing} (the doc says so):\n{printed[-3000:]}"
        outputs.append(printed)
    return "\n".join(outputs)


ALL = [(doc, b) for doc in DOCS for b in blocks(doc)]


def test_marked_numbers_are_checked() -> None:
    """A marked table is collected without its header, and a number the commands did not print
    fails the check (else the marks prove nothing)."""
    marked = [b for _, b in ALL if b.lang == "numbers"]
    assert len({b.doc for b in marked}) >= 3
    table = Block(ROOT / "README.md", 1, "numbers", ["| a | 0.6870 | 3 |"], None)
    _check_numbers(table, "p = [0.6869999 1 2 3]")
    with pytest.raises(AssertionError, match=r"did not print \['0.695'\]"):
        _check_numbers(Block(ROOT / "README.md", 1, "numbers", ["| a | 0.695 |"], None), "p = [0.687]")


def test_every_doc_block_is_collected() -> None:
    """The collector sees the README's commands and snippets (else the test below proves nothing)."""
    readme = [b for d, b in ALL if d.name == "README.md"]
    assert sum(b.lang == "bash" for b in readme) >= 3 and sum(b.lang == "python" for b in readme) >= 1
    assert any("kinprop propagate" in c.text for b in readme if b.lang == "bash" for c in b.commands())


@pytest.mark.parametrize("doc", DOCS, ids=[str(d.relative_to(ROOT)) for d in DOCS])
def test_doc_runs(doc: Path, tmp_path: Path) -> None:
    todo = [b for d, b in ALL if d == doc]
    if not todo:
        pytest.skip("no code blocks")
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    shutil.copytree(ROOT / "benchmarks", tmp_path / "benchmarks")
    shutil.copytree(ROOT / "docs", tmp_path / "docs")  # plots go to docs/img/ in some commands
    printed = ""
    for block in todo:
        if block.lang == "numbers":
            _check_numbers(block, printed)
        elif block.skip is None:
            printed = _run_block(block, tmp_path)
        else:
            printed = ""
