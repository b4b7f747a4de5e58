"""Registry of estimators by kind and name.

Kinds:

* ``"center"``: ``fn(markers) -> CenterResult``, one segment's markers in the reference frame;
* ``"axis"``: ``fn(markers) -> AxisResult``, likewise;
* ``"joint_center"``: ``fn(proximal, distal, **options) -> JointCenterResult``, both segments'
  markers in the world frame.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["KINDS", "get", "methods", "register"]

KINDS = ("center", "axis", "joint_center")
_REGISTRY: dict[str, dict[str, Callable]] = {kind: {} for kind in KINDS}


def _check_kind(kind: str) -> None:
    if kind not in _REGISTRY:
        raise ValueError(f"unknown estimator kind {kind!r}; choose one of {', '.join(KINDS)}")


def register(kind: str, name: str) -> Callable[[Callable], Callable]:
    """Decorator registering ``fn`` as estimator ``name`` of ``kind``."""
    _check_kind(kind)

    def decorate(fn: Callable) -> Callable:
        if name in _REGISTRY[kind]:
            raise ValueError(f"{kind} estimator {name!r} is already registered")
        _REGISTRY[kind][name] = fn
        return fn

    return decorate


def get(kind: str, name: str) -> Callable:
    """The estimator ``name`` of ``kind``; ``ValueError`` listing the known names otherwise."""
    _check_kind(kind)
    try:
        return _REGISTRY[kind][name]
    except KeyError:
        known = ", ".join(_REGISTRY[kind]) or "none"
        raise ValueError(f"unknown {kind} method {name!r}; known: {known}") from None


def methods(kind: str) -> tuple[str, ...]:
    """Names of the registered estimators of ``kind``, in registration order."""
    _check_kind(kind)
    return tuple(_REGISTRY[kind])
