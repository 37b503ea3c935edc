"""Parse rs274ngc program text (LinuxCNC 2.9) into lines of words, parameter settings,
o-word statements and comments.

The text is read as LinuxCNC's interpreter reads a file:

* Lines end with LF, CR LF or CR.  If the first non-blank line is ``%``, the program
  ends at the next ``%`` line (nothing after it is read).
* Outside comments, blanks and tabs mean nothing (``G0X +0. 12 34Y 7`` is
  ``G0 X0.1234 Y7``) and letters may be either case; named parameters and o-word
  names are lower case with their blanks removed (``#<P a R am>`` is ``#<param>``).
* ``( ... )`` is a comment (a ``(`` inside one is an error, as is one left open);
  ``;`` starts a comment running to the end of the line.  Only the last comment of a
  line counts; it is *active* when it starts (after blanks) with ``MSG,``, ``DEBUG,``,
  ``PRINT,``, ``LOG,``, ``LOGOPEN,``, ``LOGAPPEND,``, ``ABORT,`` (any case, the comma
  right after the keyword: ``(LOG ,x)`` is a plain comment, as ``rs274`` 2.9 reads it),
  is ``LOGCLOSE`` or ``PROBECLOSE``, or starts with ``PROBEOPEN``.
* A line: optional ``/`` (block delete), optional ``N`` number, then either one
  o-word statement (``o100 if [...]``, ``o<name> call [1] [2]``; nothing else but a
  comment on its line) or any number of words (a letter and a real value: a number,
  ``[expression]``, ``#parameter``, a function ``SIN[30]``, any of them after ``-``)
  and parameter settings ``#n = value``, ``#<name> = value``.  A letter other than
  G and M may appear once per line.
* Expressions: ``**``, then ``* / MOD``, then ``+ -``, then ``EQ NE GT GE LT LE``,
  then ``AND OR XOR`` (lowest); left to right within a level.

Every bad line is reported (``source:line:column``, what was expected, what was
found, the line with a caret) in one :class:`~probegen.errors.ProgramParseError`
before anything runs.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from probegen.errors import Diagnostic, ProgramParseError
from probegen.sim.ngc import ast

MAX_LINE = 256
"""Longest line LinuxCNC reads, characters."""
MAX_NESTING = 40
"""Deepest nesting of brackets, functions, parameter indirections and signs in a value."""
MAX_SHOWN = 10
"""Diagnostics shown in the error message (all are kept in ``error.diagnostics``)."""
WORD_LETTERS = frozenset("abcdfghijklmpqrstuvwxyz")
FUNCTIONS = frozenset({"abs", "acos", "asin", "cos", "exp", "fix", "fup", "ln", "round", "sin",
                       "sqrt", "tan"})
LEVELS: tuple[tuple[str, ...], ...] = (
    ("and", "or", "xor"), ("eq", "ne", "gt", "ge", "lt", "le"), ("+", "-"), ("*", "/", "mod"),
    ("**",))
"""Binary operators by precedence, lowest first; ``**`` is tried before ``*``."""
ACTIVE = ("MSG", "DEBUG", "PRINT", "LOGOPEN", "LOGAPPEND", "LOG", "ABORT")
"""Active comments taking text after a comma."""
KEYWORDS = {"sub": (0, 0), "endsub": (0, 1), "call": (0, 30), "do": (0, 0), "while": (1, 1),
            "endwhile": (0, 0), "if": (1, 1), "elseif": (1, 1), "else": (0, 0),
            "endif": (0, 0), "break": (0, 0), "continue": (0, 0), "repeat": (1, 1),
            "endrepeat": (0, 0), "return": (0, 1)}
"""O-word keywords and the bracketed arguments each takes (fewest, most)."""


class _Bad(Exception):
    """A syntax error at a position of the code string."""

    def __init__(self, position: int, message: str) -> None:
        super().__init__(message)
        self.position = position
        self.message = message


def comment_of(text: str, column: int) -> ast.Comment:
    """Classify a comment's text (without its parentheses)."""
    body = text.lstrip(" \t")
    upper = body.upper()
    for kind in ACTIVE:
        if upper.startswith(kind + ","):
            return ast.Comment(kind, body[len(kind) + 1:], column)
    if upper.rstrip(" \t") in ("LOGCLOSE", "PROBECLOSE"):
        return ast.Comment(upper.rstrip(" \t"), "", column)
    if upper.startswith("PROBEOPEN"):
        return ast.Comment("PROBEOPEN", body[len("PROBEOPEN"):].strip(" \t"), column)
    return ast.Comment("", text, column)


def split_code(raw: str) -> tuple[str, list[int], ast.Comment | None]:
    """The code of a line (lower case, no blanks, no comments), the 1-based column of
    each of its characters, and the line's last comment.

    Raises:
        _Bad: a comment nested in another, or left open (position: its column - 1,
            negative, so the caller reports that column).
    """
    code: list[str] = []
    columns: list[int] = []
    comment: ast.Comment | None = None
    i, n = 0, len(raw)
    while i < n:
        ch = raw[i]
        if ch == "(":
            end = raw.find(")", i + 1)
            inner = raw.find("(", i + 1)
            if end < 0:
                raise _Bad(-(i + 1), "expected ')' closing the comment, found the end of "
                                     "the line")
            if 0 <= inner < end:
                raise _Bad(-(inner + 1), "found '(' inside a comment (comments do not nest)")
            comment = comment_of(raw[i + 1:end], i + 1)
            i = end + 1
            continue
        if ch == ";":
            comment = comment_of(raw[i + 1:], i + 1)
            break
        if ch not in " \t":
            code.append(ch.lower())
            columns.append(i + 1)
        i += 1
    return "".join(code), columns, comment


class _LineParser:
    """Recursive descent over one line's code string."""

    def __init__(self, code: str) -> None:
        self.s = code
        self.i = 0
        self.depth = 0

    # -- helpers --------------------------------------------------------------------
    def peek(self, k: int = 0) -> str:
        j = self.i + k
        return self.s[j] if j < len(self.s) else ""

    def found(self) -> str:
        rest = self.s[self.i:self.i + 8]
        return f"'{rest}'" if rest else "the end of the line"

    def bad(self, expected: str) -> _Bad:
        return _Bad(self.i, f"expected {expected}, found {self.found()}")

    def expect(self, ch: str) -> None:
        if self.peek() != ch:
            raise self.bad(f"'{ch}'")
        self.i += 1

    def letters(self) -> str:
        j = self.i
        while j < len(self.s) and self.s[j].isalpha():
            j += 1
        word, self.i = self.s[self.i:j], j
        return word

    # -- values ---------------------------------------------------------------------
    def number(self) -> float:
        j = self.i
        while j < len(self.s) and self.s[j].isdigit():
            j += 1
        if j < len(self.s) and self.s[j] == ".":
            j += 1
            while j < len(self.s) and self.s[j].isdigit():
                j += 1
        text = self.s[self.i:j]
        if not any(c.isdigit() for c in text):
            raise self.bad("a number")
        self.i = j
        return float(text)

    def name(self) -> str:
        """``<name>`` after ``#`` or ``o``: the name between the angle brackets."""
        self.expect("<")
        end = self.s.find(">", self.i)
        if end <= self.i:
            raise self.bad("a name and '>'" if end < 0 else "a name")
        name, self.i = self.s[self.i:end], end + 1
        return name

    def parameter(self) -> ast.Param | ast.Named:
        """What follows ``#``: ``<name>``, a number, ``[expr]`` or another ``#``."""
        if self.peek() == "<":
            return ast.Named(self.name())
        ch = self.peek()
        if ch.isdigit() or ch == ".":
            return ast.Param(ast.Num(self.number()))
        if ch == "[":
            return ast.Param(self.bracketed())
        if ch == "#":
            self.i += 1
            return ast.Param(self.nest(self.parameter))
        raise self.bad("a parameter number, '<name>' or '['")

    def bracketed(self) -> ast.Expr:
        self.expect("[")
        value = self.expression(0)
        self.expect("]")
        return value

    def value(self) -> ast.Expr:
        """A real value: a number, ``[expr]``, ``#param``, a function, or one after a sign."""
        return self.nest(self.nested_value)

    def nest(self, read: Callable[[], ast.Expr]) -> ast.Expr:
        """``read()`` one level deeper (at most :data:`MAX_NESTING`)."""
        if self.depth == MAX_NESTING:
            raise self.bad(f"a value nested at most {MAX_NESTING} deep")
        self.depth += 1
        try:
            return read()
        finally:
            self.depth -= 1

    def nested_value(self) -> ast.Expr:
        ch = self.peek()
        if ch in "+-" and ch:
            self.i += 1
            arg = self.value()
            return ast.Neg(arg) if ch == "-" else arg
        if ch.isdigit() or ch == ".":
            return ast.Num(self.number())
        if ch == "[":
            return self.bracketed()
        if ch == "#":
            self.i += 1
            return self.parameter()
        if ch.isalpha():
            start = self.i
            name = self.letters()
            if name == "atan":
                y = self.bracketed()
                self.expect("/")
                return ast.Atan(y, self.bracketed())
            if name == "exists":
                self.expect("[")
                self.expect("#")
                if self.peek() != "<":
                    raise self.bad("a named parameter #<name> (EXISTS takes no number)")
                named = self.name()
                self.expect("]")
                return ast.Exists(named)
            if name in FUNCTIONS:
                return ast.Func(name, self.bracketed())
            self.i = start
            raise self.bad("a function (ABS ACOS ASIN ATAN COS EXISTS EXP FIX FUP LN ROUND "
                           "SIN SQRT TAN)")
        raise self.bad("a number, '[', '#' or a function")

    def operator(self, level: int) -> str | None:
        for op in LEVELS[level]:
            if self.s.startswith(op, self.i) and not (op == "*" and self.peek(1) == "*"):
                self.i += len(op)
                return op
        return None

    def expression(self, level: int) -> ast.Expr:
        if level == len(LEVELS):
            return self.value()
        left = self.expression(level + 1)
        while (op := self.operator(level)) is not None:
            left = ast.Binary(op, left, self.expression(level + 1))
        return left

    # -- a line ---------------------------------------------------------------------
    def oword(self, columns: list[int]) -> ast.OWord:
        self.i += 1  # the o
        label: str | ast.Expr
        if self.peek() == "<":
            label = f"<{self.name()}>"
        elif self.peek().isdigit():
            label = str(int(self.number()))
        elif self.peek() in ("[", "#"):
            label = self.value()
        else:
            raise self.bad("an o-word number or <name>")
        position = self.i
        keyword = self.letters()
        if keyword not in KEYWORDS:
            self.i = position
            if not keyword and self.i == len(self.s):
                raise _Bad(0, "found a Fanuc-style program number (O100 ... M99): not "
                              "supported, use o100 sub ... o100 endsub")
            raise self.bad("an o-word keyword (sub endsub call do while endwhile if elseif "
                           "else endif break continue repeat endrepeat return)")
        args: list[ast.Expr] = []
        while self.peek() == "[":
            args.append(self.bracketed())
        fewest, most = KEYWORDS[keyword]
        if self.i < len(self.s):
            raise self.bad("'[' or the end of the line (an o-word line holds nothing else)")
        if not fewest <= len(args) <= most:
            raise _Bad(position, f"expected {_count(fewest, most)} after '{keyword}', found "
                                 f"{len(args)}")
        if not isinstance(label, str) and keyword != "call":
            raise _Bad(0, f"expected a fixed o-word number or <name> with '{keyword}', found "
                          "a computed one (only 'call' takes o[expression])")
        return ast.OWord(label, keyword, tuple(args), columns[0] if columns else 1)

    def items(self, columns: list[int]) -> tuple[list[ast.Word], list[ast.Assign]]:
        words: list[ast.Word] = []
        assigns: list[ast.Assign] = []
        seen: set[str] = set()
        while self.i < len(self.s):
            start = self.i
            ch = self.peek()
            if ch == "#":
                self.i += 1
                target = self.parameter()
                self.expect("=")
                assigns.append(ast.Assign(target, self.value(), columns[start]))
            elif ch in WORD_LETTERS and ch:
                self.i += 1
                if ch not in "gm" and ch in seen:
                    raise _Bad(start, f"found a second {ch.upper()} word on the line (one "
                                      f"each, except G and M)")
                seen.add(ch)
                words.append(ast.Word(ch.upper(), self.value(), columns[start]))
            else:
                raise self.bad("a word (a letter and a value), '#' or o-word")
        return words, assigns


def _count(fewest: int, most: int) -> str:
    if fewest == most:
        return f"{fewest} bracketed value{'s' if fewest != 1 else ''}"
    return f"{fewest} to {most} bracketed values"


def parse_line(raw: str, number: int) -> ast.Line:
    """Parse one line (``number`` its 1-based line number).

    Raises:
        _Bad: the line does not parse.
    """
    code, columns, comment = split_code(raw)
    p = _LineParser(code)
    delete = p.peek() == "/"
    p.i += delete
    if p.peek() == "n":
        p.i += 1
        p.number()
    if p.peek() == "o":
        return ast.Line(number, raw, delete, p.oword(columns[p.i:]), comment=comment)
    words, assigns = p.items(columns)
    return ast.Line(number, raw, delete, None, tuple(words), tuple(assigns), comment)


def _diagnostic(source: str, number: int, raw: str, exc: _Bad) -> Diagnostic:
    if exc.position < 0:
        column = -exc.position
    else:
        _, columns, _ = split_code(raw)
        column = columns[exc.position] if exc.position < len(columns) else (
            len(raw.rstrip()) + 1)
    return Diagnostic(source, number, column, exc.message, raw)


def parse_program(text: str, *, source: str = "<program>") -> ast.ProgramFile:
    """Parse rs274ngc program text.

    Raises:
        ProgramParseError: any line does not parse; one diagnostic per bad line.
    """
    raw_lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    first = next((k for k, raw in enumerate(raw_lines) if raw.strip()), len(raw_lines))
    percent = first < len(raw_lines) and raw_lines[first].strip() == "%"
    lines: list[ast.Line] = []
    problems: list[Diagnostic] = []
    closed = False
    for k in range(first + percent if percent else 0, len(raw_lines)):
        raw = raw_lines[k]
        if percent and raw.strip() == "%":
            closed = True
            break
        if len(raw) > MAX_LINE:
            problems.append(Diagnostic(source, k + 1, MAX_LINE + 1, f"expected at most "
                                       f"{MAX_LINE} characters, found {len(raw)}", raw))
            continue
        try:
            line = parse_line(raw, k + 1)
        except _Bad as exc:
            problems.append(_diagnostic(source, k + 1, raw, exc))
            continue
        if line.oword or line.words or line.assigns or line.comment:
            lines.append(line)
    if problems:
        shown = "\n".join(str(d) for d in problems[:MAX_SHOWN])
        if len(problems) > MAX_SHOWN:
            shown += f"\n... and {len(problems) - MAX_SHOWN} more"
        raise ProgramParseError(shown, tuple(problems))
    return ast.ProgramFile(source, tuple(lines), percent and closed)


def read_program(path: Path) -> ast.ProgramFile:
    """Read and parse a program file (bytes outside ASCII read as Latin-1).

    Raises:
        ProgramParseError: the file cannot be read or does not parse.
    """
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ProgramParseError(f"{path}: cannot read: {exc.strerror}") from None
    return parse_program(data.decode("latin-1"), source=str(path))
