"""Shared hypothesis strategy: a text with a few characters inserted, deleted or replaced."""

from __future__ import annotations

from hypothesis import strategies as st


def mutate(draw: st.DrawFn, text: str, alphabet: str, *, most: int = 8) -> str:
    """Apply 1 to ``most`` random character edits drawn from ``alphabet`` to ``text``."""
    chars = list(text)
    for _ in range(draw(st.integers(1, most))):
        pos = draw(st.integers(0, len(chars)))
        op = draw(st.sampled_from(["insert", "delete", "replace"]))
        char = draw(st.sampled_from(alphabet))
        if op == "insert":
            chars.insert(pos, char)
        elif pos < len(chars):
            chars[pos : pos + 1] = [] if op == "delete" else [char]
    return "".join(chars)
