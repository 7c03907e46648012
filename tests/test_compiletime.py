"""The changes to how numba compiles (sandmod.engine.compiletime): in place, and copies still copies.

That they change nothing the kernel computes is test_golden's to show (its frames, bit for bit).
"""

import copy

from numba import njit
from numba.core import inline_closurecall, ir
from numba.core.codegen import CPUCodeLibrary
from numba.core.compiler import run_frontend

import sandmod.engine.jit  # noqa: F401  (installs them)
from sandmod.engine import compiletime


def _branchy(a, b):
    total = 0
    for k in range(a):
        if k % 3 == 0:
            total += b
        elif k % 3 == 1:
            total -= k
        else:
            total *= 2
    return total


def test_both_changes_are_in_place_once():
    inline_ir, optimize = inline_closurecall.InlineWorker.inline_ir, CPUCodeLibrary._optimize_functions
    assert inline_ir._sandmod and optimize._sandmod
    assert isinstance(inline_closurecall.copy, compiletime._BlockCopier)
    compiletime.install()  # again: nothing wrapped twice
    assert inline_closurecall.InlineWorker.inline_ir is inline_ir and CPUCodeLibrary._optimize_functions is optimize


def test_the_blocks_of_one_copy_share_one_new_scope():
    function = run_frontend(_branchy)
    assert len(function.blocks) > 3
    copier = compiletime._BlockCopier(ir)
    copier.sharing(True)
    copies = [copier.deepcopy(block) for block in function.blocks.values()]
    scopes = {id(block.scope) for block in copies}
    assert len(scopes) == 1 and id(function.blocks[0].scope) not in scopes
    again = [copier.deepcopy(block) for block in function.blocks.values()]  # the same blocks again: another copy
    assert again[0] is not copies[0] and again[0].scope is not copies[0].scope
    copier.sharing(False)  # outside an inlining, as copy.deepcopy: a scope per block
    apart = [copier.deepcopy(block) for block in function.blocks.values()]
    assert len({id(block.scope) for block in apart}) == len(apart)
    assert str(apart[0].body[0]) == str(function.blocks[0].body[0]) == str(copies[0].body[0])


def test_inlined_functions_still_compute_the_same():
    inner = njit(inline="always")(_branchy)

    @njit
    def outer(a, b):
        return inner(a, b) + inner(b, a)

    for a, b in [(0, 0), (7, 3), (20, -5)]:
        assert outer(a, b) == _branchy(a, b) + _branchy(b, a)


def test_only_our_code_gets_the_light_first_round(monkeypatch):
    from numba.core.codegen import JITCPUCodegen

    levels = []
    original = JITCPUCodegen._function_pass_manager

    def recorded(self, **kwargs):
        levels.append(kwargs.get("opt", "numba's"))
        return original(self, **kwargs)

    monkeypatch.setattr(JITCPUCodegen, "_function_pass_manager", recorded)
    assert njit(lambda a: a * 2 + 1)(20) == 41  # this module's: numba's own level
    assert levels and set(levels) == {"numba's"}
    levels.clear()
    monkeypatch.setattr(compiletime, "OURS", "test_compiletime")  # as if this module were the kernel's
    assert njit(lambda a: a * 3 + 1)(20) == 61
    assert levels and set(levels) == {compiletime.FUNCTION_OPT}
