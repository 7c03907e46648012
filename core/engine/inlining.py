"""numba's inliner, made linear in the size of what it inlines.

Before inlining a function (``inline="always"``), numba copies its IR block
by block, each block with a fresh ``copy.deepcopy`` memo. Every block refers
to the function's scope, and the scope to every variable, so each block's
copy copies all of them again: the cost grows with blocks times variables,
and the kernel's phases are inlined into one another. Compiling the cell
update spent about three quarters of its time there (numba issues 8989 and
9204).

:func:`install` makes the blocks of one copy share one memo, as a single
deep copy of the whole function would: the same IR, copied once. What the
kernel compiles to is unchanged; only the time to compile it.
If numba's inliner is not as this expects, it is left as it is.
"""

from __future__ import annotations

import copy


class _BlockCopier:
    """Stands in for the :mod:`copy` module inside numba's inliner: copies the blocks of one
    function (one scope) with one memo; everything else as :mod:`copy` does."""

    def __init__(self, ir):
        self._block = ir.Block
        self.sharing(False)

    def sharing(self, on: bool) -> None:
        """Share memos from now on (within one inlining), or not; either way the next block starts a new copy."""
        self._on = on
        self._scope = None
        self._memo: dict = {}

    def deepcopy(self, thing, memo=None):
        if memo is not None or not self._on or not isinstance(thing, self._block):
            return copy.deepcopy(thing, memo)
        if thing.scope is not self._scope or id(thing) in self._memo:
            self._scope, self._memo = thing.scope, {}  # another function, or the same one copied again
        return copy.deepcopy(thing, self._memo)

    def __getattr__(self, name):
        return getattr(copy, name)


def install() -> bool:
    """Make numba's inliner copy each function's blocks with one memo; returns whether it did."""
    try:
        from numba.core import inline_closurecall, ir

        worker = inline_closurecall.InlineWorker
        original = worker.inline_ir
    except (ImportError, AttributeError):
        return False
    if getattr(original, "_sandmod", False) or inline_closurecall.copy is not copy:
        return getattr(original, "_sandmod", False)
    copier = _BlockCopier(ir)

    def inline_ir(self, *args, **kwargs):
        copier.sharing(True)  # each inlining copies its function afresh
        try:
            return original(self, *args, **kwargs)
        finally:
            copier.sharing(False)  # and keeps nothing alive after it

    inline_ir._sandmod = True
    inline_ir.__doc__ = original.__doc__
    worker.inline_ir = inline_ir
    inline_closurecall.copy = copier
    return True
