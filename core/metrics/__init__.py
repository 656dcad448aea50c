"""SPEC metrics (shared SPEC.md): light functions on plain numpy arrays.

``core.metrics.pattern`` measures 2D patterns (ease compliance, seam mismatch,
transfer deviation, residual stretch, shear, flips); ``core.metrics.drape``
measures draped garments. Import the submodule you need.
"""
