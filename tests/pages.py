"""A docs page as its reader follows it: the files it has them write, the commands and
scripts it has them run, and what it says those print.

- A code block with a title (```` ```toml title="mods/snow.toml" ````) is a file to write.
- Each line of a ``bash`` block is a command (a comment after `` #`` is not part of it).
- A ``python`` block that starts with ``import sandmod`` is a script to run; other Python
  blocks are pieces of a larger file.
- A ``text`` block right after a ``bash`` block, with nothing but blank lines between,
  is what that block's last command prints: the end of its output, with the figures
  that vary from run to run (seconds, sizes: numbers with a decimal point) left out.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

BLOCK = re.compile(r'^```(\w*)(?: title="([^"]+)")?\n(.*?)^```', re.S | re.M)
DECIMAL = re.compile(r"\d+\.\d+")


@dataclass(frozen=True)
class Step:
    kind: str  # "file", "command", "script" or "prints"
    text: str
    path: str = ""  # a file's path, for "file"; for "prints", the command it follows
    span: tuple[int, int] = (0, 0)  # for "prints": where its text is in the page


def steps(page: Path | str) -> list[Step]:
    """The page's steps, in the order a reader takes them."""
    text = Path(page).read_text(encoding="utf-8") if isinstance(page, Path) else page
    found: list[Step] = []
    after_bash = -1  # where the last bash block ended
    for block in BLOCK.finditer(text):
        language, title, body = block.groups()
        if title:
            found.append(Step("file", body, title))
        elif language == "bash":
            found += [Step("command", line.split(" #")[0].strip()) for line in body.splitlines() if line.split(" #")[0].strip()]
        elif language == "python" and body.startswith("import sandmod"):
            found.append(Step("script", body))
        elif language == "text" and after_bash >= 0 and not text[after_bash:block.start()].strip():
            found.append(Step("prints", body, last_command(found), block.span(3)))
        after_bash = block.end() if language == "bash" else -1
    return found


def last_command(found: list[Step]) -> str:
    return next(step.text for step in reversed(found) if step.kind == "command")


def prints_what_it_shows(shown: str, output: str) -> bool:
    """Whether ``output`` ends with the lines ``shown``, the figures with decimal points aside."""
    want = DECIMAL.sub("#", shown).strip().splitlines()
    got = DECIMAL.sub("#", output).strip().splitlines()
    return len(got) >= len(want) and [line.rstrip() for line in got[len(got) - len(want):]] == [line.rstrip() for line in want]


def refreshed(page: str, outputs: dict[str, str]) -> str:
    """``page`` with the figures of each block of what a command prints (see :func:`steps`) made
    again from ``outputs`` (a command -> what it printed, as ``test_docs.follow`` returns):
    each shown line becomes the printed line it stands for. Raises ValueError where a block
    shows more than the figures differently from what its command printed."""
    parts, done = [], 0
    for step in steps(page):
        if step.kind != "prints" or step.path not in outputs:
            continue
        printed = outputs[step.path]
        if not prints_what_it_shows(step.text, printed):
            raise ValueError(f"{step.path} printed\n{printed}\nnot\n{step.text}")
        shown = step.text.rstrip("\n").splitlines()
        lines = printed.strip().splitlines()[-len(shown) :]
        parts += [page[done : step.span[0]], "\n".join(line.rstrip() for line in lines) + "\n"]
        done = step.span[1]
    return "".join(parts) + page[done:]
