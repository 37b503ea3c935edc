"""Macro B for the in-process decisions (``ir_actions``): fits, limits, G10, G68.

Straight-line arithmetic on the values the touches stored (ball centres, work
coordinates, program units):

* circle: the algebraic (Kasa) least-squares circle in XY with centred sums
  (``u = x - mean``): ``[Suu Suv; Suv Svv] [uc vc] = 1/2 [Suq Svq]`` with
  ``q = u^2 + v^2``, ``R^2 = uc^2 + vc^2 + Sq/n``; three points give the circle
  through them.  Diameter ``2 (R +- r)`` (bore +, boss -); roundness the range of the
  centres' distances (max/min without branches: ``[a+b+ABS[a-b]]/2``).
* line: the principal direction ``phi = ATAN[2 Suv]/[Suu - Svv] / 2`` and its angle from
  nominal folded into [-90, 90]; position the mean along the normal axis less ``r``.
* plane: the mean along the normal axis less ``r``.

Then ``NG`` (any limit exceeded), one ``RES`` line (docs/dprnt-format.md) and the
reaction: ``alarm`` (``ERR OUTTOL`` and ``#3000=10``), ``stop`` (``#3006``, the operator
may resume), ``flag`` (the flag variable = NG) or ``continue``.  Work offsets: ``G10 L2
Pn`` (G54-G59) / ``G10 L20 Pn`` (G54.1), the running offset's variable plus the shift.
Tools: incremental ``G91 G10 L11`` (H wear) / ``L13`` (D wear), then ``G90``; a correction
beyond the maximum is ``ERR BIGCORR`` and ``#3000=11``.  Rotation: ``G68 X Y R`` and/or
the angle in a common variable.
"""

from __future__ import annotations

from probegen.dialects.macro_b import MacroB
from probegen.errors import UnsupportedError
from probegen.ir.actions import Align, Check, SetWorkOffset, UpdateTool, result

OUT_OF_TOLERANCE_ALARM = 10
"""``#3000`` number of an out-of-tolerance feature (alarm 3010)."""
BIG_CORRECTION_ALARM = 11
"""``#3000`` number of a tool correction beyond its maximum (alarm 3011)."""
BAD_FIT_ALARM = 12
"""``#3000`` number of touches that fit no circle (collinear points)."""
ANGLE_FORMAT = "26"
"""DPRNT digits of an angle in degrees (2 + 6: 17 nrad; a + b <= 8 on the control)."""
TOOL_LINE = {"radius": 13, "length": 11}
"""G10 L number of each wear offset (memory C: L11 H wear, L13 D wear)."""
SHORT_TEXTS = {"OUT OF TOL": "OUTTOL", "NO CIRCLE FIT": "BADFIT",
               "TOOL CORR TOO BIG": "BIGCORR"}
"""Each alarm text's short form (the ``ERR`` word of its DPRNT line), used when the
feature id and the whole text do not fit the control's (``MacroB.alarm_length``)."""


def alarm_text(d: MacroB, feature: str, text: str) -> str:
    """The message ``<feature> <text>`` of an alarm, within ``d.alarm_length()``.

    The feature id is never cut (the operator must know which feature stopped the
    machine): when the whole message is too long the text takes its short form
    (``SHORT_TEXTS``: ``BORE TOOL CORR TOO BIG`` but ``HOUSINGBORE1 BIGCORR``).

    Raises:
        UnsupportedError: even the short form does not fit (a limit below 20 characters
            with a 12-character id).
    """
    for words in (text, SHORT_TEXTS[text]):
        message = f"{feature} {words}"
        if len(message) <= d.alarm_length():
            return message
    raise UnsupportedError(f"dialect {d.NAME!r}: feature {feature}: expected an alarm message "
                           f"of at most {d.alarm_length()} characters, found "
                           f"{len(message)}: {message!r}; use a shorter feature id")


def lower_action(d: MacroB, node: Check | SetWorkOffset | UpdateTool | Align) -> list[str]:
    """The Macro B lines of one action node."""
    if isinstance(node, Check):
        return _Checker(d, node).lines()
    if isinstance(node, SetWorkOffset):
        return work_offset(d, node)
    if isinstance(node, UpdateTool):
        return update_tool(d, node)
    return align(d, node)


class _Checker:
    """Builds the lines of one ``Check``."""

    def __init__(self, d: MacroB, node: Check) -> None:
        self.d, self.node = d, node
        self.out: list[str] = [f"(CHECK {node.feature} {node.fit.upper()} "
                               f"{len(node.points)} POINTS)"]

    def t(self, name: str) -> str:
        """A scratch value shared by every check."""
        return self.d.var(f"_{name}")

    def r(self, key: str) -> str:
        """A result of this feature."""
        return self.d.var(result(self.node.feature, key))

    def p(self, k: int, axis: int) -> str:
        name = self.node.points[k][axis]
        assert name is not None
        return self.d.var(name)

    def emit(self, *lines: str) -> None:
        self.out += lines

    def lines(self) -> list[str]:
        n = self.node
        self.calibrate()
        if n.fit == "circle":
            self.circle()
        else:
            self.planar()
        self.limits()
        self.report()
        self.react()
        return self.out

    def calibrate(self) -> None:
        """Move each stored ball centre by its calibration correction (none without a
        calibration, or where it prints as 0)."""
        lines = []
        for k, vector in enumerate(self.node.corrections):
            for a in range(3):
                name = self.node.points[k][a]
                step = minus(self.d, -vector[a])
                if name is not None and step:
                    lines.append(f"{self.d.var(name)}={self.d.var(name)}{step}")
        if lines:
            self.emit("(PROBE CALIBRATION: EFFECTIVE RADIUS BY DIRECTION)", *lines)

    def means(self, axes: tuple[int, ...]) -> None:
        count = len(self.node.points)
        for a in axes:
            m = self.t(f"M{a}")
            self.emit(f"{m}=0")
            self.emit(*(f"{m}={m}+{self.p(k, a)}" for k in range(count)))
            self.emit(f"{m}={m}/{count}")

    def sums(self) -> None:
        """Centred second moments (and third for a circle) in XY."""
        u, v, q = self.t("U"), self.t("V"), self.t("Q")
        names = ("SUU", "SVV", "SUV", "SUQ", "SVQ", "SQ")
        s = {k: self.t(k) for k in names}
        self.emit(*(f"{s[k]}=0" for k in names))
        mx, my = self.t("M0"), self.t("M1")
        for k in range(len(self.node.points)):
            self.emit(f"{u}={self.p(k, 0)}-{mx}", f"{v}={self.p(k, 1)}-{my}",
                      f"{q}={u}*{u}+{v}*{v}", f"{s['SUU']}={s['SUU']}+{u}*{u}",
                      f"{s['SVV']}={s['SVV']}+{v}*{v}", f"{s['SUV']}={s['SUV']}+{u}*{v}")
            if self.node.fit == "circle":
                self.emit(f"{s['SUQ']}={s['SUQ']}+{u}*{q}", f"{s['SVQ']}={s['SVQ']}+{v}*{q}",
                          f"{s['SQ']}={s['SQ']}+{q}")

    def circle(self) -> None:
        d, n = self.d, self.node
        self.means((0, 1))
        self.sums()
        suu, svv, suv = self.t("SUU"), self.t("SVV"), self.t("SUV")
        suq, svq, sq = self.t("SUQ"), self.t("SVQ"), self.t("SQ")
        det, uc, vc = self.t("DET"), self.t("U"), self.t("V")
        label = d.next_label()
        self.emit(f"{det}=2*[{suu}*{svv}-{suv}*{suv}]",
                  f"IF[ABS[{det}]GT0]GOTO{label}",
                  f"DPRNT[ERR*BADFIT*{n.feature}*1]",
                  f"#3000={BAD_FIT_ALARM}({alarm_text(d, n.feature, 'NO CIRCLE FIT')})",
                  f"N{label}",
                  f"{uc}=[{suq}*{svv}-{svq}*{suv}]/{det}",
                  f"{vc}=[{svq}*{suu}-{suq}*{suv}]/{det}")
        x, y, dia = self.r("X"), self.r("Y"), self.r("D")
        sign = "+" if n.inner else "-"
        count = len(n.points)
        self.emit(f"{x}={self.t('M0')}+{uc}", f"{y}={self.t('M1')}+{vc}",
                  f"{dia}=2*[SQRT[{uc}*{uc}+{vc}*{vc}+{sq}/{count}]{sign}"
                  f"{d.length(n.ball_radius)}]")
        self.form(x, y)
        side = "-" if n.inner else ""
        self.emit(f"{self.r('E')}={side}[{dia}-{d.length(n.diameter)}]/2")

    def form(self, x: str, y: str) -> None:
        lo, hi, ri = self.t("RMIN"), self.t("RMAX"), self.t("Q")
        for k in range(len(self.node.points)):
            self.emit(f"{ri}=SQRT[[{self.p(k, 0)}-{x}]*[{self.p(k, 0)}-{x}]"
                      f"+[{self.p(k, 1)}-{y}]*[{self.p(k, 1)}-{y}]]")
            if k == 0:
                self.emit(f"{lo}={ri}", f"{hi}={ri}")
            else:
                self.emit(f"{lo}=[{lo}+{ri}-ABS[{lo}-{ri}]]/2",
                          f"{hi}=[{hi}+{ri}+ABS[{hi}-{ri}]]/2")
        self.emit(f"{self.r('F')}={hi}-{lo}")

    def planar(self) -> None:
        d, n = self.d, self.node
        axis = max(range(3), key=lambda i: abs(n.normal[i]))
        s = 1.0 if n.normal[axis] > 0 else -1.0
        self.means((0, 1) if n.fit == "line" else (axis,))
        pos = self.r("P")
        r = d.length(n.ball_radius)
        self.emit(f"{pos}={self.t(f'M{axis}')}{'-' if s > 0 else '+'}{r}")
        self.emit(f"{self.r('E')}={'' if s > 0 else '-'}[{pos}{minus(d, n.nominal[axis])}]")
        if n.fit == "line":
            self.sums()
            a, phi = self.r("A"), self.t("PHI")
            self.emit(f"{phi}=ATAN[2*{self.t('SUV')}]/[{self.t('SUU')}-{self.t('SVV')}]",
                      f"{a}={phi}/2{minus(d, n.direction, 6)}",
                      f"{a}={a}-180*ROUND[{a}/180]")

    def deviation(self, key: str) -> str:
        """The expression each limit compares (a position's zone is computed first)."""
        d, n = self.d, self.node
        if key == "diameter":
            return f"[{self.r('D')}-{d.length(n.diameter)}]"
        if key == "form":
            return self.r("F")
        if key == "angle":
            return f"ABS[{self.r('A')}]"
        if n.fit != "circle":
            return self.r("E")
        u, v, q = self.t("U"), self.t("V"), self.t("Q")
        self.emit(f"{u}={self.r('X')}{minus(d, n.nominal[0])}",
                  f"{v}={self.r('Y')}{minus(d, n.nominal[1])}",
                  f"{q}=2*SQRT[{u}*{u}+{v}*{v}]")
        return q

    def limits(self) -> None:
        ng = self.r("NG")
        self.emit(f"{ng}=0")
        for lim in self.node.limits:
            value = self.deviation(lim.key)
            scale = self.d.num if lim.key == "angle" else self.d.length
            if lim.key in ("diameter",) or (lim.key == "position" and self.node.fit != "circle"):
                self.emit(f"IF[{value}LT{scale(lim.lower)}]THEN{ng}=1")
            self.emit(f"IF[{value}GT{scale(lim.upper)}]THEN{ng}=1")

    def report(self) -> None:
        fmt = self.d.DPRNT_FORMAT[self.d.units]
        n = self.node
        keys = ("X", "Y", "D", "F") if n.fit == "circle" else ("P",)
        fields = [f"{k}{self.r(k)}[{fmt}]" for k in keys]
        if n.fit == "line":
            fields.append(f"A{self.r('A')}[{ANGLE_FORMAT}]")
        fields.append(f"NG{self.r('NG')}[10]")
        self.emit(f"DPRNT[RES*{n.feature}*{'*'.join(fields)}]")

    def react(self) -> None:
        n, ng = self.node, self.r("NG")
        if n.on_fail == "continue":
            return
        if n.on_fail == "flag":
            self.emit(f"#{n.flag}={ng}")
            return
        label = self.d.next_label()
        stop = (f"#3000={OUT_OF_TOLERANCE_ALARM}" if n.on_fail == "alarm" else "#3006=1")
        self.emit(f"IF[{ng}EQ0]GOTO{label}", f"DPRNT[ERR*OUTTOL*{n.feature}*1]",
                  f"{stop}({alarm_text(self.d, n.feature, 'OUT OF TOL')})", f"N{label}")


def minus(d: MacroB, value: float, decimals: int | None = None) -> str:
    """Text that subtracts ``value`` (a length in mm, or a plain number with
    ``decimals``): ``-v``, ``+|v|`` for a negative one, nothing when it prints as 0."""
    text = d.length(abs(value)) if decimals is None else d.num(abs(value), decimals)
    if float(text) == 0.0:
        return ""
    return f"{'-' if value > 0 else '+'}{text}"


def offset_words(name: str) -> tuple[str, int]:
    """``G10 L2 Pn`` / ``G10 L20 Pn`` words and the first variable (X) of work offset
    ``name`` (``G54``-``G59``, ``G54.1 Pn``, Haas ``G154 Pn``: the same numbers)."""
    if name.startswith(("G54.1", "G154")):
        p = int(name.split("P")[1])
        first = 7001 + 20 * (p - 1) if p <= 48 else 14001 + 20 * (p - 1)
        return f"L20 P{p}", first
    k = int(name[1:]) - 54
    return f"L2 P{k + 1}", 5221 + 20 * k


def work_offset(d: MacroB, node: SetWorkOffset) -> list[str]:
    """``G10`` writing the running offset plus each measured shift into ``node.offset``,
    one block per axis (the others keep their values)."""
    words, _ = offset_words(node.offset)
    _, running = offset_words(node.running)
    head = (f"(SET {node.offset} {''.join('XYZ'[i] for i, _, _ in node.shifts)} FROM "
            f"{node.feature})")
    return [head, *(f"G90 G10 {words} {'XYZ'[i]}[#{running + i}+{d.var(name)}"
                    f"{minus(d, nominal)}]" for i, name, nominal in node.shifts)]


def update_tool(d: MacroB, node: UpdateTool) -> list[str]:
    """The wear correction with its dead band and maximum."""
    c = d.var(result(node.feature, "C"))
    skip, ok = d.next_label(), d.next_label()
    fmt = d.DPRNT_FORMAT[d.units]
    return [
        f"(UPDATE TOOL {node.tool} {node.offset.upper()} WEAR FROM {node.feature})",
        f"{c}=-{d.num(node.feedback, 4)}*{d.var(node.excess)}",
        f"IF[ABS[{c}]LT{d.length(node.dead_band)}]THEN{c}=0",
        f"IF[ABS[{c}]LE{d.length(node.max_correction)}]GOTO{ok}",
        f"DPRNT[ERR*BIGCORR*{node.feature}*{node.tool}]",
        f"#3000={BIG_CORRECTION_ALARM}({alarm_text(d, node.feature, 'TOOL CORR TOO BIG')})",
        f"N{ok}",
        f"DPRNT[RES*{node.feature}*T{node.tool}*C{c}[{fmt}]]",
        f"IF[{c}EQ0]GOTO{skip}",
        f"G91 G10 L{TOOL_LINE[node.offset]} P{node.tool} R{_wear(d, node, c)}",
        "G90",
        f"N{skip}",
    ]


def _wear(d: MacroB, node: UpdateTool, c: str) -> str:
    """The G10 R value: the correction, doubled where the D offset is a diameter."""
    k = d.RADIUS_WEAR_FACTOR if node.offset == "radius" else 1.0
    return c if k == 1.0 else f"[{d.num(k, 1)}*{c}]"


def align(d: MacroB, node: Align) -> list[str]:
    """Store the angle and/or rotate with G68 about the centre."""
    a = d.var(node.angle)
    out = [f"(ALIGN FROM {node.feature})"]
    if node.variable is not None:
        out.append(f"#{node.variable}={a}")
    if node.mode == "g68":
        x, y = (d.length(v) for v in node.centre)
        out.append(f"G17 G68 X{x} Y{y} R{a}")
    return out
