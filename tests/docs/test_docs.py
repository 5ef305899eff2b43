"""The documentation is executed, and the numbers it states are checked (issues 11 and 19).

Every ``bash``/``sh``/``console`` command and every ``python`` snippet in README.md and docs/
runs, in order, per document, in a scratch directory holding a copy of ``examples/`` (so
outputs such as ``assembled.yaml`` chain from one command to the next as the doc says). In a
``console`` block, the lines after a ``$ command`` are its expected output: every number on them
(ignoring a trailing ``<- note``) must appear in what the command printed, and ``$ echo $?``
states the expected exit code (otherwise 0).

``kinprop`` commands run in this process (``typer``'s CliRunner in the scratch directory, the
kernels compiled once for the whole test run; a new process per command would import the
library and load the kernels again, ~1.5 s each), and so do ``python`` snippets (each with
fresh globals, in the scratch directory); ``python`` commands (a script) run in a new process.

A block that must not run in CI is marked, on the line before its fence, with
``<!-- doc-test: skip REASON -->`` (e.g. ``scripts/paper.sh`` builds a virtualenv, a benchmark
takes minutes, ``--scheduler tcp://HOST`` needs a cluster).

Numbers outside code blocks (the rule, docs/testing.md#numbers-in-tables-and-prose): every
number in a Markdown table's body, and every number with a decimal point or an exponent in a
paragraph, list or heading, must be covered by a mark on the lines just above the table or
paragraph (several marks may stack):

* ``<!-- doc-test: numbers -->``: each such number must be among the numbers printed by the code
  block above (all its commands), to the doc's precision, sign included;
  ``<!-- doc-test: numbers from TEXT -->``: ... among the numbers printed by the doc's
  commands (or snippets), before or after, whose text contains TEXT (outputs the doc computes
  anyway: no new run);
* ``<!-- doc-test: python`` ... ``-->``: a hidden snippet, run like a visible one; the numbers
  must be the numbers it printed, one for one and in order (so a table's cells cannot pass by
  matching some other printed value);
* ``<!-- doc-test: stated REASON -->``: the numbers are not results (definitions, inputs,
  tolerances, values quoted from the paper, timings measured once); ``stated N1 N2: REASON``
  exempts only the numbers listed, the others stay under the other marks.

Not counted: numbers in code blocks, HTML comments, link targets and URLs; version numbers,
dates, standards (ISO 8855), names (dot-1), and references (section 5.2, eq. 5.10, Table 1,
issue 19, item 3, ...); inline code that
is a command, an option or an argument (``kinprop ...``, ``--tol 1e-3``, ``LCA.q=5``,
``dot-2``: a span without spaces that has letters).
"""

from __future__ import annotations

import contextlib
import io
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
MARK = re.compile(r"^\s*<!--\s*doc-test:\s*(?P<kind>numbers|stated)\b(?P<rest>.*?)-->\s*$")
HIDDEN = re.compile(r"^\s*<!--\s*doc-test:\s*python\s*$")
FENCE = re.compile(r"^```(?P<lang>[a-z]*)\s*$")
NUMBER = re.compile(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?!\w|\.\w)", re.IGNORECASE)  # "4.76." ends a sentence
CLI = [sys.executable, "-c", "from kinprop.cli import main; main()"]
TIMEOUT = 600

# what the rule does not count (see the module docstring)
_NUM = r"\(?\d+(?:\.\d+)*[a-z]?\)?"
NOT_COUNTED = [
    re.compile(r"<!--.*?-->"),
    re.compile(r"\]\([^)]*\)"),  # link targets
    re.compile(r"https?://\S+"),
    re.compile(r"\b\d+\.\d+\.\d+(?:\.\d+)*\b"),  # versions, dotted section numbers
    re.compile(r"\b(?:Python|numba|numpy|scipy|pandas|version|v)\s*\d+(?:\.\d+)+", re.IGNORECASE),
    re.compile(r"\b\d{4}-\d{2}-\d{2}\b"),  # dates
    re.compile(r"\b(?:ISO|DIN|SAE)\s*\d+\b"),  # standards
    re.compile(r"\b[A-Za-z]+-\d+\b"),  # names such as dot-1, dot-2
    re.compile(
        r"(?:\b(?:sections?|secs?\.|eqs?\.|equations?|tables?|figs?\.|figures?|chapters?|items?|"
        r"issues?)|§)\s*"
        rf"{_NUM}(?:\s*(?:,|and|or|to|-|–)\s*{_NUM})*",
        re.IGNORECASE,
    ),
]
INLINE_CODE = re.compile(r"`([^`]*)`")
#: a number in text: a unit may follow a decimal without a space (8.4x), a sentence's period too
TEXT_NUMBER = re.compile(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?![\d_]|\.\d)", re.IGNORECASE)


def _argument_like(span: str) -> bool:
    """Inline code that is a command, an option or an argument (its numbers are inputs)."""
    s = span.strip()
    if s.startswith(("kinprop ", "python ", "pip ", ".venv/", "--")) or re.match(r"-[A-Za-z]", s) or " --" in s:
        return True
    return not re.search(r"\s", s) and bool(re.search(r"[A-Za-z_]", NUMBER.sub("", s)))


def counted_numbers(text: str, table: bool) -> list[str]:
    """The numbers of one table row or paragraph that the rule counts: all of a table row's,
    a paragraph's with a decimal point or an exponent."""
    text = INLINE_CODE.sub(lambda m: " " if _argument_like(m.group(1)) else f" {m.group(1)} ", text)
    for pattern in NOT_COUNTED:
        text = pattern.sub(" ", text)
    text = text.replace("|", " ").replace("│", " ").replace("┃", " ").replace("−", "-")
    nums = [  # an integer followed by letters is a name (s'21T-D, 2F-85, 3D), not a quantity
        m.group()
        for m in TEXT_NUMBER.finditer(text)
        if not (text[m.end() : m.end() + 1].isalpha() and m.group().lstrip("+-").isdigit())
    ]
    return nums if table else [x for x in nums if "." in x or "e" in x.lower()]


@dataclass
class Command:
    text: str
    expected: list[str] = field(default_factory=list)
    exit_code: int = 0


@dataclass
class Block:
    """A code block (``bash``, ``sh``, ``console``, ``python``; ``hidden`` for a
    ``<!-- doc-test: python`` snippet) or a text a reader sees (``table``, ``prose``) with the
    marks above it: ``(kind, rest)``, kind ``numbers``, ``stated`` or ``python``."""

    doc: Path
    line: int
    lang: str
    body: list[str]
    skip: str | None = None
    hidden: bool = False
    marks: list[tuple[str, str]] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.doc.relative_to(ROOT)}:{self.line}"

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

    def counted(self) -> list[str]:
        """The numbers the rule counts (a table's header and rule rows aside)."""
        rows = self.body[2:] if self.lang == "table" else [" ".join(self.body)]
        return [x for row in rows for x in counted_numbers(row, self.lang == "table")]

    def stated(self) -> tuple[bool, set[float]]:
        """(all its numbers stated, the numbers stated one by one)."""
        every, listed = False, set()
        for kind, rest in self.marks:
            if kind == "stated":
                numbers, _ = _stated(rest)
                listed |= {float(x) for x in numbers}
                every = every or not numbers
        return every, listed

    def checked(self) -> list[str]:
        """The counted numbers a ``numbers`` or ``python`` mark compares with outputs."""
        every, listed = self.stated()
        return [] if every else [x for x in self.counted() if float(x) not in listed]

    def uncovered(self) -> list[str]:
        """Counted numbers no mark covers (the rule: none)."""
        if any(kind in ("numbers", "python") for kind, _ in self.marks):
            return []
        return self.checked()

    def source(self) -> str | None:
        """TEXT of a ``numbers from TEXT`` mark: the doc's commands its numbers come from."""
        for kind, rest in self.marks:
            m = re.match(r"\s*from\s+(.+?)\s*$", rest) if kind == "numbers" else None
            if m:
                return m.group(1).strip("\"'")
        return None


def _stated(rest: str) -> tuple[list[str], str]:
    """A stated mark's ``N1 N2: REASON`` (the numbers listed) or ``REASON`` (all): (numbers, reason)."""
    head, colon, reason = rest.partition(":")
    words = head.split()
    if colon and words and all(NUMBER.fullmatch(w) for w in words):
        return words, reason.strip()
    return [], rest.strip()


def parse(doc: Path) -> list[Block]:
    """The doc's code blocks, hidden snippets, tables and paragraphs, in order."""
    out: list[Block] = []
    marks: list[tuple[str, str]] = []
    lines = doc.read_text(encoding="utf-8").splitlines()
    k = 0
    while k < len(lines):
        line = lines[k]
        if not line.strip():
            k += 1
            continue
        if m := MARK.match(line):
            marks.append((m.group("kind"), m.group("rest").strip()))
            k += 1
            continue
        if HIDDEN.match(line):
            start = k + 1
            k += 1
            while k < len(lines) and lines[k].strip() != "-->":
                k += 1
            out.append(Block(doc, start + 1, "python", lines[start:k], hidden=True))
            marks.append(("python", ""))
            k += 1
            continue
        if line.lstrip().startswith("<!--"):  # another comment (a skip mark, a note)
            while k < len(lines) and "-->" not in lines[k]:
                k += 1
            k += 1
            continue
        m = FENCE.match(line)
        if line.startswith("```"):
            start = k
            k += 1
            while k < len(lines) and not lines[k].startswith("```"):
                k += 1
            k += 1
            lang = m.group("lang") if m else ""
            if marks:  # a numbers/stated mark is for a table or paragraph, not a code block
                out.append(Block(doc, start + 1, "orphan", [], marks=marks))
                marks = []
            if lang in ("bash", "sh", "console", "python"):
                prev = next((x for x in reversed(lines[:start]) if x.strip()), "")
                skip = SKIP.search(prev)
                why = skip.group("why").strip() if skip else None
                out.append(Block(doc, start + 1, lang, lines[start + 1 : k - 1], skip=why))
            continue
        start = k
        if line.startswith("#"):
            k += 1
            lang = "prose"
        elif line.startswith("|"):
            while k < len(lines) and lines[k].startswith("|"):
                k += 1
            lang = "table"
        else:
            k += 1
            while k < len(lines) and lines[k].strip() and not lines[k].startswith(("```", "|", "#", "<!--")):
                k += 1
            lang = "prose"
        out.append(Block(doc, start + 1, lang, lines[start:k], marks=marks))
        marks = []
    if marks:
        out.append(Block(doc, len(lines), "orphan", [], marks=marks))
    return out


def blocks(doc: Path) -> list[Block]:
    """The code blocks to run and the tables and paragraphs to check against their outputs."""
    return [b for b in parse(doc) if b.lang not in ("table", "prose", "orphan") or _compared(b)]


def _compared(b: Block) -> bool:
    return b.lang in ("table", "prose") and any(kind in ("numbers", "python") for kind, _ in b.marks)


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
    doc's precision: a rounding of one of them (within half a unit of its last digit, so a wrong
    last digit fails) or within 1e-5 relative."""
    e = float(expected)
    digits = expected.lower().split("e")[0]
    ulp = 10.0 ** -(len(digits.split(".")[1]) if "." in digits else 0)
    if "e" in expected.lower():
        ulp *= 10.0 ** int(expected.lower().split("e")[1])
    tol = max(0.5 * ulp * (1 + 1e-9), 1e-5 * abs(e))
    return any(abs(a - e) <= tol for a in printed)


def _numbers(lines: list[str]) -> list[str]:
    nums: list[str] = []
    for line in lines:
        line = line.split("<-")[0]
        nums += NUMBER.findall(line.replace("│", " ").replace("┃", " "))
    return nums


def _run_snippet(code: str, where: str, cwd: Path) -> tuple[str | None, str]:
    """Run a python snippet in this process, as a script (fresh globals) in ``cwd``: ``(its
    traceback or None when it ran to its end, what it printed on stdout and stderr)``."""
    here, out = Path.cwd(), io.StringIO()
    os.chdir(cwd)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            exec(compile(code, where, "exec"), {"__name__": "__main__"})
    except Exception:
        return traceback.format_exc(), out.getvalue()
    finally:
        os.chdir(here)
    return None, out.getvalue()


def _check_numbers(block: Block, printed: str) -> None:
    """Every number a mark compares (``Block.checked``) is among the numbers ``printed``; under
    a hidden snippet (``python`` mark), they are the numbers it printed, one for one, in order."""
    assert printed, f"{block.where}: numbers marked for checking, but no code block above printed anything"
    values = [float(x) for x in _numbers(printed.splitlines())]
    stated = block.checked()
    assert stated, f"{block.where}: a doc-test mark on a table or paragraph without numbers to compare"
    if any(kind == "python" for kind, _ in block.marks):
        if block.lang == "prose":  # as counted in prose: numbers with a decimal point or an exponent
            values = [float(x) for x in _numbers(printed.splitlines()) if "." in x or "e" in x.lower()]
        wrong = [(x, v) for x, v in zip(stated, values, strict=False) if not _printed(x, [v])]
        said = f"{block.where}: the doc says {stated}, the hidden snippet printed {values}"
        assert len(values) == len(stated) and not wrong, f"{said}; first differences (doc, printed): {wrong[:5]}"
        return
    missing = [x for x in stated if not _printed(x, values)]
    said = f"{block.where}: the commands above did not print {missing} (the doc says so)"
    assert not missing, f"{said}:\n{printed[-3000:]}"


def _run_block(block: Block, cwd: Path, history: list[tuple[str, str]]) -> str:
    """Run a code block; returns what its commands printed (a snippet: stdout and stderr), and
    appends ``(command or code, what it printed)`` to ``history``."""
    where = block.where
    if block.lang == "python":
        code = "\n".join(block.body)
        failure, printed = _run_snippet(code, where, cwd)
        assert failure is None, f"{where}: python snippet failed:\n{failure[-3000:]}"
        history.append((code, printed))
        return printed
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
        history.append((cmd.text, printed))
    return "\n".join(outputs)


PARSED = {doc: parse(doc) for doc in DOCS}
ALL = [(doc, b) for doc in DOCS for b in blocks(doc)]


def test_every_number_in_tables_and_prose_is_covered() -> None:
    """The rule (docs/testing.md#numbers-in-tables-and-prose): every counted number of a table
    or paragraph is compared with an output or stated, with a reason."""
    problems = []
    for parsed in PARSED.values():
        for b in parsed:
            if b.lang == "orphan":
                problems.append(f"{b.where}: a doc-test mark above no table or paragraph")
            for kind, rest in b.marks:
                if kind == "stated" and len(_stated(rest)[1]) < 8:
                    problems.append(f"{b.where}: a stated mark must say why the numbers are not recomputed")
            if b.lang in ("table", "prose") and (missing := b.uncovered()):
                problems.append(f"{b.where}: {missing} neither compared with an output nor stated")
    assert not problems, "\n".join(problems)


def _doc(tmp_path: Path, text: str) -> list[Block]:
    doc = ROOT / "docs" / "_checker_example.md"  # parsed from text; nothing is written there
    path = tmp_path / "x.md"
    path.write_text(text, encoding="utf-8")
    return [Block(doc, b.line, b.lang, b.body, b.skip, b.hidden, b.marks) for b in parse(path)]


def test_the_rule_counts_results_and_not_references(tmp_path: Path) -> None:
    """Counted: a table's numbers, a paragraph's decimals and exponents, inline code that is a
    value; not counted: integers in prose, versions, dates, references, arguments, links."""
    text = (
        "Python 3.11, numba 0.60.1, 2026-12-07, section 5.2, eq. 5.10 and 5.15, Table 1, "
        "[x](a/1.5.md), `--tol 1e-3`, `LCA.q=5`, `dot-2`, dot-1, ISO 8855, 3 iterations: `q2 = -0.4337`, 4.76 deg, "
        "1e-9 and 31.45 N/mm, 8.4x, −0.25, `-0.5`, `-o out.yaml`.\n\n| a | b |\n|---|---|\n| `x` 3 s'21T-D | 0.5 |\n"
    )
    prose, table = _doc(tmp_path, text)
    assert prose.counted() == ["-0.4337", "4.76", "1e-9", "31.45", "8.4", "-0.25", "-0.5"]
    assert table.counted() == ["3", "0.5"]
    assert prose.uncovered() == prose.counted()
    marked = _doc(tmp_path, "<!-- doc-test: stated 1e-9 4.76: an input and a tolerance -->\n" + text)[0]
    assert marked.uncovered() == ["-0.4337", "31.45", "8.4", "-0.25", "-0.5"]
    assert _doc(tmp_path, "<!-- doc-test: stated inputs -->\n" + text)[0].uncovered() == []


def test_a_wrong_number_in_a_marked_table_fails(tmp_path: Path) -> None:
    """A marked table is compared without its header; a number the commands did not print (a
    wrong value, a wrong sign) fails the check, else the marks prove nothing."""
    text = "<!-- doc-test: numbers -->\n| p | q |\n|---|---|\n| 0.6870 | -3 |\n"
    table = _doc(tmp_path, text)[0]
    assert table.checked() == ["0.6870", "-3"]
    _check_numbers(table, "p = [0.6869999 1 2 -3]")
    with pytest.raises(AssertionError, match=r"did not print \['0.6870'\]"):  # 0.6876 rounds to 0.6876
        _check_numbers(table, "p = [0.6876 -3]")
    with pytest.raises(AssertionError, match=r"did not print \['-3'\]"):
        _check_numbers(table, "p = [0.687 3]")
    wrong = _doc(tmp_path, text.replace("0.6870", "0.695"))[0]
    with pytest.raises(AssertionError, match=r"did not print \['0.695'\]"):
        _check_numbers(wrong, "p = [0.687 -3]")
    hidden = _doc(tmp_path, "<!-- doc-test: python\nprint(0.5, -3)\n-->\n" + text.replace("0.6870", "0.5"))
    assert [(b.lang, b.hidden) for b in hidden] == [("python", True), ("table", False)]
    assert hidden[1].uncovered() == [] and hidden[1].checked() == ["0.5", "-3"]
    _check_numbers(hidden[1], "0.5 -3")
    for printed in ("-3 0.5", "0.5 -3 1", "0.5 3"):  # swapped cells, a cell missing, a sign
        with pytest.raises(AssertionError, match="the hidden snippet printed"):
            _check_numbers(hidden[1], printed)


def test_a_doc_with_a_wrong_number_fails(tmp_path: Path) -> None:
    """The whole loop on a small doc (a snippet, marks above a table and a paragraph, a hidden
    snippet, a forward ``numbers from``): right numbers pass; each wrong one fails."""
    doc = """```python
print("p =", 0.6870, -3)
```

<!-- doc-test: numbers -->
| p | q |
|---|---|
| 0.6870 | -3 |

<!-- doc-test: numbers from print(2.5) -->
The second snippet prints 2.5.

<!-- doc-test: python
print(4.76, 1e-9)
-->
Counted: 4.76 and 1e-9.

```python
print(2.5)
```
"""
    run_doc(_doc(tmp_path, doc), tmp_path)
    for right, wrong in (
        ("| 0.6870 |", "| 0.6880 |"),
        ("| -3 |", "| 3 |"),
        ("prints 2.5", "prints 2.6"),
        ("4.76 and", "4.77 and"),
    ):
        with pytest.raises(AssertionError, match=r"did not print|the hidden snippet printed"):
            run_doc(_doc(tmp_path, doc.replace(right, wrong)), tmp_path)


def test_marks_are_collected() -> None:
    """The docs' tables and paragraphs marked for checking are collected to be run (else the
    rule above proves nothing)."""
    marked = [b for _, b in ALL if b.lang in ("table", "prose")]
    assert len({b.doc for b in marked}) >= 3


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
    run_doc(todo, tmp_path)


def run_doc(todo: list[Block], cwd: Path) -> None:
    """Run a doc's blocks in order in ``cwd`` and check its marked tables and paragraphs."""
    printed = ""
    history: list[tuple[str, str]] = []
    later = []  # ``numbers from TEXT``: checked once every command of the doc has run
    for block in todo:
        if block.lang in ("table", "prose"):
            if block.source() is None:
                _check_numbers(block, printed)
            else:
                later.append(block)
        elif block.skip is None:
            printed = _run_block(block, cwd, history)
        else:
            printed = ""
    for block in later:
        outputs = [out for text, out in history if block.source() in text]
        assert outputs, f"{block.where}: no command or snippet of the doc contains {block.source()!r}"
        _check_numbers(block, "\n".join(outputs))
