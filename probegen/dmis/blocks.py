"""The block structure of a DMIS program, for :mod:`probegen.dmis.execute`.

Which ``IF`` an ``ELSE`` and an ``ENDIF`` belong to, which ``ENDDO`` closes a ``DO``, the
``CASE``s of a ``SELECT``, where each macro starts, the ``(label)`` lines of the main
program and of each macro.  A program whose blocks do not nest is refused before
anything runs, at the statement that breaks the nesting.
"""

from __future__ import annotations

from collections.abc import Callable

from probegen.dmis.reader import Statement
from probegen.dmis.values import DmisProgramError

OPENERS = {"IF": "ENDIF", "DO": "ENDDO", "SELECT": "ENDSEL", "MACRO": "ENDMAC",
           "BEGIN": "END"}
"""Each block's first statement and the statement that closes it."""
CLOSERS = {close: start for start, close in OPENERS.items()}


class Blocks:
    """The block structure of a program: matching openers and closers, the cases of
    each SELECT, macros, labels and the region (main program or macro) of each
    statement.  Raises a located DmisProgramError for a program whose blocks do not nest."""

    def __init__(self, stmts: tuple[Statement, ...],
                 fail: Callable[[Statement, str], DmisProgramError]) -> None:
        self.end: dict[int, int] = {}
        self.else_of: dict[int, int] = {}
        self.owner_if: dict[int, int] = {}
        self.owner_select: dict[int, int] = {}
        self.owner_macro: dict[int, int | None] = {}
        self.cases: dict[int, list[int]] = {}
        self.macros: dict[str, int] = {}
        self.labels: dict[tuple[int, str], int] = {}
        self.region: list[int] = []
        self.loops: list[tuple[int, int]] = []
        stack: list[int] = []
        macro = -1
        for k, st in enumerate(stmts):
            major = st.major
            self.region.append(macro)
            if major in OPENERS:
                if major == "MACRO" and st.label is not None:
                    if macro >= 0 or any(stmts[i].major == "MACRO" for i in stack):
                        raise fail(st, "a MACRO inside a macro")
                    macro = k
                    self.macros[st.label.name] = k
                stack.append(k)
                self.cases[k] = []
            elif major in CLOSERS or major in ("ELSE", "CASE", "DFTCAS", "ENDCAS"):
                opener = stmts[stack[-1]].major if stack else None
                wanted = CLOSERS.get(major) or ("IF" if major == "ELSE" else "SELECT")
                if opener != wanted:
                    found = f"the {opener} of line {stmts[stack[-1]].line}" if stack \
                        else "no open block"
                    raise fail(st, f"{major} without its {wanted} ({found})")
                top = stack[-1]
                if major == "ELSE":
                    self.else_of[top], self.owner_if[k] = k, top
                elif major in ("CASE", "DFTCAS", "ENDCAS"):
                    self.owner_select[k] = top
                    if major != "ENDCAS":
                        self.cases[top].append(k)
                else:
                    stack.pop()
                    self.end[top] = k
                    if major == "ENDDO":
                        self.loops.append((top, k))
                    if major == "ENDMAC":
                        self.owner_macro[k] = top if stmts[top].label is not None else None
                        if stmts[top].label is not None:
                            macro = -1
            elif major == "" and st.label is not None:
                self.labels.setdefault((macro, st.label.name), k)
        if stack:
            st = stmts[stack[-1]]
            raise fail(st, f"{st.major} is never closed ({OPENERS[st.major]})")

    def skip_if(self, pc: int) -> int:
        """Where a false IF goes on: after its ELSE, else after its ENDIF."""
        return self.else_of[pc] + 1 if pc in self.else_of else self.end[pc] + 1

    def loop_of(self, target: int) -> int | None:
        """The innermost DO whose body holds ``target`` (its index), or None."""
        inner = [start for start, end in self.loops if start < target <= end]
        return max(inner) if inner else None
