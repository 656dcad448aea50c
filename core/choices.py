"""The names a user picks from on the command line and in a design: plain data, no numpy.

The CLI's argument parsers read their choices from here, so ``ease --help`` starts without loading
the pipeline's packages; the stages that own the names re-export them.
"""

#: The solver configurations a design may name (``"solver"``) and a user may choose (``ease pattern
#: --config``, the add-on's Solver): the presets of :meth:`core.pattern.config.SolverConfig.named`.
SOLVER_CONFIGS = ("improved", "paper", "stretch", "fitted", "lengths")

#: The bodies a transfer's flattening and factorisation may be made on (a design's ``"transfer_solver"``,
#: ``ease transfer --transfer-solver``): :data:`core.pattern.config.TRANSFER_SOLVERS`. ``"cup"``: the
#: target's on a bigger cup, its darts re-derived there; the reference's elsewhere (docs/darts.md).
TRANSFER_SOLVERS = ("reference", "target", "cup")

#: The pose presets every body model offers (:meth:`core.body.model.BodyModel.pose_params`).
POSE_PRESETS = ("A", "T", "P1", "P2", "P3")
#: The preset every body model is built in: the same instance as pose None.
REFERENCE_POSE = "A"
