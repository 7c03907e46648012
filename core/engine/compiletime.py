"""Five changes to how numba compiles, for the kernel's sake: each makes it compile in less time,
and none changes what it computes (the frames are the same, bit for bit: ``tests/test_golden.py``).

- **LLVM inlines the phases, numba compiles each once.** numba's own inlining
  (``inline="always"``) copies a callee's IR into every call site, so the cell
  update was one huge function, typed, lowered and optimized as a whole: its
  Python passes and LLVM's first round on it took most of the compile, and
  each of the update's two versions (with and without the fast loop) did it
  all again. A function marked by :func:`inline_everywhere` (the kernel's
  :data:`~.jit.inlined` ones) is instead compiled once per signature, on its
  own and cached on its own, like any numba function; its LLVM function is
  marked ``alwaysinline``, so that LLVM inlines it into each caller when the
  caller's module is optimized (at -O3, by numba's module pipeline). Its own
  library gets neither of numba's two -O3 module pipelines nor machine code:
  it is only what callers link in (numba's module for linking, its functions
  ``linkonce_odr``, as they were after the first round); its final module
  keeps only its globals (numba's environment), so the machine code emitted
  for it is empty. Such a function cannot be called from Python (it has no
  wrapper for that either): it raises TypeError (:func:`jit_only`). A caller
  not marked (the kernel's ``step``, ``_update_tile``) is compiled as numba
  compiles any function. The warm-up can so compile the phases in processes
  of their own, side by side, and no process compiles one twice
  (:mod:`sandmod.jobs.warmup`).
- **Callers call some functions by name.** A numba function that calls another links in the
  callee's whole module and optimizes and compiles it again as part of its own, even where
  LLVM leaves the call a call. A function marked by :func:`call_by_name` (the kernel's
  :func:`~.jit.called` one: the update without its fast loop, for the quick
  kernel of a first run) is compiled once, in full, with machine code of its own; a caller
  links in nothing of it (its module declares what it calls) and LLVM's loader finds it by
  name: its address is added as the function is compiled or loaded from the cache
  (``llvmlite.binding.add_symbol``), and a caller written to the cache names what it
  calls, which loading it loads first. The update so compiles in a process of its own,
  and the step that calls it in seconds; but a kernel that called the update's two versions
  so ran 6 to 8% slower on a world of scattered sand and water than the one that inlines
  them (``bench.py yardstick``: 0.74 of the yardstick against 0.80), for reasons not
  found, so it serves only the first run, while the other compiles (``kernel.step_soon``).
- **The quick step is optimized lightly.** What a first run's quick step compiles (the step and
  the update it calls by name: :func:`optimize_lightly`, the kernel's :func:`~.jit.quick`
  ones) gets LLVM's module passes at -O1 (:data:`QUICK_OPT`), not numba's -O3: the
  update compiled in 5.0 s instead of 5.7, the step in 2.0 instead of 2.2, and the quick
  step ran as fast (mix 7.1 ms a frame against 7.3, halves 2.2 against 2.2, 512², in turns).
- **The inliner copies each function once.** Before inlining a function
  (``inline="always"``; still so for ``_step_passes``, and for every
  :data:`~.jit.inlined` function where LLVM's inlining is not installed),
  numba copies its IR block by block, each block with
  a fresh ``copy.deepcopy`` memo. Every block refers to the function's scope,
  and the scope to every variable, so each block's copy copies all of them
  again: the cost grows with blocks times variables (numba issues 8989 and
  9204). Here the blocks of one copy share one memo, as one deep copy of the
  whole function would.
- **LLVM's first round is a light one.** numba runs LLVM's function passes
  on each function as it is compiled (at -O3), then the whole -O3 pipeline
  again on the module it links it into. For the kernel's modules the first
  round runs at -O1 (:data:`FUNCTION_OPT`): the second does the heavy work
  either way. Skipped altogether, the kernel ran 2 to 5% slower; at -O1 it
  runs as fast as at -O3 (``tools/dev/bench.py against``, in turns: mix
  1.005x, halves 1.001x, everything 0.991x).

:func:`install` makes the five changes; where numba is not as one expects (a method it
replaces is missing), it leaves numba as it is for that one, and :data:`LLVM_INLINES` says
whether LLVM inlines (if not, :data:`~.jit.inlined` falls back to numba's ``inline="always"``).

Measured on the project's 2-core VM with other work running (load about 2), each part of the
warm-up in a process of its own, one after another, from an empty cache (``python -m
sandmod.jobs.warmup PART``; "step" a tiny world's first step after them, linking them), CPU
seconds in all for the kernel a step needs:

- LLVM's inlining, each marked function's library with numba's wrappers and machine code: the
  update with and without its fast loop 40 in one process (the warm-up compiled each in a
  process of its own, each all of it), step 8; compiled by subtrees, each function once: 51
  (moves 17.6, phases 9.3, fast loop 4.4, the update 11.7, step 8.0);
- the libraries of marked functions without machine code: 44;
- and without numba's wrappers for Python (a marked function is never called from Python): 37;
- the update's two versions (``step_region_fast``, ``_full``) marked too, so that ``_update_tile``
  optimizes them once: 34.5 (moves 9.9, fast loop 2.6, phases 6.5, the update with and without
  the fast loop 2.6 and 1.7, step 11.3). ``_update_tile`` optimized only in its callers
  (``noinline``, its library without machine code) saved 3 s more of the step, but the kernel
  ran slower (``bench.py against``, numba's inlining over it: mix 1.073x, everything 1.047x).

Called by name, the update without its fast loop in a process of its own, optimized lightly, and a
step of 2 s: from an empty cache to the hourglass's first frame in 16 to 17 s on two idle cores,
against 25 s with the update inlined into the step (``tools/dev/firstframe.py``).

The kernel runs as fast as with numba's inlining (``tools/dev/bench.py against``, in turns, one
thread, numba's inlining over LLVM's in three runs: mix 0.98 to 1.07x, halves 0.98 to 1.00x,
everything 0.98 to 1.03x; see ``docs/performance.md``).
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


#: Whether LLVM inlines the functions marked by :func:`inline_everywhere` (numba is as :func:`install` expects).
LLVM_INLINES = False


def install() -> None:
    """Make numba's inliner copy each function once, LLVM's first round on the kernel's code light,
    LLVM inline the functions marked by :func:`inline_everywhere` (:data:`LLVM_INLINES`; the same
    change optimizes those marked by :func:`optimize_lightly` lightly), and callers call those
    marked by :func:`call_by_name` by name (:data:`CALLS_BY_NAME`)."""
    global LLVM_INLINES, CALLS_BY_NAME
    _copy_once()
    _optimize_once()
    LLVM_INLINES = _inline_marked()
    CALLS_BY_NAME = _call_marked_by_name()


#: The start of the LLVM names of the functions compiled only for their callers (:func:`inline_everywhere`),
#: and the attribute each gets (``alwaysinline``).
_EVERYWHERE: dict[str, str] = {}
_EXTERNAL = None  # llvmlite's external linkage, once imported


def _symbol(function) -> str:
    """The start of the LLVM name numba gives ``function`` (a plain Python function) in every
    signature: Itanium-mangled, ``_ZN`` then each dotted part of its module and name as its
    length and itself, then ``B`` and the ABI tags."""
    parts = f"{function.__module__}.{function.__qualname__}".split(".")
    return "_ZN" + "".join(f"{len(p)}{p}" for p in parts) + "B"


def inline_everywhere(function) -> None:
    """Have LLVM inline ``function`` (a plain Python function, about to be compiled) into every caller,
    its own library left without machine code (see the module)."""
    _EVERYWHERE[_symbol(function)] = "alwaysinline"


class _CompiledToInline:
    """A mixin for the dispatcher of a function LLVM inlines (:func:`jit_only`): called from Python, it says so."""

    def __call__(self, *args, **kwargs):
        raise TypeError(
            f"{self.py_func.__qualname__} is compiled only to be inlined into compiled callers "
            "(sandmod.engine.jit.inlined): it has no machine code of its own to call from Python"
        )


def jit_only(dispatcher):
    """``dispatcher`` (numba's, of a function marked by :func:`inline_everywhere`), made to raise
    TypeError when called from Python: its library has no machine code to call (see the module)."""
    cls = type(dispatcher)
    dispatcher.__class__ = type(cls.__name__, (_CompiledToInline, cls), {"__module__": cls.__module__})
    return dispatcher


def _compiles(library, prefixes) -> bool:
    """Is one of the functions ``library`` compiles (its own, not those it links) named with one of ``prefixes``?"""
    return any(
        function.name.startswith(prefix)
        for function in library._final_module.functions
        if not function.is_declaration and function.linkage == _EXTERNAL
        for prefix in prefixes
    )


def _marked(library) -> bool:
    """Does ``library`` compile a function marked by :func:`inline_everywhere`?"""
    return _compiles(library, _EVERYWHERE)


#: The optimization level of the quick step's modules (:func:`optimize_lightly`), instead of numba's -O3.
QUICK_OPT = 1
#: The start of the LLVM names of the functions marked by :func:`optimize_lightly`.
_LIGHT: set[str] = set()


def optimize_lightly(function) -> None:
    """Optimize the module of ``function`` (a plain Python function, about to be compiled) at
    :data:`QUICK_OPT`: for the quick step of a first run, which compiles so in less time and ran as
    fast (see the module)."""
    _LIGHT.add(_symbol(function))


def _light(library) -> bool:
    """Does ``library`` compile a function marked by :func:`optimize_lightly`?"""
    return _compiles(library, _LIGHT)


def _attribute(name: str) -> str | None:
    return next((attribute for prefix, attribute in _EVERYWHERE.items() if name.startswith(prefix)), None)


def _inline_marked() -> bool:
    """Give the functions of :data:`_EVERYWHERE` their attribute (``alwaysinline``, ``noinline``) as
    numba compiles them, and make their libraries only what callers link in; returns whether it
    did: not where numba is not as expected (a method replaced or relied on is missing, or
    ``_get_module_for_linking`` no longer hands out ``_shared_module``, which is set here)."""
    try:
        import llvmlite.binding as ll
        from numba.core.codegen import CPUCodeLibrary, CPUCodegen

        original, optimize = CPUCodeLibrary.add_ir_module, CPUCodeLibrary._optimize_final_module
        if "_shared_module" not in CPUCodeLibrary._get_module_for_linking.__code__.co_names:
            return False
        CPUCodegen._pass_builder  # noqa: B018
        ll.create_new_module_pass_manager().add_global_dead_code_eliminate_pass  # noqa: B018
        global _EXTERNAL
        _EXTERNAL = ll.Linkage.external
    except (ImportError, AttributeError):
        return False
    if getattr(original, "_sandmod", False):
        global _EVERYWHERE, _LIGHT
        _EVERYWHERE, _LIGHT = original._everywhere, original._light  # another copy of this module installed it: one list of marks
        return True

    def add_ir_module(self, ir_module):
        for function in ir_module.functions:
            attribute = _attribute(function.name) if function.blocks else None
            if attribute is not None:
                function.attributes.add(attribute)
        return original(self, ir_module)

    def _optimize_final_module(self):
        if _light(self):
            manager, builder = self._codegen._module_pass_manager(opt=QUICK_OPT, loop_vectorize=False, slp_vectorize=False)
            with self._recorded_timings.record(f"Module passes (light, -O{QUICK_OPT})", builder):
                manager.run(self._final_module, builder)
            return None
        if not _marked(self):
            return optimize(self)
        # What callers link in: the functions as they are (after the first round), external ones
        # made linkonce_odr as numba's _get_module_for_linking makes them. Each caller inlines them
        # and optimizes them there, at -O3; they are never called on their own.
        shared = self._final_module.clone()
        for function in shared.functions:
            if not function.is_declaration and function.linkage == _EXTERNAL:
                function.linkage = "linkonce_odr"
        self._shared_module = shared
        # This library's own machine code: none of its functions (nor the wrappers Python would call
        # them through), only its globals (numba's environment for it).
        for function in self._final_module.functions:
            if not function.is_declaration:
                function.linkage = "internal"
        manager = ll.create_new_module_pass_manager()
        manager.add_global_dead_code_eliminate_pass()
        manager.run(self._final_module, self._codegen._pass_builder(opt=0))

    add_ir_module._sandmod = _optimize_final_module._sandmod = True
    add_ir_module._everywhere, add_ir_module._light = _EVERYWHERE, _LIGHT
    CPUCodeLibrary.add_ir_module = add_ir_module
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


#: Whether callers call the functions marked by :func:`call_by_name` by name (numba is as :func:`install` expects).
CALLS_BY_NAME = False
#: The start of the LLVM names of the functions marked by :func:`call_by_name`.
_BY_NAME: set[str] = set()
#: Those of them compiled or loaded in this process: LLVM name -> (module, qualified name, signature),
#: what a cached caller needs to load them again before its machine code is loaded.
_CALLED: dict[str, tuple] = {}


def call_by_name(function) -> None:
    """Have callers call ``function`` (a plain Python function, about to be compiled) by its name:
    its machine code, compiled once, not a copy of it compiled again into each caller (see the module)."""
    _BY_NAME.add(_symbol(function))


def _by_name(name: str) -> bool:
    return any(name.startswith(prefix) for prefix in _BY_NAME)


def _call_marked_by_name() -> bool:
    """Make callers of the functions marked by :func:`call_by_name` link in nothing of theirs (the call
    is to a declaration, which the loader resolves), tell LLVM's loader where each is once compiled
    or loaded, and make a cached caller load them first; returns whether it did."""
    try:
        import llvmlite.binding as ll
        from numba.core.codegen import CPUCodeLibrary
        from numba.core.dispatcher import Dispatcher

        originals = CPUCodeLibrary._get_module_for_linking, CPUCodeLibrary.serialize_using_object_code, CPUCodeLibrary._unserialize.__func__
        add_overload = Dispatcher.add_overload
        if CPUCodeLibrary._unserialize.__code__.co_varnames[:3] != ("cls", "codegen", "state"):
            return False
    except (ImportError, AttributeError):
        return False
    if getattr(add_overload, "_sandmod", False):
        return True
    for_linking, serialize, unserialize = originals

    def _get_module_for_linking(self):
        if self._shared_module is None and any(_by_name(f.name) for f in self._final_module.functions if not f.is_declaration):
            # Nothing to link in: each caller's module declares what it calls, and the loader finds it.
            empty = ll.parse_assembly("")
            empty.triple, empty.data_layout = self._final_module.triple, self._final_module.data_layout
            self._shared_module = empty
        return for_linking(self)

    def serialize_using_object_code(self):
        name, kind, (code, shared) = serialize(self)
        # What it calls, and what its callers link in calls (an inlined function's final module keeps none of its code).
        modules = [self._final_module] + ([self._shared_module] if self._shared_module is not None else [])
        called = {f.name for module in modules for f in module.functions if f.is_declaration and f.name in _CALLED}
        return name, kind, (code, shared, [_CALLED[name] for name in sorted(called)])

    def _unserialize(cls, codegen, state):
        name, kind, data = state
        if kind == "object" and len(data) == 3:
            code, shared, called = data
            for module, qualname, signature in called:  # loaded (or compiled) first: the loader needs them
                _dispatcher(module, qualname).compile(signature)
            state = name, kind, (code, shared)
        return unserialize(cls, codegen, state)

    def add_overload_(self, cres):
        add_overload(self, cres)
        name = cres.fndesc.llvm_func_name
        if _by_name(name) and not cres.objectmode:
            cres.library._ensure_finalized()
            address = cres.library.codegen._engine._ee.get_function_address(name)  # also where loaded from the cache
            if not address:
                raise RuntimeError(f"{name}: compiled, but LLVM's loader does not find it")
            ll.add_symbol(name, address)
            _CALLED[name] = (self.py_func.__module__, self.py_func.__qualname__, tuple(cres.signature.args))

    add_overload_._sandmod = True
    CPUCodeLibrary._get_module_for_linking = _get_module_for_linking
    CPUCodeLibrary.serialize_using_object_code = serialize_using_object_code
    CPUCodeLibrary._unserialize = classmethod(_unserialize)
    Dispatcher.add_overload = add_overload_
    return True


def _dispatcher(module: str, qualname: str):
    import importlib

    found = importlib.import_module(module)
    for part in qualname.split("."):
        found = getattr(found, part)
    return found
