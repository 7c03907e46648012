"""Two changes to how numba compiles, for the kernel's sake: each makes it compile in less time,
and neither changes what it computes (the frames are the same, bit for bit).

- **The inliner copies each function once.** Before inlining a function
  (``inline="always"``), numba copies its IR block by block, each block with
  a fresh ``copy.deepcopy`` memo. Every block refers to the function's scope,
  and the scope to every variable, so each block's copy copies all of them
  again: the cost grows with blocks times variables, and the kernel's phases
  are inlined into one another (numba issues 8989 and 9204). Here the blocks
  of one copy share one memo, as one deep copy of the whole function would.
- **LLVM's first round is a light one.** numba runs LLVM's function passes
  on each function as it is compiled (at -O3), then the whole -O3 pipeline
  again on the module it links it into. For the kernel's modules the first
  round runs at -O1 (:data:`FUNCTION_OPT`): the second does the heavy work
  either way. Skipped altogether, the kernel ran 2 to 5% slower; at -O1 it
  runs as fast as at -O3 (``tools/dev/bench.py against``, in turns: mix
  1.005x, halves 1.001x, everything 0.991x).

:func:`install` makes both changes; where numba is not as they expect, it leaves it as it is.
Measured from an empty cache on one idle core (``python -m sandmod.jobs.warmup PART``), the cell
update without its fast loop took 100 s before, 26 s after; with it, 100 s and 37 s.
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


#: The optimization level of the first round, on each function (numba's: 3, as the second's).
FUNCTION_OPT = 1
#: The modules whose functions get the light first round (their names are in every function they compile to).
OURS = "sandmod"


def install() -> None:
    """Make numba's inliner copy each function once, and LLVM's first round on the kernel's code light."""
    _copy_once()
    _optimize_once()
    _inline_marked()


#: The start of the LLVM names of the functions LLVM must inline wherever they are called.
_EVERYWHERE: set[str] = set()


def inline_everywhere(function) -> None:
    """Have LLVM inline ``function`` (a plain Python function, about to be compiled) into every caller."""
    parts = f"{function.__module__}.{function.__qualname__}".split(".")
    _EVERYWHERE.add("_ZN" + "".join(f"{len(p)}{p}" for p in parts) + "B")


def _inline_marked() -> bool:
    try:
        from numba.core.codegen import CPUCodeLibrary

        original = CPUCodeLibrary.add_ir_module
    except (ImportError, AttributeError):
        return False
    if getattr(original, "_sandmod", False):
        return True

    def add_ir_module(self, ir_module):
        for function in ir_module.functions:
            if function.blocks and any(function.name.startswith(p) for p in _EVERYWHERE):
                function.attributes.add("alwaysinline")
        return original(self, ir_module)

    add_ir_module._sandmod = True
    CPUCodeLibrary.add_ir_module = add_ir_module
    optimize = CPUCodeLibrary._optimize_final_module

    def _optimize_final_module(self):
        own = [f.name for f in self._final_module.functions if not f.is_declaration and f.linkage.name == "external"]
        if not any(name.startswith(p) for name in own for p in _EVERYWHERE):
            return optimize(self)
        manager, builder = self._codegen._module_pass_manager(opt=FUNCTION_OPT, cost="cheap")  # its callers inline it, and optimize it there
        manager.run(self._final_module, builder)

    CPUCodeLibrary._optimize_final_module = _optimize_final_module
    return True


def _copy_once() -> bool:
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


def _optimize_once() -> bool:
    """Run numba's function passes at :data:`FUNCTION_OPT` on modules of :data:`OURS`; returns whether it did."""
    try:
        from numba.core.codegen import CPUCodeLibrary

        original = CPUCodeLibrary._optimize_functions
    except (ImportError, AttributeError):
        return False
    if getattr(original, "_sandmod", False):
        return True

    def _optimize_functions(self, ll_module):
        if not any(OURS in function.name for function in ll_module.functions if not function.is_declaration):
            return original(self, ll_module)
        ll_module.data_layout = self._codegen._data_layout
        for function in ll_module.functions:
            manager, builder = self._codegen._function_pass_manager(opt=FUNCTION_OPT)
            manager.run(function, builder)

    _optimize_functions._sandmod = True
    CPUCodeLibrary._optimize_functions = _optimize_functions
    return True
