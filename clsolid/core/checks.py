"""Parameter checks shared by every method's parameters: each raises an InputError that
names the parameter, its value and what it may be."""

from __future__ import annotations

import numbers

from ..errors import InputError


def int_in(name: str, value, lo: int, hi: int | None = None) -> int:
    """*value* as an int, if it is an integer (not a bool) in ``[lo, hi]`` (no upper bound without *hi*)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputError(f"{name}={value!r} must be an integer")
    if value < lo or (hi is not None and value > hi):
        rng = f">= {lo}" if hi is None else f"in [{lo}, {hi}]"
        raise InputError(f"{name}={value!r} must be {rng}")
    return int(value)


def one_of(name: str, value, options: tuple) -> str:
    """*value*, if it is one of *options*."""
    if value not in options:
        raise InputError(f"{name}={value!r} must be one of {', '.join(map(repr, options))}")
    return value
