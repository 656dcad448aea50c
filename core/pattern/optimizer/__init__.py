"""The local-global ease optimizer: :class:`.solver.PatternSolver` and its parts.

Public entry points are :mod:`core.pattern.solve`'s; this package is the method behind them:
the flattening (:mod:`.panels`, :mod:`.init`, :mod:`.mirror_flat`), the targets
(:mod:`.targets`, :mod:`.feedback`), the seams and darts (:mod:`.seams`, :mod:`.dart_gaps`), an
iteration's steps (:mod:`.steps`, :mod:`.guard`, :mod:`.factor`), a solve's state and start
(:mod:`.state`, :mod:`.start`). The same steps compiled are :mod:`core.pattern.accel`'s.
"""
