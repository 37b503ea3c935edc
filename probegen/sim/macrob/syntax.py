"""Syntax error messages for Macro B blocks: where, what was expected, what was found.

A block whose shape does not parse (see :mod:`probegen.sim.macrob.parse`) is parsed
again as written, by a plain parser of the same grammar, to find the first bad token;
the terminals the parser would have accepted there are named in words and grouped
("an operator", "a macro statement").
"""

from __future__ import annotations

import functools

from lark import Lark, Token
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from probegen.errors import readable_list
from probegen.resources import grammar_text


@functools.cache
def _checker() -> Lark:
    """Build the parser used only to locate syntax errors (plain trees, no builders)."""
    return Lark(grammar_text("macrob"), parser="lalr", maybe_placeholders=True)


_READABLE = {
    "N": "a sequence number N",
    "LETTER": "an address letter",
    "HASH": "'#'",
    "STATEMENT": "a macro statement",
    "NUMBER": "a number",
    "INT": "a whole number",
    "SIGN": "a sign",
    "LSQB": "'['",
    "FUNC": "a function",
    "OPERATOR": "an operator",
    "RELOP": "a comparison (EQ NE GT GE LT LE)",
    "LOGIC": "AND, OR or XOR",
    "EQUAL": "'='",
    "COMMA": "','",
    "SLASH": "'/'",
    "RSQB": "']'",
    "GOTO": "GOTO",
    "THEN": "THEN",
    "DO": "DO",
    "DTEXT": "DPRNT text",
    "DFORMAT": "a format of two digits",
    "$END": "end of block",
}
"""Readable names of the grammar's terminals, in the order an error lists them."""

_STATEMENTS = {"IF", "WHILE", "DO", "END", "GOTO", "DPRNT", "POPEN", "PCLOS", "O", "COLON"}
"""What may begin a block besides N, an address letter and '#'."""
_GROUPS = {
    "FUNC": {"FUNC", "ATAN", "POW"},
    "OPERATOR": {"ADDOP", "MULOP"},
}

_HINTS = {
    ")": "')' outside a comment (comments do not nest on Fanuc)",
    "(": "'(' (a comment cannot open here)",
}


def syntax_error(compact: str) -> tuple[int, str]:
    """Return the compact position and message of the first syntax error of a block."""
    try:
        _checker().parse(compact)
    except UnexpectedToken as exc:
        found = _describe(exc.token)
        accepted = set(exc.accepts or exc.expected)
        if exc.token.type == "RELOP" and "RELOP" not in accepted:
            found += " (comparisons belong in IF [...] and WHILE [...])"
        position = len(compact) if exc.token.type == "$END" else exc.token.start_pos or 0
        return position, f"expected {_expected(accepted)}, found {found}"
    except UnexpectedCharacters as exc:
        position = exc.pos_in_stream or 0
        parser = getattr(exc, "interactive_parser", None)
        allowed = set(parser.accepts()) if parser is not None else set(exc.allowed or ())
        char = compact[position]
        found = _HINTS.get(char, repr(char))
        return position, f"expected {_expected(allowed)}, found {found}"
    except UnexpectedInput:  # not raised by the LALR parser; kept for safety
        return len(compact), "unexpected end of block"
    return 0, "cannot read this block"  # the shape failed but the block parsed


def _expected(terminals: set[str]) -> str:
    """Return ``"a, b or c"`` for the terminals the parser accepted."""
    if "SIGN" in terminals and "MULOP" in terminals:  # after an operand
        terminals = terminals - {"SIGN"}
    if "IF" in terminals:  # the start of a block
        terminals = (terminals - _STATEMENTS) | {"STATEMENT"}
    for name, members in _GROUPS.items():
        if terminals & members:
            terminals = (terminals - members) | {name}
    return readable_list(terminals, _READABLE)


def _describe(token: Token) -> str:
    """Describe a token that came where it should not."""
    if token.type == "$END":
        return "end of block"
    if token.type in ("NUMBER", "INT", "DFORMAT"):
        return f"the number {token.value}"
    if token.type in ("N", "O"):
        return f"'{token.value}' (a sequence or program number must begin its block)"
    if token.type in _WHOLE_TOKENS:
        return f"'{token.value}'"
    char = token.value[:1]  # text the lexer fell back on: name its first character
    return _HINTS.get(char, repr(char))


_WHOLE_TOKENS = frozenset(
    "LETTER N O IF WHILE DO END GOTO THEN DPRNT POPEN PCLOS FUNC ATAN POW RELOP LOGIC "
    "ADDOP MULOP".split()
)
