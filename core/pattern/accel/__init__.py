"""The pattern solver's compiled steps, behind one seam: Warp CPU kernels that give numpy's bits.

The solver's method is written in numpy, scipy and qdldl (:mod:`core.pattern.optimizer.steps`,
:mod:`core.pattern.optimizer.feedback`, :mod:`core.pattern.optimizer.factor`); this package holds the same steps
compiled, and nothing else:

- :mod:`.compiled` launches :mod:`.kernels` (the per-triangle steps: local step, targets' feedback,
  right-hand side terms, collapse guard, flip check, grain votes) and is where the choice is made;
- :mod:`.ldl` with :mod:`.ldl_kernels`: QDLDL's loops, refactorising only the rows of L a change
  reaches and solving both pattern coordinates in one pass;
- :mod:`.products` with :mod:`.sparse_kernels`: the iteration's Jacobians and right-hand side
  products in one pass each.

The contract (docs/architecture.md, "Two code paths, one result"): on one machine and build, the
same bits as the numpy path; a pattern is the same bytes either way. Where the kernels do not apply
(a case they do not cover, a NaN where Warp's min / max would part from numpy's) the step runs its
numpy code; where Warp is missing, fails to compile or refuses a launch, numpy runs for the rest of
the process after one warning.

:func:`choose` makes the choice: ``EASE_SOLVER_KERNELS`` (``warp``, the default, or ``numpy``),
then loading the kernels (compiled on a machine's first run, then cached). A
:class:`core.pattern.optimizer.solver.PatternSolver` calls it once when it is built and records the answer
(``solver.kernels``). Measured on the long-sleeve shirt (transfer to four sizes, CPU time, this
project's 2-core x86-64 VM; benchmarks/results/pattern_kernels_history.md): the kernels take
~110 ms a transfer where numpy takes ~180-220 ms; each part pays (numpy for the per-triangle
steps ~+60 %, for the LDL ~+25 %, for the products ~+20 %).
"""

from __future__ import annotations

from typing import Optional

from ...progress import Progress


def choose(progress: Optional[Progress] = None) -> bool:
    """Whether the solver's steps run compiled: asked for (``EASE_SOLVER_KERNELS``, or
    :func:`.compiled.use` in tests) and loaded; loads (compiles on a machine's first run) where
    asked for. With ``EASE_SOLVER_KERNELS=numpy`` Warp is not imported."""
    from . import compiled

    # wanted() first: a numpy choice never imports Warp; not enabled(), which would give the choice of
    # a solver whose call builds this one (compiled.chosen)
    return compiled.wanted() and compiled.load(progress)
