"""Shared numerics, each with one home: rigid poses, the fminsearch simplex, small matrices,
the concentric-sphere and two-segment least-squares systems, a cluster's distance geometry, the
rank threshold, values shared within one checked call, and the compiled kernels' decorator.

Imported by the estimators; imports nothing from the rest of jointbench but
:mod:`jointbench.owncode` (which code is the package's own, for the kernels' cache digest).
"""
