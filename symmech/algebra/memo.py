"""Memoised functions of sympy expressions, emptied with sympy's own cache.

A memo keyed by expressions finds a structurally equal key that is a distinct object (an
expression built anew) only after comparing the two with ``==`` node by node, and that
comparison visits a subtree shared in a DAG once per path to it.  A scene declared again
after ``sympy.core.cache.clear_cache()`` rebuilds every expression as such a twin of the
last run's, so a memo that outlived sympy's cache made the run slower, not faster (the
pendulum on a cart declared as users write it spent most of its time in these
comparisons).  :func:`expression_cache` is :func:`functools.lru_cache` registered in
sympy's list of caches (``sympy.core.cache.CACHE``, where sympy's own ``cacheit``
registers its memos), so that ``clear_cache()`` empties it too.  Memos keyed by atoms or
numbers, whose ``==`` is cheap, are plain ``lru_cache`` and outlive sympy's cache (their
values, a ``srepr`` or an ``evalf``, cost more to recompute than to find).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from typing import Any, TypeVar

from sympy.core import cache as sympy_cache

__all__ = ["expression_cache"]

F = TypeVar("F", bound=Callable[..., Any])


def expression_cache(maxsize: int, typed: bool = True) -> Callable[[F], F]:
    """``functools.lru_cache(maxsize, typed)``, cleared by sympy's ``clear_cache()``."""

    def decorate(fn: F) -> F:
        cached = lru_cache(maxsize=maxsize, typed=typed)(fn)
        sympy_cache.CACHE.append(cached)
        return cached  # type: ignore[return-value]

    return decorate
