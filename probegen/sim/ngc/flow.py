"""The o-word structure of a parsed rs274ngc file: subroutines, conditionals, loops.

Read once per file before it runs (LinuxCNC 2.9, "O codes"): ``sub``/``endsub``,
``if``/``elseif``/``else``/``endif``, ``while``/``endwhile``, ``do``/``while``,
``repeat``/``endrepeat``, ``break``/``continue`` (the innermost loop with their label),
``return`` (inside a subroutine body).  Labels pair up by nesting within a subroutine
body or the main program, so a body may reuse the labels of another.  Subroutine
bodies do not nest.  A statement that does not pair up (an ``endif`` with no ``if``,
an ``if`` with no ``endif``, a ``break`` outside its loop ...) is a syntax error of the
file, reported with the others in one :class:`~probegen.errors.ProgramParseError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from probegen.errors import Diagnostic, ProgramParseError
from probegen.sim.ngc import ast

LOOPS = ("while", "do", "repeat")


@dataclass
class Flow:
    """Where each o-word statement of a file leads (indices into ``ProgramFile.lines``).

    Attributes:
        subs: subroutine label → index of its ``sub`` line.
        end: ``sub`` → its ``endsub``; a loop's first line → its last (``endwhile``, the
            closing ``while`` of a ``do``, ``endrepeat``); ``elseif``/``else`` → ``endif``.
        start: a loop's last line → its first.
        branches: ``if`` → its ``elseif``/``else`` lines and its ``endif``, in order.
        loop: ``break``/``continue`` → the first line of its loop.
        closing: the ``while`` lines that close a ``do``.
    """

    subs: dict[str, int] = field(default_factory=dict)
    end: dict[int, int] = field(default_factory=dict)
    start: dict[int, int] = field(default_factory=dict)
    branches: dict[int, list[int]] = field(default_factory=dict)
    loop: dict[int, int] = field(default_factory=dict)
    closing: set[int] = field(default_factory=set)


class _Mismatch(Exception):
    pass


@dataclass
class _Open:
    kind: str
    label: str
    index: int
    branches: list[int] = field(default_factory=list)
    has_else: bool = False


class _Builder:
    def __init__(self) -> None:
        self.flow = Flow()
        self.stack: list[_Open] = []

    def top(self, kinds: tuple[str, ...], label: str, what: str) -> _Open:
        if not self.stack or self.stack[-1].kind not in kinds or self.stack[-1].label != label:
            raise _Mismatch(f"found 'o{label} {what}' with no open "
                            f"'o{label} {' or '.join(kinds)}' to match it")
        return self.stack[-1]

    def statement(self, k: int, o: ast.OWord) -> None:
        label, word, flow = str(o.label), o.keyword, self.flow
        if word == "sub":
            if self.stack:
                raise _Mismatch(f"found 'o{label} sub' inside 'o{self.stack[-1].label} "
                                f"{self.stack[-1].kind}' (subroutine bodies do not nest)")
            if label in flow.subs:
                raise _Mismatch(f"found a second definition of subroutine o{label}")
            flow.subs[label] = k
            self.stack.append(_Open("sub", label, k))
        elif word == "endsub":
            flow.end[self.top(("sub",), label, word).index] = k
            self.stack.pop()
        elif word in ("if", "do", "repeat") or (word == "while" and not self.closes_do(label)):
            self.stack.append(_Open(word, label, k))
        elif word in ("elseif", "else"):
            opened = self.top(("if",), label, word)
            if opened.has_else:
                raise _Mismatch(f"found 'o{label} {word}' after 'o{label} else'")
            opened.branches.append(k)
            opened.has_else = word == "else"
        elif word in ("endif", "endwhile", "endrepeat", "while"):
            kinds = {"endif": ("if",), "endwhile": ("while",), "endrepeat": ("repeat",),
                     "while": ("do",)}[word]
            opened = self.top(kinds, label, word)
            self.stack.pop()
            if word == "endif":
                flow.branches[opened.index] = [*opened.branches, k]
                flow.end.update(dict.fromkeys(opened.branches, k))
            else:
                flow.end[opened.index], flow.start[k] = k, opened.index
                if word == "while":
                    flow.closing.add(k)
        elif word in ("break", "continue"):
            found = next((o for o in reversed(self.stack) if o.kind == "sub" or (
                o.kind in LOOPS and o.label == label)), None)
            if found is None or found.kind == "sub":
                raise _Mismatch(f"found 'o{label} {word}' outside a loop labelled o{label}")
            flow.loop[k] = found.index
        elif word == "return" and not any(o.kind == "sub" for o in self.stack):
            raise _Mismatch(f"found 'o{label} return' outside a subroutine body")

    def closes_do(self, label: str) -> bool:
        return bool(self.stack) and self.stack[-1].kind == "do" and self.stack[-1].label == label


def build_flow(file: ast.ProgramFile) -> Flow:
    """The o-word structure of ``file``.

    Raises:
        ProgramParseError: statements that do not pair up, one diagnostic each.
    """
    builder = _Builder()
    problems: list[Diagnostic] = []
    for k, line in enumerate(file.lines):
        if line.oword is not None:
            try:
                builder.statement(k, line.oword)
            except _Mismatch as exc:
                problems.append(Diagnostic(file.source, line.number, line.oword.column,
                                           str(exc), line.text))
    for opened in builder.stack:
        line = file.lines[opened.index]
        closer = {"sub": "endsub", "if": "endif", "while": "endwhile", "do": "while",
                  "repeat": "endrepeat"}[opened.kind]
        problems.append(Diagnostic(file.source, line.number, line.oword.column if line.oword
                                   else 1, f"expected 'o{opened.label} {closer}' closing "
                                   f"'o{opened.label} {opened.kind}', found the end of the file",
                                   line.text))
    if problems:
        raise ProgramParseError("\n".join(str(d) for d in problems[:10]), tuple(problems))
    return builder.flow
