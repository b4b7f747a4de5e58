"""Shared numerics, each with one home: rigid poses, the fminsearch simplex, the rank threshold.

Imported by the estimators; imports nothing from the rest of jointbench but
:mod:`jointbench.geometry`.
"""
