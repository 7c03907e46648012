"""The changes to how numba compiles (sandmod.engine.compiletime): in place, copies still copies,
and the functions marked to be inlined are inlined by LLVM, with no machine code of their own.

That they change nothing the kernel computes is test_golden's to show (its frames, bit for bit).
"""

import os
import subprocess
import sys

import numpy as np
import pytest
from numba import njit
from numba.core import inline_closurecall, ir
from numba.core.codegen import CPUCodeLibrary
from numba.core.compiler import run_frontend

import sandmod.engine.jit  # noqa: F401  (installs them)
from sandmod.engine import compiletime, jit
from sandmod.jobs import warmup


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


def _levels(monkeypatch, maker):
    """The optimization levels that numba's ``maker`` of pass managers is asked for, from now on."""
    from numba.core.codegen import JITCPUCodegen

    levels = []
    original = getattr(JITCPUCodegen, maker)

    def recorded(self, **kwargs):
        levels.append(kwargs.get("opt", "numba's"))
        return original(self, **kwargs)

    monkeypatch.setattr(JITCPUCodegen, maker, recorded)
    return levels


def test_only_our_code_gets_the_light_first_round(monkeypatch):
    levels = _levels(monkeypatch, "_function_pass_manager")
    assert njit(lambda a: a * 2 + 1)(20) == 41  # this module's: numba's own level
    assert levels and set(levels) == {"numba's"}
    levels.clear()
    monkeypatch.setattr(compiletime, "OURS", "test_compiletime")  # as if this module were the kernel's
    assert njit(lambda a: a * 3 + 1)(20) == 61
    assert levels and set(levels) == {compiletime.FUNCTION_OPT}


def _halved(a):
    return a // 2 - 1


def test_only_the_quick_step_is_optimized_lightly(monkeypatch):
    levels = _levels(monkeypatch, "_module_pass_manager")
    assert njit(lambda a: a * 2 + 1)(20) == 41
    assert levels and compiletime.QUICK_OPT not in levels  # numba's -O3, twice
    levels.clear()
    assert jit.quick(_halved, cache=False)(20) == 9
    assert levels == [compiletime.QUICK_OPT]


def test_the_update_without_its_fast_loop_never_compiles_it(monkeypatch):
    # step_region is handed None, not False, for the version without: numba drops the branch before typing it.
    from numba import types

    from sandmod.engine import kernel

    typed = []
    original = kernel._fast_cells.compile
    monkeypatch.setattr(kernel._fast_cells, "compile", lambda signature: typed.append(signature) or original(signature))
    region = warmup.phase_signatures(warmup._tiny_world())[kernel.step_region_full]
    for fast, compiles in ((types.none, False), (types.boolean, True)):
        typed.clear()
        njit(cache=False)(kernel.step_region.py_func).compile((*region, fast))
        assert bool(typed) is compiles, fast


def _leaf(a, i):
    return a[i] * 3 + 1


def _middle(a, i):
    return _leaf_inlined(a, i) - _leaf_inlined(a, i + 1)


_leaf_inlined = jit.inlined(_leaf, cache=False)
_middle_inlined = jit.inlined(_middle, cache=False)


@njit(_nrt=False)
def _caller(a):
    total = 0
    for i in range(len(a) - 1):
        total += _middle_inlined(a, i) * i
    return total


def _library(dispatcher):
    return dispatcher.overloads[dispatcher.signatures[0]].library


def _defined(module):
    return [function.name for function in module.functions if not function.is_declaration]


def test_llvm_inlining_is_in_place_once():
    add, optimize = CPUCodeLibrary.add_ir_module, CPUCodeLibrary._optimize_final_module
    assert compiletime.LLVM_INLINES and add._sandmod and optimize._sandmod
    compiletime.install()  # again: nothing wrapped twice
    assert CPUCodeLibrary.add_ir_module is add and CPUCodeLibrary._optimize_final_module is optimize


def test_a_marked_function_is_inlined_by_llvm_into_its_callers_and_has_no_machine_code():
    a = np.arange(12, dtype=np.int64) ** 2
    assert _caller(a) == sum((_leaf(a, i) - _leaf(a, i + 1)) * i for i in range(len(a) - 1))
    caller = _library(_caller)._final_module
    assert any("_caller" in name for name in _defined(caller))  # a caller not marked: numba's own pipeline and machine code
    assert not any(name.startswith(tuple(compiletime._EVERYWHERE)) for name in _defined(caller))  # inlined, none left
    assert "call" not in "".join(line for line in str(caller).splitlines() if "_leaf" in line or "_middle" in line)
    for marked in (_middle_inlined, _leaf_inlined):
        library = _library(marked)
        assert _defined(library._final_module) == []  # no machine code of its own, not even a wrapper
        shared = [f for f in library._get_module_for_linking().functions if f.name.startswith(tuple(compiletime._EVERYWHERE))]
        assert shared and all("alwaysinline" in str(f).split("{")[0] for f in shared if not f.is_declaration)
    with pytest.raises(TypeError, match="inlined into compiled callers"):
        _middle_inlined(a, 1)


def test_where_numba_is_not_as_expected_numba_inlines_instead(monkeypatch):
    monkeypatch.delattr(CPUCodeLibrary, "_get_module_for_linking")
    assert not compiletime._inline_marked()
    monkeypatch.undo()
    monkeypatch.setattr(CPUCodeLibrary, "_get_module_for_linking", lambda self: self._final_module)  # hands out another module
    assert not compiletime._inline_marked()
    monkeypatch.undo()
    monkeypatch.setattr(compiletime, "LLVM_INLINES", False)
    copied = jit.inlined(_leaf, cache=False)
    assert copied.targetoptions.get("inline") == "always" and "_nrt" not in copied.targetoptions


def test_the_warmup_compiles_each_phase_for_the_types_the_kernel_calls_it_with():
    warmup.compile_new_kernels()  # as the test session's start does, if it has not
    for function, signature in warmup.phase_signatures(warmup._tiny_world()).items():
        compiled = [key[0] for key in function._cache._cache_file._load_index()]
        assert compiled == [tuple(signature)], function.py_func.__qualname__  # one version: the warmup's is the kernel's


_CALLS_BY_NAME = '''
import numpy as np
from sandmod.engine.jit import called, compiled, inlined

@called
def leaf(a, i):
    total = 0
    for k in range(i, len(a)):
        total += a[k] * k
    return total

@inlined
def middle(a, i):
    return leaf(a, i) + 1

@compiled
def caller(a, i):
    return leaf(a, i) - middle(a, i + 1)

@compiled
def later(a, i):
    return middle(a, i)

def main(first):
    a = np.arange(10, dtype=np.int64)
    if not first:  # compiled now, before anything loads leaf: middle, from the cache, loads it
        print(later(a, 1))
    print(caller(a, 1))
    print(sum(caller.stats.cache_hits.values()), sum(leaf.stats.cache_hits.values()), sum(leaf.stats.cache_misses.values()))
    if first:  # compiled here: the caller's module declares leaf, defines none of it
        module = caller.overloads[caller.signatures[0]].library._final_module
        print(sorted({bool(f.is_declaration) for f in module.functions if "4leaf" in f.name}))
'''


def test_a_function_called_by_name_is_compiled_once_and_a_cached_caller_loads_it_first(tmp_path):
    """A caller links in nothing of a function marked `called`: its module declares it, the loader finds
    its machine code; from the cache, the caller has what it calls loaded before its own code, and so
    does an inlined function that calls it, for a caller compiled later."""
    (tmp_path / "bynamed.py").write_text(_CALLS_BY_NAME)
    env = os.environ | {"NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}
    squares = sum(k * k for k in range(1, 10))
    expected = squares - (squares - 1 + 1)

    def run(first):
        done = subprocess.run([sys.executable, "-c", f"import bynamed; bynamed.main({first})"], env=env, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        return done.stdout.splitlines()

    first = run(True)
    assert first == [str(expected), "0 0 1", "[True]"]  # compiled, leaf once; declared in the caller, not defined there
    again = run(False)
    assert again == [str(squares + 1), str(expected), "1 1 0"]  # leaf from the cache, loaded for middle's sake  # both from the cache, leaf loaded for the caller's sake
