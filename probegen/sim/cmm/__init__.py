"""The DMIS interpreter: DMIS statements run against a ``Cmm`` (moves and probing).

Frames, nominal and actual features, fits, constructions, tolerances and the output
file.  Two machines drive it: the virtual CMM (``probegen.sim.vm.CmmAdapter``) and the
post-processor (``probegen.post``), which runs it once against the nominal part to plan
the machine-tool program and once against the touches a machine tool returned to
evaluate them.  It imports neither ``sim`` nor ``cad``.
"""
