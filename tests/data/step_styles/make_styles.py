"""Make the STEP files with colour and style records, good and malformed (issue 17, item 7).

Each file is ``samples/sphere25/sphere25.step`` with one presentation chain added before
``ENDSEC;`` (a colour, its fill-area style, a surface side style with a rendering record,
the usage, the styled item on the solid and the presentation representation), as CAD
systems write it.  ``styled.step`` has it well formed; each other file sets one field
unset (``$``) or points one reference nowhere, as Inventor and NX exports do:

=====================  =============================================================
file                   what is wrong
=====================  =============================================================
unset_side.step        ``SURFACE_STYLE_USAGE($, ...)``: the side is unset (#906)
unset_colour.step      ``FILL_AREA_STYLE_COLOUR('steel', $)``: no colour (#902)
unset_red.step         ``COLOUR_RGB('steel', $, ...)``: the red component unset (#901)
unset_rendering.step   ``SURFACE_STYLE_RENDERING_WITH_PROPERTIES($, ...)`` (#909), the
                       Prusa MINI heatsink's case (Inventor 2019)
dangling_colour.step   ``FILL_AREA_STYLE_COLOUR('steel', #9999)``: no entity #9999 (#902)
=====================  =============================================================

Run from the repository root::

    .venv/bin/python tests/data/step_styles/make_styles.py

tests/test_step_styles.py checks that the committed files are what this script writes.
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
SOURCE = ROOT / "samples/sphere25/sphere25.step"
HERE = Path(__file__).resolve().parent
END = "ENDSEC;\nEND-ISO-10303-21;"

CHAIN = """#901 = COLOUR_RGB('steel',{red},0.75,0.75);
#902 = FILL_AREA_STYLE_COLOUR('steel',{colour});
#903 = FILL_AREA_STYLE('steel',(#902));
#904 = SURFACE_STYLE_FILL_AREA(#903);
#905 = SURFACE_SIDE_STYLE('steel',(#904,#909));
#906 = SURFACE_STYLE_USAGE({side},#905);
#907 = PRESENTATION_STYLE_ASSIGNMENT((#906));
#908 = STYLED_ITEM('color',(#907),#15);
#909 = SURFACE_STYLE_RENDERING_WITH_PROPERTIES({method},#901,(#910));
#910 = SURFACE_STYLE_TRANSPARENT(0.);
#911 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#908),#228);
"""
GOOD = {"red": "0.75", "colour": "#901", "side": ".BOTH.", "method": ".NORMAL_SHADING."}
VARIANTS = {
    "styled": {},
    "unset_side": {"side": "$"},
    "unset_colour": {"colour": "$"},
    "unset_red": {"red": "$"},
    "unset_rendering": {"method": "$"},
    "dangling_colour": {"colour": "#9999"},
}
"""File stem -> the fields changed from :data:`GOOD`."""


def styled_text(change: dict[str, str], source: str | None = None) -> str:
    """The sample's STEP text with the chain, ``change`` applied to its fields."""
    text = SOURCE.read_text(encoding="ascii") if source is None else source
    assert text.count(END) == 1, "the sample's end changed"
    return text.replace(END, CHAIN.format(**{**GOOD, **change}) + END)


def main() -> None:
    for stem, change in VARIANTS.items():
        (HERE / f"{stem}.step").write_text(styled_text(change), encoding="ascii")


if __name__ == "__main__":
    main()
