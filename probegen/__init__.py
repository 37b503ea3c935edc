"""probegen: a compiler for dimensional measurement on CNC machine tools and CMMs.

From a part model (STEP) and a feature spec (TOML) probegen plans measuring points and
the stylus path and emits a measuring program in a controller dialect (Fanuc Macro B,
DMIS, ...).  See ``docs/architecture.md`` for the pipeline and module boundaries.
"""

__version__ = "0.1.0"
