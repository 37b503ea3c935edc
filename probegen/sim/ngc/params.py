"""The parameters of the virtual LinuxCNC control (LinuxCNC 2.9, "Parameters").

| parameters | meaning |
|---|---|
| ``#1``-``#30`` | subroutine locals: a call's arguments, the rest 0; restored on return |
| ``#31``-``#5000`` | global, 0 until written |
| ``#5061``-``#5070`` ... ``#5420``-``#5428`` | system parameters (:meth:`NgcMotion.read_param`) |
| other numbers up to ``#5602`` | kept as written, 0 until then (``#5599`` is 1) |
| ``#<name>`` | local to the subroutine that writes it; gone when it returns |
| ``#<_name>`` | global; predefined ones (``#<_x>``, ``#<_metric>``, ``#<_value>`` ...) read only |

Reading a named parameter that does not exist is the interpreter's error ``Named
parameter #<name> not defined``; a number outside 1-5602 is ``Parameter number out of
range``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from probegen.sim.ngc.expr import error

MAX_PARAMETER = 5602
LOCALS = 30


class System(Protocol):
    """The control's side: system numbered parameters and predefined named ones."""

    def read_param(self, number: int) -> float | None:
        """A system parameter's value, or None when ``number`` is a plain parameter."""
        ...

    def write_param(self, number: int, value: float) -> bool:
        """Write a system parameter; False when ``number`` is a plain one."""
        ...


class Parameters:
    """Numbered and named parameters, with a local level per subroutine call."""

    def __init__(self, system: System, predefined: Callable[[str], float | None]) -> None:
        self.system = system
        self.predefined = predefined
        self.locals: list[float] = [0.0] * (LOCALS + 1)
        self.named: dict[str, float] = {}
        self.globals: dict[str, float] = {}
        self.numbered: dict[int, float] = {5599: 1.0}
        self.levels: list[tuple[list[float], dict[str, float]]] = []

    # -- numbered -----------------------------------------------------------------------
    def read(self, index: int) -> float:
        if 1 <= index <= LOCALS:
            return self.locals[index]
        if not 1 <= index <= MAX_PARAMETER:
            raise error(f"Parameter number out of range (#{index})")
        value = self.system.read_param(index)
        return self.numbered.get(index, 0.0) if value is None else value

    def write(self, index: int, value: float) -> None:
        if 1 <= index <= LOCALS:
            self.locals[index] = value
        elif not 1 <= index <= MAX_PARAMETER:
            raise error(f"Parameter number out of range (#{index})")
        elif not self.system.write_param(index, value):
            self.numbered[index] = value

    # -- named --------------------------------------------------------------------------
    def lookup_named(self, name: str) -> float | None:
        if name.startswith("_"):
            value = self.predefined(name)
            return self.globals.get(name) if value is None else value
        return self.named.get(name)

    def read_named(self, name: str) -> float:
        value = self.lookup_named(name)
        if value is None:
            raise error(f"Named parameter #<{name}> not defined")
        return value

    def write_named(self, name: str, value: float) -> None:
        if name.startswith("_"):
            if self.predefined(name) is not None:
                raise error(f"Cannot assign to read-only parameter #<{name}>")
            self.globals[name] = value
        else:
            self.named[name] = value

    # -- calls --------------------------------------------------------------------------
    @property
    def depth(self) -> int:
        """How many calls are in progress."""
        return len(self.levels)

    def push(self, args: list[float]) -> None:
        """A call: ``args`` into #1-#n, the other locals 0, no local names."""
        self.levels.append((self.locals, self.named))
        self.locals = [0.0, *args, *([0.0] * (LOCALS - len(args)))]
        self.named = {}

    def pop(self) -> None:
        """A return: the caller's locals again."""
        self.locals, self.named = self.levels.pop()

    def snapshot(self) -> dict[int, float]:
        """The numbered parameters written (not 0), and the work offsets not 0."""
        out = {k: v for k, v in self.numbered.items() if v and k != 5599}
        for number in range(5211, 5391):
            value = self.system.read_param(number)
            if value:
                out[number] = value
        return dict(sorted(out.items()))
