"""Run the executable half of DMIS: variables, control flow and macros.

:func:`execute` walks a parsed program as a CMM controller does and yields, in the order
they run, every statement reached, with every variable and expression in its
parameters replaced by its value (:func:`is_control` tells the statements this module
carries out itself from the ones the caller executes: motion, features, output...).
So a ``DO`` loop of ``PTMEAS`` comes out as the straight list of its touches.

Executed here (DMIS 5.3):

* ``DECL/COMMON|GLOBAL|LOCAL,INTGR|LONG|REAL|DOUBLE|CHAR,n|BOOL|VECTOR,name[,name[n]...]``
* ``X=ASSIGN/expr``, ``ASSIGN/X=expr``, ``A[i]=ASSIGN/expr`` (:mod:`probegen.dmis.values`)
* ``X=OBTAIN/label,index``: parameter ``index`` (1 = the first after ``/``) of the
  label's statement as the CMM would output it, from the caller (:class:`Host`)
* ``IF/(cond)`` ... [``ELSE``] ... ``ENDIF``; ``(name)`` and ``JUMPTO/(name)``
* ``DO/i,start,stop[,step]`` ... ``ENDDO`` (bounds evaluated once; ``i`` counts from
  ``start`` by ``step`` while it has not passed ``stop``)
* ``SELECT/expr``, ``CASE/v[,v...]`` ... ``ENDCAS``, ``DFTCAS`` ... ``ENDCAS``, ``ENDSEL``
* ``M(name)=MACRO/p1,p2...`` ... ``ENDMAC`` and ``CALL/M(name),a1,a2...``: a number,
  string, BOOL or VECTOR argument becomes a local variable of the call; a label or a
  keyword stands in for the parameter wherever it is written (``F(P)`` with ``P`` =
  ``F(C1)`` is ``F(C1)``).  A ``MACRO`` without a label, and ``BEGIN/...`` ... ``END/...``,
  wrap statements that run in place (WinWerth wraps whole programs so).
* ``TEXT/QUERY,(name),length,type,just,'prompt'[,default]``: the answer from
  ``answers`` (by name), else the statement's default; never a prompt.

Guards: at most ``max_steps`` statements run (:data:`MAX_STEPS`) and macro calls nest at
most :data:`MAX_CALLS` deep; beyond, a located :class:`DmisProgramError`, never a hang.
With ``measured="refuse"`` (the post-processor: a machine-tool program is fixed when it
is posted) a branch, loop bound, selection or statement that uses a value measured at
run time (``OBTAIN`` of an actual) raises ``UnsupportedError`` naming the statement.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, replace
from typing import Literal, Protocol

from probegen.dmis.blocks import Blocks
from probegen.dmis.expressions import Evaluator, Frame, UnknownName
from probegen.dmis.reader import DmisFile, Expr, Group, Label, Param, Statement, Text
from probegen.dmis.values import (
    TYPES,
    DmisProgramError,
    EvalError,
    Functions,
    Value,
    Variable,
    relation,
    to_param,
    truth,
)
from probegen.errors import UnsupportedError

MAX_STEPS = 200_000
"""Most statements one run executes (loops counted per pass): more is taken as an
endless loop."""

MAX_CALLS = 64
"""Deepest nesting of macro calls."""

CONTROL = frozenset({
    "", "DECL", "ASSIGN", "OBTAIN", "IF", "ELSE", "ENDIF", "DO", "ENDDO", "SELECT", "CASE",
    "DFTCAS", "ENDCAS", "ENDSEL", "MACRO", "ENDMAC", "JUMPTO", "BEGIN", "END",
})
"""Major words carried out here (``""`` is a ``(label)`` line); ``CALL/M(x)`` too."""

def is_control(st: Statement) -> bool:
    """True for a statement :func:`execute` carries out itself (the caller only lists it)."""
    if st.major == "CALL":
        return bool(st.params) and isinstance(st.params[0], Label) and st.params[0].kind == "M"
    return st.major in CONTROL


class Host(Protocol):
    """What the run of a program knows beyond its text: the values ``OBTAIN`` reads."""

    def obtain(self, label: Label, index: int) -> tuple[Param, bool]:
        """Return parameter ``index`` (1-based) of ``label``'s statement as output, and
        whether it was measured (an actual) rather than known before the run.

        Raises:
            EvalError: the label is unknown or has no such parameter.
        """
        ...


@dataclass(slots=True)
class Run:
    """One run of a program; :meth:`statements` yields what it executes."""

    program: DmisFile
    host: Host
    answers: Mapping[str, object] = field(default_factory=dict)
    measured: Literal["run", "refuse"] = "run"
    max_steps: int = MAX_STEPS
    notes: list[tuple[int, str, str]] = field(default_factory=list)
    ev: Evaluator = field(default_factory=Evaluator)

    def error(self, st: Statement, message: str) -> DmisProgramError:
        return DmisProgramError(f"{self.program.source}:{st.line}: {message} ({st.text})")

    def refuse(self, st: Statement, line: int, what: str) -> UnsupportedError:
        return UnsupportedError(
            f"{self.program.source}:{st.line}: cannot post-process {st.major or 'the label'} "
            f"for a machine tool: {what} a value measured at run time (OBTAIN at line "
            f"{line}); a machine-tool program is fixed when it is posted\n    {st.text}")

    def statements(self) -> Iterator[Statement]:
        """Yield every statement executed, in order, parameters evaluated."""
        stmts = self.program.statements
        blocks = Blocks(stmts, self.error)
        pc, steps = 0, 0
        while pc < len(stmts):
            st = stmts[pc]
            steps += 1
            if steps > self.max_steps:
                raise self.error(st, f"more than {self.max_steps} statements executed: an "
                                     "endless loop (JUMPTO, DO)?")
            try:
                if is_control(st):
                    yield st
                    pc = self.control(st, pc, blocks)
                    continue
                out = self.substituted(st)
            except EvalError as exc:
                raise self.error(st, str(exc)) from None
            if out.major == "UNITS":
                self.ev.set_angle(1.0 if "ANGRAD" in out.params else Evaluator().angle)
            yield out
            pc += 1

    # ---------------------------------------------------------------- control flow

    def control(self, st: Statement, pc: int, blocks: Blocks) -> int:
        """Carry out a control statement; return the next statement index."""
        major, params = st.major, st.params
        if major == "DECL":
            self.declare(st)
        elif major == "ASSIGN":
            target, value = _assignment(params)
            self.ev.assign(target, self.ev.evaluate(value), self.ev.measured)
        elif major == "OBTAIN":
            self.obtain(st)
        elif major == "IF":
            return pc + 1 if self.condition(st) else blocks.skip_if(pc)
        elif major == "ELSE":
            return blocks.end[blocks.owner_if[pc]] + 1
        elif major == "DO":
            return self.start_loop(st, pc, blocks)
        elif major == "ENDDO":
            return self.next_pass(st, pc)
        elif major == "SELECT":
            return self.select(st, pc, blocks)
        elif major in ("CASE", "DFTCAS", "ENDCAS"):
            return blocks.end[blocks.owner_select[pc]] + 1  # a case body has ended
        elif major == "MACRO":
            return pc + 1 if st.label is None else blocks.end[pc] + 1  # a definition
        elif major == "ENDMAC":
            return self.leave_macro(pc, blocks)
        elif major == "CALL":
            return self.call(st, pc, blocks)
        elif major == "JUMPTO":
            return self.jump(st, pc, blocks)
        return pc + 1

    def declare(self, st: Statement) -> None:
        params = list(st.params)
        scope = params.pop(0) if params and params[0] in ("COMMON", "GLOBAL", "LOCAL") \
            else "LOCAL"
        kind = params.pop(0) if params else None
        if kind not in TYPES:
            raise EvalError(f"DECL: expected a type ({', '.join(TYPES)}), found "
                            f"{kind if kind is not None else 'nothing'}")
        length = None
        if kind == "CHAR":
            size = params.pop(0) if params else None
            if not isinstance(size, int) or size < 1:
                raise EvalError(f"DECL/...,CHAR: expected the length, found {size}")
            length = size
        if not params:
            raise EvalError("DECL: no variable named")
        table = self.ev.frame.scope if scope == "LOCAL" else self.ev.globals
        for item in params:
            name, dims = _declared_name(item)
            old = table.get(name)
            var = Variable.declared(str(kind), length, dims)
            if old is not None and (old.type, old.length, old.dims) != (var.type, var.length,
                                                                         var.dims):
                raise EvalError(f"{name} is already declared {old.type}")
            if old is None:
                table[name] = var

    def obtain(self, st: Statement) -> None:
        if len(st.params) != 2 or not isinstance(st.params[0], Expr) \
                or st.params[0].op != "=":
            raise EvalError("OBTAIN expects X=OBTAIN/label,index")
        target, label = st.params[0].operands
        index = self.ev.evaluate(st.params[1])
        if not isinstance(label, Label) or not isinstance(index, int) or index < 1:
            raise EvalError("OBTAIN expects a label and a parameter index >= 1")
        found, measured = self.host.obtain(Label(label.kind, self.ev.label_name(label.name)),
                                           index)
        value = self.ev.evaluate(found) if not isinstance(found, str) else found
        self.ev.assign(target, value, st.line if measured else None)

    def condition(self, st: Statement) -> bool:
        if len(st.params) != 1:
            raise EvalError(f"{st.major} expects one condition in parentheses")
        value = truth(self.ev.evaluate(st.params[0]))
        self.check_known(st, "branches on")
        return value

    def check_known(self, st: Statement, what: str) -> None:
        """Refuse (``measured="refuse"``) what depends on a measured value."""
        if self.ev.measured is not None and self.measured == "refuse":
            raise self.refuse(st, self.ev.measured, what)

    def start_loop(self, st: Statement, pc: int, blocks: Blocks) -> int:
        if len(st.params) not in (3, 4) or not isinstance(st.params[0], str):
            raise EvalError("DO expects index,start,stop[,step]")
        name = st.params[0]
        bounds: list[float] = []
        for param in st.params[1:]:
            value = self.ev.evaluate(param)
            self.check_known(st, "loops over")
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise EvalError(f"DO: expected a number, found {value!r}")
            bounds.append(value)
        start, stop, step = bounds[0], bounds[1], bounds[2] if len(bounds) == 3 else 1
        if step == 0:
            raise EvalError("DO: the step is 0 (an endless loop)")
        if (stop - start) / step + 1 > self.max_steps:
            raise EvalError(f"DO runs {int((stop - start) / step) + 1} times (at most "
                            f"{self.max_steps} statements are executed)")
        self.ev.assign(name, start, None)
        if (step > 0 and start > stop) or (step < 0 and start < stop):
            return blocks.end[pc] + 1
        self.ev.frame.loops.append((pc, blocks.end[pc], name, stop, step))
        return pc + 1

    def next_pass(self, st: Statement, pc: int) -> int:
        loops = self.ev.frame.loops
        if not loops or loops[-1][1] != pc:
            raise EvalError("ENDDO reached outside its DO loop (a JUMPTO into it?)")
        start, _, name, stop, step = loops[-1]
        value = self.ev.evaluate(name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise EvalError(f"DO index {name} is not a number")
        value = value + step
        self.ev.assign(name, value, None)
        if (step > 0 and value > stop) or (step < 0 and value < stop):
            loops.pop()
            return pc + 1
        return start + 1

    def select(self, st: Statement, pc: int, blocks: Blocks) -> int:
        if len(st.params) != 1:
            raise EvalError("SELECT expects one value")
        value = self.ev.evaluate(st.params[0])
        self.check_known(st, "selects on")
        default = None
        for case in blocks.cases[pc]:
            case_st = self.program.statements[case]
            if case_st.major == "DFTCAS":
                default = case
                continue
            for param in case_st.params:
                try:
                    if relation(".EQ.", value, self.ev.evaluate(param)):
                        return case + 1
                except EvalError as exc:
                    raise self.error(case_st, str(exc)) from None
        return default + 1 if default is not None else blocks.end[pc] + 1

    def call(self, st: Statement, pc: int, blocks: Blocks) -> int:
        label = st.params[0]
        assert isinstance(label, Label)
        start = blocks.macros.get(label.name)
        if start is None:
            raise EvalError(f"M({label.name}) is not defined (M({label.name})=MACRO/...)")
        if len(self.ev.frames) > MAX_CALLS:
            raise EvalError(f"macro calls nested more than {MAX_CALLS} deep (a macro "
                            "calling itself?)")
        names = [_parameter(p) for p in self.program.statements[start].params]
        args = st.params[1:]
        if len(args) != len(names):
            raise EvalError(f"M({label.name}) has {len(names)} parameters, found "
                            f"{len(args)} arguments")
        frame = Frame(macro=label.name, back=pc + 1)
        for name, arg in zip(names, args, strict=True):
            self.bind(frame, name, arg)
        self.ev.frames.append(frame)
        return start + 1

    def bind(self, frame: Frame, name: str, arg: Param) -> None:
        """Bind one macro argument (evaluated in the caller) to parameter ``name``."""
        if isinstance(arg, Label):
            frame.words[name] = Label(arg.kind, self.ev.label_name(arg.name))
            return
        try:
            value = self.ev.evaluate(arg)
        except UnknownName:
            frame.words[name] = arg  # a keyword (XAXIS, INNER ...)
            return
        if isinstance(value, Label):
            frame.words[name] = value
            return
        kind = {bool: "BOOL", int: "INTGR", float: "REAL", str: "CHAR"}.get(type(value),
                                                                           "VECTOR")
        var = Variable.declared(kind, None, ())
        var.values[0], var.measured[0] = value, self.ev.measured
        frame.scope[name] = var
        if isinstance(value, str):
            frame.words[name] = Text(value)

    def leave_macro(self, pc: int, blocks: Blocks) -> int:
        if blocks.owner_macro.get(pc) is None:
            return pc + 1  # the end of a wrapper MACRO without a label
        frame = self.ev.frames.pop() if len(self.ev.frames) > 1 else None
        if frame is None:
            raise EvalError("ENDMAC reached outside a macro call")
        return frame.back

    def jump(self, st: Statement, pc: int, blocks: Blocks) -> int:
        name = _jump_name(st.params)
        region = blocks.region[pc]
        target = blocks.labels.get((region, name))
        if target is None:
            raise EvalError(f"JUMPTO: no label ({name})"
                            + (" in this macro" if region >= 0 else ""))
        loops = self.ev.frame.loops
        while loops and not loops[-1][0] < target <= loops[-1][1]:
            loops.pop()
        inner = blocks.loop_of(target)
        if inner is not None and not any(loop[0] == inner for loop in loops):
            line = self.program.statements[inner].line
            raise EvalError(f"JUMPTO ({name}) jumps into the DO loop of line {line}")
        return target

    # ---------------------------------------------------------------- substitution

    def substituted(self, st: Statement) -> Statement:
        """``st`` with its label resolved and every variable and expression replaced by
        its value (a VECTOR by its three numbers); keywords stay."""
        if st.major == "TEXT" and st.params and st.params[0] == "QUERY":
            self.query(st)
            return st
        marks: list[int] = []
        params: list[Param] = []
        for param in st.params:
            params.extend(self.param(param, marks))
        label = st.label
        if label is not None and label.kind:
            self.ev.measured = None
            label = Label(label.kind, self.ev.label_name(label.name))
            marks += [self.ev.measured] if self.ev.measured is not None else []
        if marks and self.measured == "refuse":
            raise self.refuse(st, marks[0], "uses")
        return replace(st, label=label, params=tuple(params))

    def param(self, param: Param, marks: list[int]) -> tuple[Param, ...]:
        if isinstance(param, int | float | Text):
            return (param,)
        if isinstance(param, Expr) and param.op in ("=", ":"):
            return (param,)  # an assignment or a WRITE format: left as written
        if isinstance(param, str) and param not in (".TRUE.", ".FALSE."):
            word = self.ev.frame.words.get(param)
            if word is not None and not isinstance(word, Text):
                return (word,)
        try:
            value = self.ev.evaluate(param)
        except UnknownName:
            return (param,)
        if self.ev.measured is not None:
            marks.append(self.ev.measured)
        return _as_params(value)

    def query(self, st: Statement) -> None:
        params = st.params
        name = _jump_name(params[1:2]) if len(params) > 1 else ""
        if not name:
            raise EvalError("TEXT/QUERY expects (name),length,type,justify,'prompt'")
        if name in self.answers:
            answer: object = self.answers[name]
            how = "from the answers file"
        elif len(params) > 6:
            answer, how = self.ev.evaluate(params[6]), "the statement's default"
        else:
            raise EvalError(f"TEXT/QUERY ({name}) has no answer: give one in an answers "
                            f"file ({name} = ...) or a default after the prompt")
        var = self.ev.variable(name)
        if var is None:
            raise EvalError(f"TEXT/QUERY: {name} is not declared")
        if isinstance(answer, str) and var.type not in ("CHAR",):
            answer = Functions().table()["VAL"][2](answer)
        if not isinstance(answer, bool | int | float | str):
            raise EvalError(f"TEXT/QUERY ({name}): the answer {answer!r} is not a value")
        self.ev.assign(name, answer, None)
        self.notes.append((st.line, st.text, f"answered {answer!r} ({how}); no prompt in "
                                             "a batch run"))


def _as_params(value: Value) -> tuple[Param, ...]:
    return (value,) if isinstance(value, Label) else to_param(value)


def _assignment(params: tuple[Param, ...]) -> tuple[Param, Param]:
    if len(params) != 1 or not isinstance(params[0], Expr) or params[0].op != "=":
        raise EvalError("ASSIGN expects X=ASSIGN/expression (or ASSIGN/X=expression)")
    target, value = params[0].operands
    return target, value


def _declared_name(item: Param) -> tuple[str, tuple[int, ...]]:
    if isinstance(item, str):
        return item, ()
    if isinstance(item, Expr) and item.op == "[]" and isinstance(item.operands[0], str):
        dims = item.operands[1:]
        if all(isinstance(d, int) and not isinstance(d, bool) and d >= 1 for d in dims):
            return item.operands[0], tuple(int(d) for d in dims)  # type: ignore[arg-type]
    raise EvalError(f"DECL: expected a variable name (or NAME[n]), found {item}")


def _parameter(param: Param) -> str:
    if isinstance(param, str):
        return param
    if isinstance(param, Text):
        return param.value.upper()
    raise EvalError(f"MACRO: expected parameter names, found {param}")


def _jump_name(params: tuple[Param, ...]) -> str:
    item = params[0] if len(params) == 1 else None
    if isinstance(item, Group) and len(item.items) == 1:
        item = item.items[0]
    if isinstance(item, str):
        return item
    if isinstance(item, int) and not isinstance(item, bool):
        return str(item)
    raise EvalError("expected a label in parentheses, (name)")


def execute(program: DmisFile, host: Host, *, answers: Mapping[str, object] | None = None,
            measured: Literal["run", "refuse"] = "run", max_steps: int = MAX_STEPS,
            notes: list[tuple[int, str, str]] | None = None) -> Iterator[Statement]:
    """Yield the statements ``program`` executes (module docstring); ``notes`` collects
    (line, statement, note) for answered queries."""
    run = Run(program, host, answers or {}, measured, max_steps)
    if notes is not None:
        run.notes = notes
    return run.statements()


def load_answers(path: str) -> dict[str, str | int | float]:
    """Read the answers to a program's ``TEXT/QUERY`` statements: a TOML file of
    ``NAME = value`` lines (a string or a number; names case-insensitive).

    Raises:
        SpecError: the file is missing, not TOML, or holds a value of another kind.
    """
    from probegen.errors import SpecError
    from probegen.files import load_toml

    out: dict[str, str | int | float] = {}
    for key, value in load_toml(path).items():
        if not isinstance(value, str | int | float) or isinstance(value, bool):
            raise SpecError(f"{path}: answer {key!r}: expected a string or a number, "
                                f"found {value!r}"[:300])
        out[key.upper()] = value
    return out
