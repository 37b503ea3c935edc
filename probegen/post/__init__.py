"""The DMIS post-processor: a CMM's DMIS program → a machine-tool probing program.

``probegen post`` (see ``docs/post.md``):

* :mod:`probegen.post.frontend`: the DMIS program → ``ir.Program`` (the planner's IR),
  every move cleared by the collision check, plus the touch list of the feature map
  (both in :mod:`probegen.post.posted`);
* :mod:`probegen.post.featuremap`: ``program.features.json``, what the evaluation needs
  to know of the posted program (the DMIS text as run, every touch with its DMIS
  feature, line and probing line);
* :mod:`probegen.post.evaluate`: a DPRNT log of the posted program → the DMIS
  program's features, tolerances and output file, by running the DMIS program again
  with the logged touches in place of a CMM's.

DMIS semantics (frames, features, fits, tolerances) come from :mod:`probegen.sim.cmm`,
the interpreter the virtual CMM runs too; nothing here imports ``probegen.sim``.
"""
